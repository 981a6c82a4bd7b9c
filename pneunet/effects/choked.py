"""``choked``: ISO 6358 critical pressure ratio b."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect


@register_effect
class Choked(Effect):
    """Choked (sonic) flow with the ISO 6358 critical pressure ratio b.

    The quadrature law ṁ = G·√(p_hi² − p_lo²) = G·p_hi·√(1 − r²), r = p_lo/p_hi,
    is the ISO 6358 law with b = 0.  With a critical ratio b > 0 (ISO 6358-1):

        ṁ = G·p_hi                                 r ≤ b   (choked)
        ṁ = G·p_hi·√(1 − ((r − b)/(1 − b))²)        r > b   (subsonic)

    with the valve conductance G = 1/R of eq. 19 unchanged.  Null value b = 0.

    Residual signature of the missing effect: among open points the relative
    error depends on p_out/p_in — the plain model under-predicts the flow at low
    pressure ratios (r < ~0.5) and, once R_f is refitted, over-predicts it near
    r → 1.
    """

    id = "choked"
    params = {"b": Param("1", 0.0, 0.9, 0.0, "critical pressure ratio", init=0.05)}
    order = 10
    signature = "open-valve error varies with p_out/p_in (flow under-predicted at low ratio)"
    tell_apart = "points with p_out/p_in well below b at high p_in (flow stops rising as p_out falls)"

    def flow(self, m, x, b):
        if b == 0.0:
            return m
        r = np.where(x.p_hi > 0, x.p_lo / np.where(x.p_hi > 0, x.p_hi, 1.0), 1.0)
        z = np.clip((r - b) / (1.0 - b), 0.0, 1.0)
        return x.g * x.p_hi * np.sqrt(1.0 - z * z)
