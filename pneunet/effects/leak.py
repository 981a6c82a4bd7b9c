"""``leak``: flow past the closed seat."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect


@register_effect
class Leak(Effect):
    """Leak past the closed seat: a constant quadrature conductance in parallel.

        ṁ = ṁ_valve + G_leak·√(p_hi² − p_lo²)

    The seat does not seal perfectly (the paper excluded leaking valves, sec.
    5.4); the leak path is a fixed orifice that stays when the membrane closes.
    G_leak in mg/(s·kPa); null value 0.

    Residual signature: closed points (Δp ≤ p_close) show a positive flow that
    grows with √(p_in² − p_out²) and does not depend on p_ctrl.
    """

    id = "leak"
    params = {"G": Param("mg/(s*kPa)", 0.0, 0.5, 0.0, "leak conductance", init=1e-3)}
    order = 30
    signature = "closed valve: positive flow growing with sqrt(p_in^2 - p_out^2)"
    tell_apart = "closed-valve points (p_ctrl at its maximum) over a wide range of p_in, p_out"

    def flow(self, m, x, G):
        return m + G * np.sqrt(np.maximum(x.d, 0.0))
