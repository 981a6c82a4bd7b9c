"""Event alignment of a simulated oscillation to a recorded one.

Compared sample by sample, a model whose period is off by 1 % is a quarter cycle out
of phase after 25 cycles: the error then measures the accumulated phase, not the
model, and a least-squares fit has a local minimum at every cycle slip.  Aligned, each
recorded cycle k (from its rising mid-level crossing r_k to the next) is compared with
the simulated cycle k started at the simulation's own k-th crossing s_k:

    model value at recorded time t = y_sim(s_k + t − r_k),   r_k ≤ t < r_{k+1}

(before the first crossing, y_sim(t): the start-up from the known initial state).  A
period error then shows once per cycle, at its end, where it belongs; a few
milliseconds of timing at a jump of an algebraic node no longer add up.  The recorded
crossings are taken from a straight line through the samples around each one; each
cycle's shift is then refined on the whole cycle (least squares over its samples), so
the crossing's own noise does not stand in the cycle's residual.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: samples on each side of a recorded crossing used for its straight-line estimate
LINE_HALF_WIDTH = 2
#: Gauss–Newton steps refining each cycle's shift on the whole cycle
REFINE_STEPS = 2


def crossings(t, y, level) -> np.ndarray:
    """Times where ``y`` rises through ``level`` (linear between samples; hysteresis
    :func:`~pneunet.truth.circuits.data.crossing_band`), those closer than 30 % of the median
    spacing to the previous one dropped (noise)."""
    from ...engine.oscillation import rising_crossings
    from .data import crossing_band

    out = rising_crossings(t, y, level, crossing_band(y))
    if len(out) > 2:
        gap = 0.3 * float(np.median(np.diff(out)))
        keep = [0]
        for i in range(1, len(out)):
            if out[i] - out[keep[-1]] >= gap:
                keep.append(i)
        out = out[keep]
    return out


def recorded_crossings(t, y, level) -> np.ndarray:
    """Rising crossings of a noisy recording, each refined by least squares on a line
    through the ``2·LINE_HALF_WIDTH`` samples around it."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    rough = crossings(t, y, level)
    out = []
    for c in rough:
        i = int(np.searchsorted(t, c))
        lo, hi = max(0, i - LINE_HALF_WIDTH), min(len(t), i + LINE_HALF_WIDTH)
        if hi - lo < 2:
            out.append(c)
            continue
        slope, icept = np.polyfit(t[lo:hi] - c, y[lo:hi], 1)
        out.append(c + (level - icept) / slope if slope > 0 else c)
    return np.array(out)


