"""Check valves: flow a→b once p_a − p_b exceeds a cracking pressure, a small leak otherwise.

The open fraction rises smoothly (C¹) over ``width`` kPa above the cracking pressure:

    s = (p_a − p_b − pcrack)/width,   u(s) = 0 (s ≤ 0),  3s² − 2s³ (0 < s < 1),  1 (s ≥ 1)

and the flow is the quadrature law (eq. 4) through the open fraction plus a leak:

    ṁ = (u/R + 1/Rleak) · sr(p_a² − p_b²)       [mg/s, a→b; negative is back-flow]

sr is the regularised signed root of :func:`pneunet.laws.signed_root` (band ``flow_band``).
The leak passes both ways (no leak when Rleak is not given).  The valve reseats where it
cracks: there is no hysteresis between opening and reseating.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..laws import signed_root
from . import register
from .base import ElementFamily, Param

_OUT_IN = np.array([1.0, -1.0])  # a flow a→b leaves node a and enters node b


def open_fraction(delta_p, pcrack, width):
    """Open fraction u (smoothstep of (Δp − pcrack)/width) and du/dΔp (1/kPa)."""
    s = np.clip((delta_p - pcrack) / width, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s), 6.0 * s * (1.0 - s) / width


@register
class CheckValve(ElementFamily):
    """Check valve a→b: cracking pressure, smooth opening over ``width``, closed leakage."""

    kind = "check_valve"
    aliases = ("D",)
    description = "check valve a→b: cracking pressure, C¹ opening over width, closed leak"
    ports = ("a", "b")
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

    def _law(self, p, partials):
        p_a, p_b = p[..., 0], p[..., 1]
        u, du = open_fraction(p_a - p_b, self._pcrack, self._width)
        root, slope = signed_root(p_a * p_a - p_b * p_b, self.context.options.flow_band,
                                  derivative=partials)
        g = u * self._g_open + self._g_leak
        mdot = g * root
        if not partials:
            return mdot, None, None
        d_open = du * self._g_open * root  # through the open fraction, ∂/∂p_a = −∂/∂p_b
        return mdot, d_open + 2.0 * g * slope * p_a, -d_open - 2.0 * g * slope * p_b

    def outflows(self, t, p, pdot):
        mdot, d_a, d_b = self._law(p, partials=True)
        grad = np.stack([d_a, d_b], axis=1)[:, None, :]
        return mdot[:, None] * _OUT_IN, _OUT_IN[:, None] * grad, None

    def flows(self, t, p, pdot):
        return self._law(p, partials=False)[0][..., None] * _OUT_IN

    def signals(self, t, p):
        opening, _ = open_fraction(p[..., 0] - p[..., 1], self._pcrack, self._width)
        return {"mdot": ("mg/s", self.flows(t, p, None)[..., 0]), "opening": ("1", opening)}
