"""Check valves: flow a→b once p_a − p_b exceeds a cracking pressure, a small leak otherwise.

The open fraction rises smoothly (C¹) over ``width`` kPa above the cracking pressure:

    s = (p_a − p_b − pcrack)/width,   u(s) = 0 (s ≤ 0),  3s² − 2s³ (0 < s < 1),  1 (s ≥ 1)

and the flow is the quadrature law (eq. 4) through the open fraction plus a leak:

    ṁ = (u/R + 1/Rleak) · sr(p_a² − p_b²)       [mg/s, a→b; negative is back-flow]

sr is the regularised signed root of :func:`pneunet.physics.laws.signed_root` (band ``flow_band``).
The leak passes both ways (no leak when Rleak is not given).  In a liquid circuit the
law is linear, ṁ = (u/R + 1/Rleak)·(p_a − p_b): R is the open valve's Δp/ṁ (kPa·s/mg).  ``check_valve`` reseats where
it cracks; ``hysteretic_check_valve`` reseats at a lower pressure, its open fraction a state.
"""
from __future__ import annotations

import numpy as np

from ...common.errors import ParameterError
from ..laws import signed_root
from . import run_checks
from .base import ElementFamily, Param, register

_OUT_IN = np.array([1.0, -1.0])  # a flow a→b leaves node a and enters node b


def open_fraction(delta_p, pcrack, width):
    """Open fraction u (smoothstep of (Δp − pcrack)/width) and du/dΔp (1/kPa)."""
    s = np.clip((delta_p - pcrack) / width, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s), 6.0 * s * (1.0 - s) / width


@register
class CheckValve(ElementFamily):
    checks_run = True
    """Check valve a→b: cracking pressure, smooth opening over ``width``, closed leakage."""

    kind = "check_valve"
    aliases = ("D",)
    description = "check valve a→b: cracking pressure, C¹ opening over width, closed leak"
    ports = ("a", "b")
    fluids = ("gas", "liquid")
    params = {
        "R": Param("resistance", "resistance when fully open, kPa·s/mg", low=0.0,
                   low_inclusive=False),
        "pcrack": Param("pressure_difference", "cracking pressure p_a − p_b, kPa", low=0.0,
                        default=0.0),
        "width": Param("pressure_difference", "pressure range above pcrack over which the "
                       "valve opens fully, kPa", low=0.0, low_inclusive=False, default=5.0),
        "Rleak": Param("resistance", "resistance of the leak when closed, kPa·s/mg "
                       "(default: no leak)", low=0.0, low_inclusive=False, default=np.inf),
    }

    @classmethod
    def check_spec(cls, spec):
        r, r_leak = spec.params["R"], spec.params["Rleak"]
        if r_leak <= r:
            raise ParameterError(f"Rleak={r_leak:g} kPa·s/mg must exceed the open resistance "
                                 f"R={r:g} kPa·s/mg", where=spec.where,
                                 hint="a leak is a small conductance: Rleak > R, e.g. 1000·R")

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._g_open = 1.0 / self.column("R")
        self._g_leak = 1.0 / self.column("Rleak")
        self._pcrack, self._width = self.column("pcrack"), self.column("width")
        self._liquid = context.options.liquid is not None

    def _quadrature(self, p_a, p_b, opening, partials):
        """ṁ = (u/R + 1/Rleak)·sr(p_a² − p_b²) (a liquid: ·(p_a − p_b)), that driving term,
        and ∂ṁ/∂p_a, ∂ṁ/∂p_b at fixed u."""
        g = opening * self._g_open + self._g_leak
        if self._liquid:
            drive = p_a - p_b
            return g * drive, drive, (g + 0.0 * drive if partials else None), \
                (-g + 0.0 * drive if partials else None)
        root, slope = signed_root(p_a * p_a - p_b * p_b, self.context.options.flow_band,
                                  derivative=partials)
        if not partials:
            return g * root, root, None, None
        return g * root, root, 2.0 * g * slope * p_a, -2.0 * g * slope * p_b

    def _law(self, p, partials):
        p_a, p_b = p[..., 0], p[..., 1]
        u, du = open_fraction(p_a - p_b, self._pcrack, self._width)
        mdot, root, d_a, d_b = self._quadrature(p_a, p_b, u, partials)
        if not partials:
            return mdot, None, None
        d_open = du * self._g_open * root  # through the open fraction, ∂/∂p_a = −∂/∂p_b
        return mdot, d_a + d_open, d_b - d_open

    def outflows(self, t, p, pdot):
        mdot, d_a, d_b = self._law(p, partials=True)
        grad = np.stack([d_a, d_b], axis=1)[:, None, :]
        return mdot[:, None] * _OUT_IN, _OUT_IN[:, None] * grad, None

    def flows(self, t, p, pdot):
        return self._law(p, partials=False)[0][..., None] * _OUT_IN

    def signals(self, t, p):
        dp = p[..., 0] - p[..., 1]
        opening, _ = open_fraction(dp, self._pcrack, self._width)
        if np.size(t) > 1:
            run_checks.check_valve_shut(self.specs, t, dp, opening, self._pcrack)
        return {"mdot": ("mg/s", self.flows(t, p, None)[..., 0]), "opening": ("1", opening)}