@dataclass(frozen=True)
class Alignment:
    """Cycle starts of the recording at signal ``signal`` (mid level ``level``)."""

    signal: str
    level: float
    starts: np.ndarray
    margin: float  # s simulated past the record so a slower model still has its cycle
    record: tuple = ()  # (times, values) of the recorded signal: each cycle's shift refined

    @classmethod
    def of(cls, t, y, signal: str) -> "Alignment | None":
        """Alignment for the recorded oscillation ``y(t)``; None when it holds fewer
        than two full cycles (then samples are compared at their own times)."""
        from .data import oscillates

        y = np.asarray(y, float)
        if not oscillates(t, y):
            return None
        half = t >= t[0] + 0.5 * (t[-1] - t[0])
        level = 0.5 * (float(np.min(y[half])) + float(np.max(y[half])))
        starts = recorded_crossings(t, y, level)
        if len(starts) < 3:
            return None
        return cls(signal, level, starts, 0.5 * float(np.median(np.diff(starts))),
                   (np.asarray(t, float), y))

    def window(self, t0: float, t1: float) -> "Alignment":
        """The same alignment restricted to cycle starts up to ``t1``."""
        return Alignment(self.signal, self.level, self.starts[self.starts <= t1], self.margin,
                         self.record)

    def model_times(self, times, sim_t, sim_y, first_time: float = 0.0,
                    settled: bool = False, anchored: bool = True) -> np.ndarray:
        """Simulation times compared with the recorded ``times`` (see the module doc);
        ``first_time``: the netlist time of the record's first sample.

        The simulation's crossings are found as the recording's are, from its values
        at the recorded spacing, so the sampling's own bias cancels.  Started from the
        record's own state, the cycles before the first recorded crossing are compared
        at their own times; ``settled`` (the simulation settled before the record, in an
        arbitrary phase): recorded cycle k with the k-th simulated cycle that starts after
        ``first_time`` + the first recorded crossing, the part before that crossing
        with the one before it.  ``anchored``: the start state is exact (the netlist's rest
        at switch-on), so the part before the first crossing keeps its own times; else
        (a state read from noisy first samples) its shift is refined as a cycle's."""
        from .model import sample_at

        times = np.asarray(times, float)
        if settled:
            dt = float(np.median(np.diff(times)))
            grid = np.arange(first_time, float(sim_t[-1]), dt)
        else:
            grid = times + first_time
        sim_starts = recorded_crossings(grid, sample_at(sim_t, sim_y, grid), self.level)
        if settled:
            sim_starts = sim_starts[sim_starts >= first_time + self.starts[0]]
        n = min(len(sim_starts), len(self.starts))
        if n == 0:
            return times + first_time
        k = np.searchsorted(self.starts[:n], times, side="right") - 1
        before = sim_starts[0] - self.starts[0] if settled else first_time
        shift = np.where(k >= 0, sim_starts[np.maximum(k, 0)] - self.starts[np.maximum(k, 0)],
                         before)
        kept = settled or not anchored
        return times + self._refined(shift, k if kept else np.where(k >= 0, k, -2),
                                     times, sim_t, sim_y)

    def _refined(self, shift, k, times, sim_t, sim_y):
        """Each cycle's shift moved by Gauss–Newton steps to the one that matches the whole
        recorded cycle best (least squares over its samples): a crossing time read from a
        few noisy samples is off by milliseconds, and that error times the steep slope
        after a corner would stand in the residual of the whole cycle."""
        from .model import sample_at

        if not self.record:
            return shift
        rec_t, rec_y = self.record
        measured = np.interp(times, rec_t, rec_y)
        dt = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
        h = 1e-3 * dt
        out = shift.copy()
        for cycle in np.unique(k[k >= -1]):  # -2: compared at its own times
            idx = k == cycle
            s = float(shift[idx][0])
            for _ in range(REFINE_STEPS):
                at = times[idx] + s
                r = sample_at(sim_t, sim_y, at) - measured[idx]
                slope = (sample_at(sim_t, sim_y, at + h) - sample_at(sim_t, sim_y, at - h)) / (2 * h)
                denom = float(slope @ slope)
                if not denom > 0:
                    break
                s += float(np.clip(-(r @ slope) / denom, -dt, dt))
            out[idx] = s
        return out


def thinning(times, values, step: float) -> int:
    """Every how many samples a diagnosis fits an oscillating record ``values(times)``:
    the smallest k for which a change of ``step`` in ln value of a parameter its period
    scales with moves the end of a cycle by at most k sample spacings (1 for a record
    that does not oscillate).  Each cycle ends at an edge a sample or two wide: sampled
    finer, the cost is rugged at the scale of the fit's difference step, and LM stops
    between its kinks (the 240 mL oscillator at 50 Hz, 8.8 s cycles, with a hidden 3 mL
    dead volume: every fit of the dead volume stopped 2.5–4.9× the noise floor, and a
    wrong pair was accepted; on every 3rd sample (k = 3), and on every 2nd, the dead
    volume alone reaches the floor, every interval covering the truth)."""
    times = np.asarray(times, float)
    aligned = Alignment.of(times, values, "")
    if aligned is None or len(times) < 2:
        return 1
    spacing = float(np.median(np.diff(times)))
    period = float(np.median(np.diff(aligned.starts)))
    return max(1, math.ceil(step * period / spacing - 1e-9))


def thinned(df, node: str, step: float):
    """(``df`` on one sample in k, k, the note saying why or None) for a recording
    ``df`` (time_s, p_<node>_kPa, ...) of a circuit that oscillates on its own
    (:func:`thinning`; ``step``: the fits' difference step in ln value)."""
    column = f"p_{node}_kPa"
    if column not in df:
        return df, 1, None
    t = df["time_s"].to_numpy(float)
    k = thinning(t, df[column].to_numpy(float), step)
    if k == 1:
        return df, 1, None
    rate = 1.0 / float(np.median(np.diff(t)))
    note = (f"fitted on one sample in {k} ({rate / k:.3g} of {rate:.3g} Hz): at the full "
            f"rate a difference step of {step:g} in ln value moves the end of a cycle at "
            f"{node} by more than a sample, and the fits stop between the kinks that edges "
            "a sample wide put in the cost (so does the final fit, and its intervals miss: "
            "the values and intervals reported are those of the samples fitted)")
    out = df.iloc[::k].reset_index(drop=True)
    out.attrs = dict(df.attrs)
    return out, k, note
