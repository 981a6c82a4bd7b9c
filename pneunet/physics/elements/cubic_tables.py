"""Many monotone-cubic (PCHIP) tables evaluated at once: y(x), y'(x) and y''(x) of every
instance in one vectorised pass (a table actuator then costs about what an accumulator does).

Each instance's table (x strictly increasing) is scipy's ``PchipInterpolator`` (Fritsch–
Carlson slopes: no overshoot, local extrema kept), continued linearly with its end slopes
outside the table.  All instances' knots are mapped onto one increasing axis, instance i
onto [2i, 2i + 1], so that one ``np.searchsorted`` finds every interval.
"""
from __future__ import annotations

from bisect import bisect_right

import numpy as np

from .base import FEW_INSTANCES


class CubicTables:
    """PCHIP interpolants of the tables ``[(x, y), …]``, one per instance."""

    def __init__(self, tables):
        from scipy.interpolate import PchipInterpolator

        self.lo = np.array([float(x[0]) for x, _ in tables])
        self.hi = np.array([float(x[-1]) for x, _ in tables])
        self._span = self.hi - self.lo
        knots, coeffs, firsts, count = [], [], [], 0
        for i, (x, y) in enumerate(tables):
            curve = PchipInterpolator(np.asarray(x, float), np.asarray(y, float))
            firsts.append(count)
            count += len(x) - 1
            knots.append((np.asarray(x[:-1], float) - x[0]) / (x[-1] - x[0]) + 2 * i)
            coeffs.append(curve.c)
        self._knots = np.concatenate(knots)
        self._x0 = np.concatenate([np.asarray(x[:-1], float) for x, _ in tables])
        self._c = np.concatenate(coeffs, axis=1)         # (4, intervals): c0·h³ + … + c3
        self._first = np.array(firsts)
        self._y_lo = np.array([float(y[0]) for _, y in tables])
        self._y_hi = np.array([float(PchipInterpolator(x, y)(x[-1])) for x, y in tables])
        self.slope_lo = self._c[2][self._first]
        last = np.r_[self._first[1:], self._c.shape[1]] - 1
        h_last = self.hi - self._x0[last]
        c = self._c[:, last]
        self.slope_hi = (3 * c[0] * h_last + 2 * c[1]) * h_last + c[2]
        self._offset = 2.0 * np.arange(len(tables))
        # the same, as Python floats: one instance at a time beats numpy's per-call cost
        self._each = [(self._x0[f:f + len(x) - 1].tolist(), self._c[:, f:f + len(x) - 1].T.tolist(),
                       float(x[0]), float(x[-1]), lo_y, hi_y, s_lo, s_hi)
                      for (x, _), f, lo_y, hi_y, s_lo, s_hi in zip(
                          tables, self._first, self._y_lo.tolist(), self._y_hi.tolist(),
                          self.slope_lo.tolist(), self.slope_hi.tolist())]

    def __call__(self, x):
        """y, dy/dx and d²y/dx² of each instance at x (..., n)."""
        x = np.asarray(x, dtype=float)
        if x.ndim == 1 and x.size <= FEW_INSTANCES:
            return tuple(np.array(column) for column in zip(*map(_one, self._each, x.tolist())))
        inside = np.clip(x, self.lo, self.hi)
        where = (inside - self.lo) / self._span + self._offset
        j = np.searchsorted(self._knots, where, side="right") - 1
        j = np.maximum(j, self._first)  # x at lo: the first interval
        c0, c1, c2, c3 = self._c[0][j], self._c[1][j], self._c[2][j], self._c[3][j]
        h = inside - self._x0[j]
        y = ((c0 * h + c1) * h + c2) * h + c3
        dy = (3 * c0 * h + 2 * c1) * h + c2
        d2y = 6 * c0 * h + 2 * c1
        below, above = x < self.lo, x > self.hi
        if below.any() or above.any():
            y = np.where(below, self._y_lo + self.slope_lo * (x - self.lo),
                         np.where(above, self._y_hi + self.slope_hi * (x - self.hi), y))
            dy = np.where(below, self.slope_lo, np.where(above, self.slope_hi, dy))
            d2y = np.where(below | above, 0.0, d2y)
        return y, dy, d2y


def _one(table, x):
    """(y, y', y'') of one table at the float x."""
    x0, coeffs, lo, hi, y_lo, y_hi, slope_lo, slope_hi = table
    if x < lo:
        return y_lo + slope_lo * (x - lo), slope_lo, 0.0
    if x > hi:
        return y_hi + slope_hi * (x - hi), slope_hi, 0.0
    j = max(bisect_right(x0, x) - 1, 0)
    c0, c1, c2, c3 = coeffs[j]
    h = x - x0[j]
    return ((c0 * h + c1) * h + c2) * h + c3, (3 * c0 * h + 2 * c1) * h + c2, 6 * c0 * h + 2 * c1
