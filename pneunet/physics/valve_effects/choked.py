"""``choked``: choked (sonic) flow — ISO 6358 ellipse (b, m) or capped quadrature law."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect


@register_effect
class Choked(Effect):
    """Choked (sonic) flow in both published forms: the ISO 6358 ellipse with
    critical ratio b and subsonic exponent m, and the quadrature law capped at a
    critical pressure ratio r_c.

    With r = p_lo/p_hi, the valve conductance G = 1/R of eq. 19 and
    z = (max(r, r*) − b)/(1 − b) clipped to [0, 1]:

        ṁ = G·p_hi·(1 − z²)^m,      r* = b + c·(1 − b)

    * ISO 6358-1 (1989): c = 0, m = ½ — ṁ = G·p_hi for r ≤ b (choked),
      G·p_hi·√(1 − ((r − b)/(1 − b))²) above;
    * ISO 6358-1:2013, generalised subsonic exponent: c = 0, m ≠ ½;
    * quadrature law capped at the critical ratio r_c: b = 0, m = ½, c = r_c —
      ṁ = G·√(p_hi² − p_lo²) for r ≥ r_c, G·p_hi·√(1 − r_c²) below.

    b = 0, m = ½, c = 0 is the plain quadrature law ṁ = G·√(p_hi² − p_lo²) of the
    valve; null value b = 0, m = 0.5, c = 0.  (c measures the cap on the ellipse's
    own axis z, so every parameter changes the flow wherever it is not null.)

    Residual signature of the missing effect: among open points the relative
    error depends on p_out/p_in — for the ellipse the plain model under-predicts
    the flow at low pressure ratios (r < ~0.5) and, once R_f is refitted,
    over-predicts it near r → 1; for the capped law it over-predicts the flow
    below r_c.
    """

    id = "choked"
    params = {
        "b": Param("1", 0.0, 0.9, 0.0, "ISO 6358 critical pressure ratio", init=0.05),
        "m": Param("1", 0.2, 1.5, 0.5, "subsonic exponent (ISO 6358-1:2013)", init=0.5),
        "c": Param("1", 0.0, 0.9, 0.0, "flow capped below r = b + c(1 - b) "
                   "(= r_c of the capped quadrature law when b = 0)", init=0.5),
    }
    order = 10
    signature = "open-valve error varies with p_out/p_in (flow under-predicted at low ratio)"
    tell_apart = "points with p_out/p_in well below b at high p_in (flow stops rising as p_out falls)"

    def flow(self, mdot, x, b, m, c):
        # the valve flow ``mdot`` is replaced: the effect defines the pressure law
        if b == 0.0 and m == 0.5 and c == 0.0:
            return mdot
        r = np.where(x.p_hi > 0, x.p_lo / np.where(x.p_hi > 0, x.p_hi, 1.0), 1.0)
        r = np.maximum(r, b + c * (1.0 - b))
        z = np.clip((r - b) / (1.0 - b), 0.0, 1.0)
        s = 1.0 - z * z
        return x.g * x.p_hi * (np.sqrt(s) if m == 0.5 else s ** m)
