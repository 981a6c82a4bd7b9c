"""``laminar``: a viscous term beside the quadratic law."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect


@register_effect
class Laminar(Effect):
    """Viscous (Hagen–Poiseuille) pressure drop in series with the quadratic law.

    Isothermal laminar flow of a gas obeys p_hi² − p_lo² = K·ṁ; in series with the
    quadratic valve resistance R = 1/G of eq. 19:

        p_hi² − p_lo² = ṁ²/G² + K·ṁ
        ⇒ ṁ = 2·ṁ_q² / (G²K + √(G⁴K² + 4·ṁ_q²)),   ṁ_q = G·√(p_hi² − p_lo²)

    (ṁ_q is the flow without the effect, so the term composes with ``choked``).
    K in kPa²·s/mg (K = 2·p̄·R_lam for a linear resistance R_lam at mean pressure p̄);
    null value 0.

    Residual signature: open points are over-predicted by a roughly constant
    amount G²K/2, i.e. relatively most at small flows and small p_in − p_out.
    """

    id = "laminar"
    params = {"K": Param("kPa^2*s/mg", 0.0, 500.0, 0.0, "viscous coefficient", init=0.5)}
    order = 20
    signature = "open valve: flow over-predicted most (relatively) at small flows"
    tell_apart = "open-valve points at small p_in - p_out (low flow, large Delta p)"

    def flow(self, m, x, K):
        if K == 0.0:
            return m
        gk = x.g * x.g * K
        return 2.0 * m * m / (gk + np.sqrt(gk * gk + 4.0 * m * m) + 1e-300)