#: the state node carries the open fraction x as the pressure-like ambient + x·STATE_SPAN
STATE_SPAN_KPA = 100.0


@register
class HystereticCheckValve(CheckValve):
    """Check valve that opens above ``pcrack`` and reseats below ``preseat`` < pcrack.

    Its open fraction x is a state, carried at a third node (``state``, an internal node
    you name) as z = ambient + 100 kPa·x, and relaxes with time constant ``tau``:

        τ·ẋ = u_o·(1 − x) − u_c·x,   u_o = S((Δp − pcrack)/width),  u_c = S((preseat − Δp)/width)

    with S the smoothstep above.  Between preseat and pcrack both drives vanish and x
    keeps its value (the hysteresis); the flow is (x/R + 1/Rleak)·sr(p_a² − p_b²).  It
    starts closed.  A steady state inside the band depends on the history: use ``tran``.
    """

    kind = "hysteretic_check_valve"
    aliases = ()
    description = "check valve opening above pcrack, reseating below preseat (state node)"
    ports = ("a", "b", "state")
    flow_ports = (0, 1)
    storage_ports = (2,)
    params = {
        **CheckValve.params,
        "preseat": Param("pressure_difference", "reseating pressure p_a − p_b (< pcrack), kPa"),
        "tau": Param("time", "time constant of opening and closing, s", low=0.0,
                     low_inclusive=False, default=1e-3),
    }

    @classmethod
    def check_spec(cls, spec):
        super().check_spec(spec)
        if spec.params["preseat"] >= spec.params["pcrack"]:
            raise ParameterError(f"preseat={spec.params['preseat']:g} kPa must be below "
                                 f"pcrack={spec.params['pcrack']:g} kPa", where=spec.where,
                                 hint="the valve reseats at a lower pressure than it cracks")

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._preseat, self._tau = self.column("preseat"), self.column("tau")
        self._ambient = context.options.ambient

    def _opening(self, z):
        return (z - self._ambient) / STATE_SPAN_KPA

    def _state(self, p, pdot, partials):
        """Residual τ·ż − span·(u_o·(1 − x) − u_c·x) of the state node (kPa/s), and its
        partials by Δp and by z."""
        dp, x = p[..., 0] - p[..., 1], self._opening(p[..., 2])
        u_o, du_o = open_fraction(dp, self._pcrack, self._width)
        u_c, du_c = open_fraction(-dp, -self._preseat, self._width)  # du_c is ∂/∂(−Δp)
        residual = self._tau * pdot[..., 2] - STATE_SPAN_KPA * (u_o * (1.0 - x) - u_c * x)
        if not partials:
            return residual, None, None
        return residual, -STATE_SPAN_KPA * (du_o * (1.0 - x) + du_c * x), u_o + u_c

    def outflows(self, t, p, pdot):
        x = self._opening(p[:, 2])
        mdot, root, d_a, d_b = self._quadrature(p[:, 0], p[:, 1], x, partials=True)
        residual, d_dp, d_z = self._state(p, pdot, partials=True)
        dq_dp = np.zeros((self.n, 3, 3))
        dq_dp[:, 0] = np.stack([d_a, d_b, root * self._g_open / STATE_SPAN_KPA], axis=1)
        dq_dp[:, 1] = -dq_dp[:, 0]
        dq_dp[:, 2] = np.stack([d_dp, -d_dp, d_z], axis=1)
        dq_dpdot = np.zeros((self.n, 3, 3))
        dq_dpdot[:, 2, 2] = self._tau
        return np.stack([mdot, -mdot, residual], axis=1), dq_dp, dq_dpdot

    def flows(self, t, p, pdot):
        mdot = self._quadrature(p[..., 0], p[..., 1], self._opening(p[..., 2]), False)[0]
        return np.stack([mdot, -mdot, self._state(p, pdot, partials=False)[0]], axis=-1)

    def initial_pressure(self):
        return np.full(self.n, self._ambient)  # closed

    def signals(self, t, p):
        x = self._opening(p[..., 2])
        mdot = self._quadrature(p[..., 0], p[..., 1], x, False)[0]
        if np.size(t) > 1:
            run_checks.check_valve_shut(self.specs, t, p[..., 0] - p[..., 1], x, self._pcrack)
        return {"mdot": ("mg/s", mdot), "opening": ("1", x)}
