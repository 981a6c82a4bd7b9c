"""The measurement noise floor, estimated from the data alone.

A residual (measurement − model) is misfit plus noise.  Along a sampled record, the
misfit is smooth from one sample to the next while white noise is not: the second
difference r[i−1] − 2·r[i] + r[i+1] cancels a locally linear misfit and keeps the noise
with variance 6σ².  A robust scale (the normalised median absolute deviation) ignores
the few places where the misfit is sharp (a fold, a valve opening).
"""
from __future__ import annotations

import numpy as np

#: MAD → standard deviation of a normal distribution
MAD_TO_SIGMA = 1.4826


def second_differences(r, groups=None, centres: bool = False):
    """r[i−1] − 2r[i] + r[i+1] for every i whose neighbours lie in the same group
    (a sweep, a contiguous stretch of samples); ``groups`` None: one group.  With
    ``centres`` also the indices i (to bin the differences by where they sit)."""
    r = np.asarray(r, float)
    if len(r) < 3:
        return (np.empty(0), np.empty(0, int)) if centres else np.empty(0)
    ok = np.ones(len(r) - 2, dtype=bool)
    if groups is not None:
        g = np.asarray(groups)
        ok = (g[:-2] == g[1:-1]) & (g[2:] == g[1:-1])
    d2 = r[:-2] - 2 * r[1:-1] + r[2:]
    keep = ok & np.isfinite(d2)
    return (d2[keep], np.flatnonzero(keep) + 1) if centres else d2[keep]


def robust_sigma(d2) -> float:
    """Noise standard deviation from second differences ``d2`` (zero-centred):
    1.4826 · median |d2| / √6."""
    return float(MAD_TO_SIGMA * np.median(np.abs(d2)) / np.sqrt(6.0))


def difference_sigma(r, groups=None, min_points: int = 10) -> float:
    """Noise standard deviation of ``r`` (same unit) from its second differences:
    1.4826 · median |d2 − median d2| / √6.  NaN when fewer than ``min_points``."""
    d2 = second_differences(r, groups)
    if len(d2) < min_points:
        return float("nan")
    return robust_sigma(d2 - np.median(d2))


def record_sigma(y, groups=None, order: int = 4, min_points: int = 10) -> float:
    """Noise standard deviation of a recorded signal ``y`` itself (no model yet): the
    normalised MAD of its ``order``-th differences within each group, / √C(2k, k) (70
    for k = 4).  A smooth signal's curvature cancels here where second differences keep
    it (a 100 mm swing of period 6 s at 20 Hz: second differences 0.1 mm, fourth
    0.001 mm).  At least the rounding of a signal logged on a grid
    (:func:`rounding_sigma`).  NaN with fewer than ``min_points`` differences."""
    from math import comb

    y = np.asarray(y, float)
    if len(y) <= order:
        return float("nan")
    d = np.diff(y, n=order)
    ok = np.isfinite(d)
    if groups is not None:
        g = np.asarray(groups)
        ok &= g[order:] == g[:-order]
    d = d[ok]
    if len(d) < min_points:
        return float("nan")
    spread = MAD_TO_SIGMA * np.median(np.abs(d - np.median(d)))
    return float(max(spread / np.sqrt(comb(2 * order, order)), rounding_sigma(y)))


#: standard deviation of rounding to a grid of step q, in q: uniform on ±q/2
ROUNDING_SIGMA = 1.0 / np.sqrt(12.0)


def resolution(y) -> float:
    """The step of the grid that a recorded signal's values lie on (a logger's or an
    ADC's resolution, in y's unit: 1.0 for whole kPa), 0.0 when they lie on none.

    Rounding to a step q adds an error of standard deviation q/√12 to every sample
    (:data:`ROUNDING_SIGMA`).  Differences do not see it where the signal is flat for
    longer than a step (every sample rounds the same way), so a noise floor taken from
    differences falls towards 0 on a quiet record logged in whole units.  The step is
    the smallest gap between neighbouring distinct values when every such gap is a
    whole number of it (within 1 %; an offset grid a·n + b too).  A grid much finer
    than the spacing of the values is not seen, and need not be: its rounding is far
    below any noise."""
    y = np.asarray(y, float)
    u = np.unique(y[np.isfinite(y)])
    if len(u) < 3:
        return 0.0
    # values a float's last digits apart (0.1·3 against 0.3) are one value
    u = u[np.concatenate([[True], np.diff(u) > 1e-9 * np.max(np.abs(u))])]
    if len(u) < 3:
        return 0.0
    gaps = np.diff(u)
    steps = gaps / np.min(gaps)
    if float(np.max(np.abs(steps - np.round(steps)))) > 0.01:
        return 0.0
    return float((u[-1] - u[0]) / np.sum(np.round(steps)))


def rounding_sigma(y) -> float:
    """Standard deviation of the rounding in a recorded signal ``y``: its
    :func:`resolution` / √12 (0.0 when it lies on no grid)."""
    return resolution(y) * ROUNDING_SIGMA


def segments(mask) -> np.ndarray:
    """Group ids of the contiguous runs of True in ``mask`` (−1 where False, each False
    sample its own group so no difference spans it)."""
    mask = np.asarray(mask, bool)
    starts = np.cumsum(np.concatenate([[True], mask[1:] != mask[:-1]]))
    return np.where(mask, starts, -1 - np.arange(len(mask)))


#: the lag-1 autocorrelation of white noise's second differences: −4/6
WHITE_D2_CORRELATION = -2.0 / 3.0


def difference_correlation(r, groups=None, min_points: int = 30) -> tuple[float, int]:
    """(lag-1 autocorrelation of ``r``'s second differences, pairs used): robust
    (Gnanadesikan–Kettenring, from the MADs of the pairs' sums and differences: a few
    sharp corners do not move it), within groups.  White noise gives
    −2/3 (:data:`WHITE_D2_CORRELATION`, standard error about 1/√n); AR(1) noise of
    coefficient φ gives (−4 + 7φ − 4φ² + φ³)/(6 − 8φ + 2φ²): −0.59 at φ = 0.3, −0.52 at
    0.7, towards −1/2 as φ → 1.  NaN with fewer than ``min_points`` pairs."""
    d, at = second_differences(r, groups, centres=True)
    pair = np.flatnonzero(np.diff(at) == 1)
    if groups is not None:
        g = np.asarray(groups)
        pair = pair[g[at[pair]] == g[at[pair + 1]]]
    if len(pair) < min_points:
        return float("nan"), int(len(pair))
    a, b = d[pair], d[pair + 1]
    u = np.median(np.abs((a + b) - np.median(a + b))) ** 2
    v = np.median(np.abs((a - b) - np.median(a - b))) ** 2
    if not u + v > 0:
        return float("nan"), int(len(pair))
    return float((u - v) / (u + v)), int(len(pair))
