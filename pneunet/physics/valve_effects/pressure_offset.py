"""``pressure-offset``: wrong ambient/gauge offset or sensor offset."""
from __future__ import annotations

from .base import Effect, Param, register_effect


@register_effect
class PressureOffset(Effect):
    """A common offset on the measured absolute pressures.

    Gauge readings converted with a wrong barometric pressure (the paper used
    96 kPa) or a shared sensor offset: the valve really sees

        p_x,true = p_x,measured + p0        for x = in, out, ctrl

    The quadratic law then uses (p_in + p0)² − (p_out + p0)², which changes the
    flow most at low absolute pressures; Δp moves by (a_in + a_out − 1)·p0.
    p0 in kPa; null value 0.

    Residual signature: open-valve relative error that depends on p_in + p_out
    (largest at low absolute pressure), not on p_ctrl.
    """

    id = "pressure-offset"
    params = {"p0": Param("kPa", -50.0, 50.0, 0.0, "offset added to measured pressures",
                          init=0.5)}
    order = 10
    signature = "open-valve relative error depends on the absolute pressure level p_in + p_out"
    tell_apart = "a reading of all sensors at ambient pressure (zero check) or open points at low p_in"

    def pressures(self, x, p0):
        return x.p_in + p0, x.p_out + p0, x.p_ctrl + p0
