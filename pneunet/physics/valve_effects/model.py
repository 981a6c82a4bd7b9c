"""ValveModel: the six-parameter valve law extended by composable effects."""
from __future__ import annotations

import numpy as np

from ...common.errors import ParameterError
from ..laws import signed_root, valve_conductance
from ..valve_params import VALVE_PARAMETERS, ValveParams
from .base import Effect, Inputs, as_effect, available_effects, get_effect

BASE_KEYS = tuple(VALVE_PARAMETERS)  # Rf, pclose, ptrans, e, ain, aout

_NEWTON_ITER = 30


class ValveModel:
    """Six-parameter membrane valve (eq. 19/25) with a list of :class:`Effect` s.

    ``ValveModel(params, effects=["leak", Choked(b=0.3)])``.  Effects given by
    id start at their null value; the model with only null effects equals the
    plain valve law.  The object is immutable (``with_effect`` etc. return new
    models).

    ``flow(p_in, p_out, p_ctrl, *, time=None, sweep=None)`` is vectorised and
    is what the circuit engine, the virtual bench and the fits call.  Inputs an
    effect needs but that are not given (``time``/``sweep`` in a circuit) reach
    its hooks as None; each effect documents what it does then (``hysteresis``
    uses the mean threshold p_close).
    """

    def __init__(self, params: ValveParams, effects=()):
        if not isinstance(params, ValveParams):
            params = ValveParams(**dict(params))
        self.params = params
        effs = [as_effect(e) for e in effects]
        ids = [e.id for e in effs]
        if len(set(ids)) != len(ids):
            raise ParameterError(f"effect listed twice in {ids}")
        self.effects: tuple[Effect, ...] = tuple(effs)

    # -- composition --------------------------------------------------------------------
    @property
    def effect_ids(self) -> list[str]:
        return [e.id for e in self.effects]

    @property
    def needs(self) -> set[str]:
        return {n for e in self.effects for n in e.needs if not e.is_null()}

    def effect(self, effect_id: str) -> Effect:
        for e in self.effects:
            if e.id == effect_id:
                return e
        raise ParameterError(f"model has no effect {effect_id!r}")

    def with_effect(self, effect) -> "ValveModel":
        eff = as_effect(effect)
        rest = [e for e in self.effects if e.id != eff.id]
        return ValveModel(self.params, rest + [eff])

    def with_params(self, params: ValveParams) -> "ValveModel":
        return ValveModel(params, self.effects)

    def __repr__(self):
        p = ", ".join(f"{k}={v:.4g}" for k, v in self.params.as_dict().items())
        return f"ValveModel({p}; effects={list(self.effects)})"

    # -- the law ------------------------------------------------------------------------
    def flow(self, p_in, p_out, p_ctrl, *, time=None, sweep=None, band=0.0):
        """Signed mass flow in→out, mg/s (exact √ unless ``band`` > 0, see laws.py)."""
        P = self.params
        p_in, p_out, p_ctrl = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                                     for v in (p_in, p_out, p_ctrl)))
        x = Inputs(p_in=p_in, p_out=p_out, p_ctrl=p_ctrl, params=P,
                   time=None if time is None else np.asarray(time, dtype=float),
                   sweep=None if sweep is None else np.asarray(sweep, dtype=float))
        active = [e for e in self.effects if not e.is_null()]
        stage = lambda hook: sorted((e for e in active if hook in e.hooks()),  # noqa: E731
                                    key=lambda e: e.order)
        for eff in stage("pressures"):
            x.p_in, x.p_out, x.p_ctrl = eff.pressures(x, **eff.values)
        forward = x.p_in >= x.p_out
        x.forward = forward
        x.p_hi = np.where(forward, x.p_in, x.p_out)
        x.p_lo = np.where(forward, x.p_out, x.p_in)
        x.d = x.p_hi * x.p_hi - x.p_lo * x.p_lo
        root, _ = signed_root(x.d, band)
        root = np.abs(root)
        dp0 = P.ain * x.p_hi + P.aout * x.p_lo - x.p_ctrl
        dp_effects = stage("delta_p")
        plain_dp = [e for e in dp_effects if not e.uses_flow]
        flow_dp = [e for e in dp_effects if e.uses_flow]
        for eff in plain_dp:
            dp0 = eff.delta_p(dp0, x, **eff.values)
        flow_effects = stage("flow")

        def magnitude(dp):
            g, _ = valve_conductance(dp, P.Rf, P.pclose, P.ptrans, P.e)
            x.g = g
            m = g * root
            for eff in flow_effects:
                m = eff.flow(m, x, **eff.values)
            return m

        if not flow_dp:
            m = magnitude(dp0)
        else:
            m = self._solve_implicit(magnitude, dp0, flow_dp, x)
        return np.where(forward, m, -m)

    @staticmethod
    def _solve_implicit(magnitude, dp0, flow_dp, x):
        """Solve m = magnitude(Δp(m)) by safeguarded Newton (Δp falls as m rises)."""

        def h(m):
            x.mdot = m
            dp = dp0
            for eff in flow_dp:
                dp = eff.delta_p(dp, x, **eff.values)
            return m - magnitude(dp)

        lo = np.zeros_like(dp0)
        hi = magnitude(np.full_like(dp0, 1e9)) + 1e-9  # fully open: an upper bound
        m = magnitude(dp0)  # Δp(ṁ) ≤ Δp(0) for the library effect -> start high
        m = np.clip(m, lo, hi)
        for _ in range(_NEWTON_ITER):
            hm = h(m)
            lo = np.where(hm <= 0, m, lo)
            hi = np.where(hm >= 0, m, hi)
            step = 1e-6 * (1.0 + np.abs(m))
            dh = (h(m + step) - hm) / step
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = m - hm / dh
            bad = ~np.isfinite(newton) | (newton <= lo) | (newton >= hi)
            new = np.where(bad, 0.5 * (lo + hi), newton)
            if np.all(np.abs(new - m) <= 1e-10 * (1.0 + np.abs(m))):
                m = new
                break
            m = new
        x.mdot = m
        return m

    def __call__(self, frame):
        """Flow for a DataFrame with the canonical columns (``time_s``/``sweep`` optional)."""
        return self.flow(frame["p_in_kPa"].to_numpy(), frame["p_out_kPa"].to_numpy(),
                         frame["p_ctrl_kPa"].to_numpy(),
                         time=frame["time_s"].to_numpy() if "time_s" in frame else None,
                         sweep=frame["sweep"].to_numpy() if "sweep" in frame else None)

    # -- cards --------------------------------------------------------------------------
    def card_params(self) -> dict[str, float]:
        """Flat parameter dict of a ``.model NAME VALVE(...)`` card.

        Effect parameters are named ``<effect id with - as _>_<param>``.
        """
        out = dict(self.params.as_dict())
        for eff in self.effects:
            for k, v in eff.values.items():
                out[eff.card_prefix() + k] = v
        return out

    @classmethod
    def from_card_params(cls, card: dict) -> "ValveModel":
        """Inverse of :meth:`card_params` (unknown names raise ParameterError)."""
        card = dict(card)
        missing = [k for k in BASE_KEYS if k not in card]
        if missing:
            raise ParameterError(f"valve model card lacks {', '.join(missing)}")
        base = ValveParams(**{k: float(card.pop(k)) for k in BASE_KEYS})
        prefixes = sorted(((get_effect(i).card_prefix(), i) for i in available_effects()),
                          key=lambda t: -len(t[0]))
        values: dict[str, dict[str, float]] = {}
        for key, val in card.items():
            for prefix, eid in prefixes:
                if key.startswith(prefix) and key[len(prefix):] in get_effect(eid).params:
                    values.setdefault(eid, {})[key[len(prefix):]] = float(val)
                    break
            else:
                raise ParameterError(
                    f"unknown valve model parameter {key!r}",
                    hint="effect parameters are <effect>_<param>, effects: "
                         + ", ".join(available_effects()))
        return cls(base, [get_effect(eid)(**vals) for eid, vals in values.items()])

    def model_card(self, name: str) -> str:
        body = " ".join(f"{k}={v:.6g}" for k, v in self.card_params().items())
        return f".model {name} VALVE({body})"

    # -- parameter vectors (used by fits) -----------------------------------------------
    def vector_spec(self):
        """[(name, lo, hi)] of the free parameters in the order of :meth:`to_vector`.

        The base law is parametrised as (Rf, pclose, ptrans − pclose, e, ain, aout).
        """
        spec = [("Rf", 1e-3, 1e3), ("pclose", -1000.0, 2000.0), ("pwidth", 1e-3, 3000.0),
                ("e", 0.1, 10.0), ("ain", 0.0, 3.0), ("aout", 0.0, 3.0)]
        for eff in self.effects:
            for k, p in eff.params.items():
                spec.append((f"{eff.id}.{k}", p.lo, p.hi))
        return spec

    def to_vector(self) -> np.ndarray:
        P = self.params
        v = [P.Rf, P.pclose, P.ptrans - P.pclose, P.e, P.ain, P.aout]
        for eff in self.effects:
            v.extend(eff.values[k] for k in eff.params)
        return np.array(v, dtype=float)

    def from_vector(self, v) -> "ValveModel":
        v = [float(t) for t in v]
        base = ValveParams(Rf=v[0], pclose=v[1], ptrans=v[1] + v[2], e=v[3], ain=v[4], aout=v[5])
        effs, i = [], 6
        for eff in self.effects:
            vals = {k: v[i + j] for j, k in enumerate(eff.params)}
            i += len(eff.params)
            effs.append(type(eff)(**vals))
        return ValveModel(base, effs)
