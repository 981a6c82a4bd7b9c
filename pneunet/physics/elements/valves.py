"""Membrane valves: the six-parameter model (eqs. 13, 19, 25), three ports.

Ports ``in``, ``out``, ``ctrl``.  Flow goes from the higher to the lower of
``in``/``out``; a_in belongs to the higher port (eq. 25).  The control chamber
is a dead end: no flow enters it.

``model`` is a :class:`~pneunet.physics.valve_params.ValveParams` (evaluated analytically,
vectorised over all such valves) or any object with a vectorised method
``flow(p_in, p_out, p_ctrl) -> mdot`` — e.g. a valve model extended with
physical effects — whose partials are taken by central differences.  An
optional ``backward`` ValveParams applies when p_out > p_in (mirror valves, Table 1).
"""
from __future__ import annotations

import numpy as np

from ..laws import Scalar, valve_delta_p, valve_flow_and_partials, valve_opening
from ...common.errors import ParameterError
from ..valve_params import ValveParams, resolve_valve_model
from .base import ElementFamily, FEW_INSTANCES, Param, register

_FD_STEP_KPA = 1e-4
_PORTS = np.array([1.0, -1.0, 0.0])  # flow in→out leaves node in, enters out; none at ctrl


@register
class MembraneValve(ElementFamily):
    """Fluid-driven membrane valve (six-parameter model)."""

    kind = "valve"
    aliases = ("X", "membrane_valve")
    description = "membrane valve with ports in, out, ctrl (six-parameter model)"
    ports = ("in", "out", "ctrl")
    flow_ports = (0, 1)
    params = {
        "model": Param("dimensionless", "ValveParams or a model with flow(p_in, p_out, p_ctrl)",
                       kind="object"),
        "backward": Param("dimensionless", "ValveParams for flow out→in (default: model)",
                          kind="object", default=False),
    }

    @classmethod
    def check_spec(cls, spec):
        try:
            spec.params["model"] = resolve_valve_model(spec.params["model"])
            if spec.params["backward"]:
                spec.params["backward"] = resolve_valve_model(spec.params["backward"])
        except ParameterError as err:
            raise ParameterError(err.message, where=spec.where, hint=err.hint) from None
        if spec.params["backward"] and not isinstance(spec.params["backward"], ValveParams):
            raise ParameterError("a backward model must be a six-parameter ValveParams",
                                 where=spec.where)

    def __init__(self, specs, context):
        super().__init__(specs, context)
        models = [s.params["model"] for s in specs]
        self._analytic = np.array([isinstance(m, ValveParams) for m in models])
        fwd = [m if isinstance(m, ValveParams) else None for m in models]
        self._fwd = _param_arrays(fwd)
        has_backward = any(s.params["backward"] for s in specs)
        # forward and backward parameters stacked (6, n) in the law's order (None: no
        # backward model)
        self._both = (np.array(list(self._fwd.values())),
                      np.array(list(_param_arrays([s.params["backward"] or m for s, m in
                                                   zip(specs, fwd)]).values()))) \
            if has_backward else None
        self._custom = {}
        for i, m in enumerate(models):
            if not self._analytic[i]:
                self._custom.setdefault(id(m), (m, []))[1].append(i)
        # few analytic valves: each one's (forward, backward) parameters as floats
        self._rows = None
        if self.n <= FEW_INSTANCES and self._analytic.all():
            fwd_rows = np.array(list(self._fwd.values()))
            both = self._both or (fwd_rows, fwd_rows)
            self._rows = list(zip(both[0].T.tolist(), both[1].T.tolist()))
        self.on_floats = self._rows is not None
        self._own_rows = np.arange(3 * self.n).reshape(self.n, 3).tolist()  # p (n, 3) raveled

    def _analytic_flow(self, p, partials=True):
        if self._both is None:
            params = self._fwd.values()
        else:  # each valve's parameters for its flow direction: (6, ..., n)
            forward = (p[..., 0] >= p[..., 1])[..., None, :]
            params = np.moveaxis(np.where(forward, *self._both), -2, 0)  # no-op for (n, 3)
        return valve_flow_and_partials(p[..., 0], p[..., 1], p[..., 2], *params,
                                       band=self.context.options.flow_band, partials=partials)

    def float_outflows(self, t, p, pdot, rows, partials):
        """Each valve's law on Python floats (laws.Scalar), in one loop (few valves)."""
        band = self.context.options.flow_band
        q, dq = [], [] if partials else None
        for (i, o, c), (fwd, bwd) in zip(rows, self._rows):
            m, g = valve_flow_and_partials(p[i], p[o], p[c], *(fwd if p[i] >= p[o] else bwd),
                                           band=band, partials=partials, xp=Scalar)
            q += (m, -m, 0.0)
            if partials:
                d_in, d_out, d_ctrl = g
                dq += (d_in, d_out, d_ctrl, -d_in, -d_out, -d_ctrl, 0.0, 0.0, 0.0)
        return q, dq, None

    def outflows(self, t, p, pdot):
        if self._rows is not None:
            q, dq, _ = self.float_outflows(t, p.ravel().tolist(), None, self._own_rows, True)
            return np.array(q).reshape(self.n, 3), np.array(dq).reshape(self.n, 3, 3), None
        mdot, (d_in, d_out, d_ctrl) = self._analytic_flow(p)
        grads = np.stack(np.broadcast_arrays(d_in, d_out, d_ctrl), axis=-1)  # (n, 3)
        for model, idx in self._custom.values():
            mdot[idx], grads[idx] = _numeric_flow(model, p[idx])
        return mdot[:, None] * _PORTS, _PORTS[:, None] * grads[:, None, :], None

    def _flow(self, p):
        """Flow in→out (mg/s) for pressures p (..., n, 3), without partials."""
        mdot, _ = self._analytic_flow(p, partials=False)
        for model, idx in self._custom.values():
            mdot[..., idx] = model.flow(p[..., idx, 0], p[..., idx, 1], p[..., idx, 2])
        return mdot

    def flows(self, t, p, pdot):
        if self._rows is not None and p.ndim == 2:
            q, _, _ = self.float_outflows(t, p.ravel().tolist(), None, self._own_rows, False)
            return np.array(q).reshape(self.n, 3)
        return self._flow(p)[..., None] * _PORTS

    def signals(self, t, p):
        mdot = self._flow(p)
        dp = valve_delta_p(p[..., 0], p[..., 1], p[..., 2], self._fwd["ain"], self._fwd["aout"])
        opening = valve_opening(dp, self._fwd["pclose"], self._fwd["ptrans"])
        return {"mdot": ("mg/s", mdot), "dp": ("kPa", dp), "opening": ("1", opening)}

    def undefined_signals(self, suffix):
        """A valve following a user's flow model has no membrane parameters: no dp, no
        opening."""
        if suffix not in ("dp", "opening"):
            return frozenset()
        return frozenset(i for _, idx in self._custom.values() for i in idx)


def _param_arrays(params: list[ValveParams | None]) -> dict[str, np.ndarray]:
    """Columns of valve parameters; NaN for a user's model (it has none: its flows are
    its own; its dp and opening are left out of solutions, :meth:`undefined_signals`)."""
    return {k: np.array([getattr(r, k) if r else np.nan for r in params])
            for k in ValveParams.__dataclass_fields__}


def _numeric_flow(model, p):
    """Flow of a custom valve model and its partials by central differences."""
    mdot = np.asarray(model.flow(p[:, 0], p[:, 1], p[:, 2]), dtype=float)
    grads = np.empty((len(p), 3))
    for j in range(3):
        hi, lo = p.copy(), p.copy()
        hi[:, j] += _FD_STEP_KPA
        lo[:, j] -= _FD_STEP_KPA
        grads[:, j] = (model.flow(hi[:, 0], hi[:, 1], hi[:, 2])
                       - model.flow(lo[:, 0], lo[:, 1], lo[:, 2])) / (2 * _FD_STEP_KPA)
    return mdot, grads
