"""``internal-drop``: pressure drop inside the valve acting on the membrane."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register_effect


@register_effect
class InternalDrop(Effect):
    """Pressure drop in the inlet chamber that acts on the membrane (the paper's sec. 7
    suggestion: flow-dependent pressures *inside* the valve).

    A fraction λ of the fixed resistance R_f lies between the inlet port and the
    chamber the membrane sees, so the membrane feels
    p_ch = √(p_hi² − (λ·R_f·ṁ)²) instead of p_hi and

        Δp = a_in·p_ch + a_out·p_lo − p_ctrl      (implicit in ṁ, solved per point)

    λ dimensionless in [0, 1]; null value 0.  The root is unique because Δp falls
    as ṁ rises.

    Residual signature: the valve opens more slowly than the plain model says
    when the flow is large — over-prediction along the opening flank (Δp slightly
    above p_close) growing with p_in; the open/closed plane itself is unaffected.
    """

    id = "internal-drop"
    params = {"lam": Param("1", 0.0, 1.0, 0.0, "fraction of R_f upstream of the membrane",
                           init=0.05)}
    uses_flow = True
    order = 50
    signature = "opening flank over-predicted at high flow (Delta p sags as the flow rises)"
    tell_apart = "partly open points at high p_in with large flow vs. small flow at the same Delta p"

    def delta_p(self, dp, x, lam):
        if lam == 0.0:
            return dp
        drop = lam * x.params.Rf * x.mdot
        p_ch = np.sqrt(np.maximum(x.p_hi * x.p_hi - drop * drop, 0.0))
        return dp - x.params.ain * (x.p_hi - p_ch)
