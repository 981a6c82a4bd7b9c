"""``hysteresis``: different opening and closing thresholds."""
from __future__ import annotations

from .base import Effect, Param, register_effect


@register_effect
class Hysteresis(Effect):
    """Different opening and closing thresholds (membrane stiction / adhesion to the seat).

    With the sweep direction s (−1: p_ctrl falling, the valve opening; +1:
    p_ctrl rising, the valve closing) the threshold becomes

        p_close,eff = p_close − s·h/2     ⇔     Δp_eff = Δp + s·h/2

    so the valve opens at p_close + h/2 and closes at p_close − h/2.  h in kPa;
    null value 0.  Needs the ``sweep`` column (or row order from which the
    diagnosis derives it); without a sweep direction (a circuit simulation) the
    mean threshold p_close is used.

    Residual signature: the residual changes sign with the sweep direction along
    the opening flank; falling and rising sweeps disagree at the same pressures.
    """

    id = "hysteresis"
    params = {"h": Param("kPa", -60.0, 60.0, 0.0, "opening minus closing threshold", init=0.5)}
    needs = ("sweep",)
    order = 40
    signature = "residual flips sign with the sweep direction near the opening threshold"
    tell_apart = "rising and falling p_ctrl sweeps at the same p_in, p_out"

    def delta_p(self, dp, x, h):
        if h == 0.0 or x.sweep is None:
            return dp
        return dp + x.sweep * (0.5 * h)
