"""``leak``: flow past the closed seat, laminar or turbulent."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect

#: reference pressure sum (kPa) that keeps G in mg/(s·kPa) for every exponent pair
P_REF = 200.0


@register_effect
class Leak(Effect):
    """Leak past the closed seat: a fixed leak path in parallel with the valve,
    laminar or turbulent.

        ṁ = ṁ_valve + G·Δp^n·(p_hi + p_lo)^q·P_ref^(1 − n − q),   Δp = p_hi − p_lo

    with P_ref = 200 kPa.  The published forms are exponent pairs (n, q):

    * turbulent, quadrature law G·√(p_hi² − p_lo²):  n = ½, q = ½ (the default);
    * turbulent, incompressible orifice ∝ √Δp:       n = ½, q = 0;
    * laminar, ∝ Δp (viscous, at mean pressure):     n = 1, q = 0;
    * laminar, compressible Poiseuille ∝ p_hi² − p_lo²: n = 1, q = 1.

    The seat does not seal perfectly (the paper excluded leaking valves, sec.
    5.4); the leak path stays when the membrane closes.  G in mg/(s·kPa);
    null value G = 0 (n = 0.5, q = 0.5).

    Residual signature: closed points (Δp ≤ p_close) show a positive flow that
    grows with p_in − p_out (and possibly with p_in + p_out) and does not depend on
    p_ctrl.
    """

    id = "leak"
    params = {"G": Param("mg/(s*kPa)", 0.0, 0.5, 0.0, "leak conductance", init=1e-3),
              "n": Param("1", 0.25, 1.5, 0.5, "exponent of p_hi - p_lo (1/2 turbulent, "
                         "1 laminar)"),
              "q": Param("1", -0.5, 1.5, 0.5, "exponent of p_hi + p_lo (compressibility)")}
    order = 30
    signature = "closed valve: positive flow growing with p_in - p_out"
    tell_apart = "closed-valve points (p_ctrl at its maximum) over a wide range of p_in, p_out"

    def flow(self, mdot, x, G, n, q):
        if G == 0.0:
            return mdot
        if n == 0.5 and q == 0.5:
            return mdot + G * np.sqrt(np.maximum(x.d, 0.0))
        dp = np.maximum(x.p_hi - x.p_lo, 0.0)
        return mdot + G * dp ** n * (x.p_hi + x.p_lo) ** q * P_REF ** (1.0 - n - q)
