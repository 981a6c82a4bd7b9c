"""Measurements on sampled signals (netlist ``.meas``): pure functions of (t, y) arrays.

Every function takes a time vector ``t`` (increasing) and a signal ``y`` of the same
length and returns a float.  Crossing times are interpolated linearly between
samples.  A measurement that cannot be made (no crossing, window empty) raises
:class:`MeasureError` with the reason.
"""
from __future__ import annotations

import numpy as np

from ..common.errors import PneunetError


class MeasureError(PneunetError):
    """A measurement that cannot be made on the given signal."""


def _window(t, y, t_from=None, t_to=None):
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.shape != y.shape or t.ndim != 1:
        raise MeasureError("time and signal must be 1-D arrays of the same length")
    lo = t[0] if t_from is None else max(t_from, t[0])
    hi = t[-1] if t_to is None else min(t_to, t[-1])
    if hi < lo:
        raise MeasureError(f"empty window [{lo:g}, {hi:g}] s")
    inside = (t > lo) & (t < hi)
    tw = np.concatenate([[lo], t[inside], [hi]])
    yw = np.concatenate([[np.interp(lo, t, y)], y[inside], [np.interp(hi, t, y)]])
    if hi == lo:
        tw, yw = tw[:1], yw[:1]
    return tw, yw


def value_at(t, y, at):
    """y(at), linearly interpolated (FIND ... AT=)."""
    t = np.asarray(t, dtype=float)
    if not t[0] <= at <= t[-1]:
        raise MeasureError(f"time {at:g} s is outside the simulated [{t[0]:g}, {t[-1]:g}] s")
    return float(np.interp(at, t, y))


def minimum(t, y, t_from=None, t_to=None):
    return float(np.min(_window(t, y, t_from, t_to)[1]))


def maximum(t, y, t_from=None, t_to=None):
    return float(np.max(_window(t, y, t_from, t_to)[1]))


def peak_to_peak(t, y, t_from=None, t_to=None):
    yw = _window(t, y, t_from, t_to)[1]
    return float(np.max(yw) - np.min(yw))


def integral(t, y, t_from=None, t_to=None):
    tw, yw = _window(t, y, t_from, t_to)
    return float(np.trapezoid(yw, tw)) if hasattr(np, "trapezoid") else float(np.trapz(yw, tw))


def average(t, y, t_from=None, t_to=None):
    """Time average (trapezoidal) over the window."""
    tw, yw = _window(t, y, t_from, t_to)
    if tw[-1] == tw[0]:
        return float(yw[0])
    return integral(tw, yw) / (tw[-1] - tw[0])


def rms(t, y, t_from=None, t_to=None):
    tw, yw = _window(t, y, t_from, t_to)
    if tw[-1] == tw[0]:
        return float(abs(yw[0]))
    return float(np.sqrt(integral(tw, yw ** 2) / (tw[-1] - tw[0])))


def crossings(t, y, level, edge="cross", t_from=None, t_to=None):
    """All interpolated times where y crosses ``level`` ('rise', 'fall' or 'cross')."""
    tw, yw = _window(t, y, t_from, t_to)
    d = yw - level
    out = []
    for i in range(len(d) - 1):
        a, b = d[i], d[i + 1]
        rising = a < 0 <= b
        falling = a > 0 >= b
        if (rising and edge in ("rise", "cross")) or (falling and edge in ("fall", "cross")):
            # skip duplicated samples (jumps stored twice) and zero-length steps
            dt = tw[i + 1] - tw[i]
            out.append(float(tw[i] + (dt * (-a) / (b - a) if b != a else 0.0)))
    return out


def when(t, y, level, edge="cross", n=1, t_from=None, t_to=None):
    """Time of the n-th crossing of ``level`` (n = -1: the last one)."""
    times = crossings(t, y, level, edge, t_from, t_to)
    if not times or (n > 0 and len(times) < n):
        raise MeasureError(f"the signal {'crosses' if edge == 'cross' else edge + 's through'} "
                           f"{level:g} only {len(times)} time(s), not {n}"
                           if times else f"the signal never {edge}s through {level:g}")
    return times[n - 1] if n > 0 else times[-1]


def find_when(t, y, t2, y2, level, edge="cross", n=1, t_from=None, t_to=None):
    """y at the time signal y2 (on times t2) crosses ``level``."""
    return value_at(t, y, when(t2, y2, level, edge, n, t_from, t_to))


def transition_time(t, y, low, high, t_from=None, t_to=None):
    """Rise (low < high) or fall time: from the first crossing of ``low`` to the next of ``high``.

    For a rise, the start is the last time the signal rose through ``low`` before
    it first reaches ``high`` (a signal starting exactly at ``low`` starts at t0).
    """
    rising = high > low
    edge = "rise" if rising else "fall"
    tw, yw = _window(t, y, t_from, t_to)
    t_end = when(tw, yw, high, edge, 1)
    before = [c for c in crossings(tw, yw, low, edge) if c <= t_end]
    if before:
        t_begin = before[-1]
    elif (yw[0] >= low if rising else yw[0] <= low):
        t_begin = float(tw[0])
    else:  # pragma: no cover - cannot reach high without crossing low
        raise MeasureError(f"the signal never crosses {low:g}")
    return float(t_end - t_begin)


def period(t, y, level=None, t_from=None, t_to=None, cycles=None):
    """Mean period of an oscillation from successive rising crossings of ``level``.

    ``level`` defaults to the mid-range of the window; ``cycles`` limits the mean
    to the last N full cycles (default: all full cycles in the window).
    """
    tw, yw = _window(t, y, t_from, t_to)
    if level is None:
        level = 0.5 * (np.max(yw) + np.min(yw))
        if np.max(yw) - np.min(yw) <= 1e-9 * max(1.0, abs(level)):
            raise MeasureError("the signal does not oscillate (it is constant)")
    times = crossings(tw, yw, level, "rise")
    if len(times) < 2:
        raise MeasureError(f"fewer than two rising crossings of {level:g}: no oscillation "
                           "in the window", hint="simulate longer or lower FROM=")
    times = np.array(times)
    if cycles:
        times = times[-(cycles + 1):]
    return float((times[-1] - times[0]) / (len(times) - 1))


def frequency(t, y, level=None, t_from=None, t_to=None, cycles=None):
    return 1.0 / period(t, y, level, t_from, t_to, cycles)


def trig_targ(t1, y1, trig: dict, t2, y2, targ: dict):
    """Delay from a trigger crossing to a target crossing (each a dict of val/edge/n/from)."""
    a = when(t1, y1, trig["val"], trig.get("edge", "cross"), trig.get("n", 1), trig.get("from"))
    b = when(t2, y2, targ["val"], targ.get("edge", "cross"), targ.get("n", 1), targ.get("from"))
    return float(b - a)
