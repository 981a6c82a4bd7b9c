"""Dense output within one integrator step: the cubic Hermite through its two ends.

Between two accepted steps (t_k, y_k, ẏ_k) and (t_k+1, y_k+1, ẏ_k+1) the cubic
matching both values and both slopes has an error O(h⁴), below the step's own
local error for the BDF orders 1–5 at the tolerances pneunet uses, so the output
grid no longer sets the step size (docs/numerics.md).  Many steps of one solution at
once: :class:`pneunet.physics.waveforms.SampleTable`.
"""
from __future__ import annotations


def hermite_step(s, h, y0, d0, y1, d1, slope=True):
    """Value and slope of the cubic through (y0, slope d0) and (y1, d1) over a step of
    length h, at the fractions s of the step (arrays broadcasting together); the slope
    is None unless asked for."""
    s2, s3 = s * s, s * s * s
    value = ((2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * h * d0
             + (3 * s2 - 2 * s3) * y1 + (s3 - s2) * h * d1)
    if not slope:
        return value, None
    slope = ((6 * s2 - 6 * s) * (y0 - y1) / h + (3 * s2 - 4 * s + 1) * d0
             + (3 * s2 - 2 * s) * d1)
    return value, slope
