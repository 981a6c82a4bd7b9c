"""Dense output between stored integrator steps: piecewise cubic Hermite.

Between two accepted steps (t_k, y_k, ẏ_k) and (t_k+1, y_k+1, ẏ_k+1) the cubic
matching both values and both slopes has an error O(h⁴), below the step's own
local error for the BDF orders 1–5 at the tolerances pneunet uses, so the output
grid no longer sets the step size (docs/numerics.md).
"""
from __future__ import annotations

import numpy as np


def hermite(t: np.ndarray, y: np.ndarray, yp: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Values at ``times`` (m,) ⊂ [t[0], t[-1]] of the cubic Hermite interpolant of
    the rows ``y``, ``yp`` (k, n) at the increasing times ``t`` (k,); shape (m, n)."""
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = (times - t[k])[:, None] / h
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * y[k] + (s3 - 2 * s2 + s) * h * yp[k]
            + (3 * s2 - 2 * s3) * y[k + 1] + (s3 - s2) * h * yp[k + 1])
