"""Oscillation analysis of a transient: sustained or decaying, period, duty cycle, extremes.

:func:`analyze_oscillation` works on any sampled signal (a Solution's pressure, or a
measured trace).  :func:`oscillator_period` simulates a circuit for as long as it takes
the cycle to converge: it doubles the simulated time until the last periods and
extremes agree to the requested tolerance, instead of running one fixed long transient.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..common.errors import PneunetError
from ..common.reprs import Summarized, number


@dataclass(frozen=True, repr=False)
class Oscillation(Summarized):
    """Result of :func:`analyze_oscillation`.

    kind        'limit_cycle' (sustained), 'decaying', 'growing', 'equilibrium', or
                'undetermined' (still moving, fewer than two full cycles: simulate longer)
    period_s    mean of the last ``cycles`` periods (nan without oscillation)
    duty_cycle  fraction of a period the signal spends above the mid level
    rise_fraction  fraction of a period the signal rises (filling, valve open)
    p_min, p_max   extremes over the last full cycles (or final value for equilibrium)
    amplitude_ratio  peak-to-peak of the last cycle / the one before (1: sustained)
    converged   the last two periods agree to ``rtol``
    """

    kind: str
    period_s: float
    frequency_hz: float
    duty_cycle: float
    rise_fraction: float
    p_min: float
    p_max: float
    final: float
    cycles: int
    amplitude_ratio: float
    period_change: float
    converged: bool

    @property
    def oscillating(self) -> bool:
        return self.kind == "limit_cycle"

    def _summary(self):
        rows = [("period", number(self.period_s, "s")),
                ("duty cycle", number(self.duty_cycle, "", 3)),
                ("pressure", f"{self.p_min:.4g}–{self.p_max:.4g} kPa"),
                ("cycles", str(self.cycles)), ("converged", str(self.converged))]
        return self.kind, rows, ".as_dict() for every field"

    def as_dict(self) -> dict:
        d = asdict(self)
        d["oscillating"] = self.oscillating
        return d


def rising_crossings(t, y, level, band: float = 0.0) -> np.ndarray:
    """Times (s) where ``y`` rises through ``level``, linear between samples.

    With ``band`` > 0 (signal units: a few noise σ of a recording) a rise counts once
    per excursion, from the last sample below ``level − band`` to the first at or above
    ``level + band``; its time is where a straight line fitted to the samples between
    them meets the level.  Noise riding on a falling or flat stretch near the level then
    makes no crossing, and noise on the rise does not bias its time."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    d = y - level
    if band > 0:
        return _banded_rises(t, d, band)
    idx = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))[0]
    step = d[idx + 1] - d[idx]
    frac = np.divide(-d[idx], step, out=np.zeros(idx.size), where=step != 0)
    return t[idx] + frac * (t[idx + 1] - t[idx])


def _banded_rises(t, d, band) -> np.ndarray:
    """The rises of ``d`` through 0 with hysteresis ``band`` (see :func:`rising_crossings`)."""
    below, above = np.flatnonzero(d < -band), np.flatnonzero(d >= band)
    out = []
    k = 0
    while k < below.size:
        a = np.searchsorted(above, below[k])
        if a == above.size:
            break
        j = above[a]
        last = below[np.searchsorted(below, j) - 1]  # last sample below before j
        span = slice(last, j + 1)
        slope, icept = np.polyfit(t[span] - t[last], d[span], 1)
        out.append(float(np.clip(t[last] - icept / slope, t[last], t[j])) if slope > 0
                   else t[last])
        k = np.searchsorted(below, j)
    return np.array(out)


def analyze_oscillation(t, y=None, *, rtol: float = 1e-3, min_amplitude: float = 1.0,
                        cycles: int = 3, band: float = 0.0) -> Oscillation:
    """Classify the signal ``y(t)`` and measure its oscillation.

    The mid level is the mean of the extremes of the second half of the record;
    cycles are delimited by its rising crossings.  ``min_amplitude`` (signal units,
    kPa) is the smallest peak-to-peak counted as oscillation; ``rtol`` the relative
    change of the period and amplitude between the last two cycles below which the
    cycle counts as converged; ``band`` the crossings' hysteresis for a noisy
    recording (:func:`rising_crossings`).
    """
    if y is None or hasattr(t, "signals"):
        raise PneunetError("analyze_oscillation takes a time array and a signal array, "
                           f"got {type(t).__name__}" + (" and no signal" if y is None else ""),
                           hint="analyze_oscillation(sol.t, sol.pressure('tank')); to simulate "
                                "a circuit until it oscillates steadily: oscillator_period")
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or len(t) < 3:
        raise PneunetError("analyze_oscillation needs 1-D time and signal arrays of equal length")
    final = float(y[-1])
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    lo, hi = float(np.min(y[half])), float(np.max(y[half]))
    nan = float("nan")
    if hi - lo < min_amplitude:
        return Oscillation("equilibrium", nan, nan, nan, nan, final, final, final, 0, nan, nan, True)
    level = 0.5 * (lo + hi)
    rises = rising_crossings(t, y, level, band)
    if len(rises) < 3:
        # fewer than two full cycles: a transient that has not settled yet
        kind = "undetermined"
        return Oscillation(kind, nan, nan, nan, nan, lo, hi, final, max(len(rises) - 1, 0), nan, nan,
                           False)
    periods = np.diff(rises)
    amps, duty, rise = [], [], []
    for a, b in zip(rises[:-1], rises[1:]):
        inside = (t >= a) & (t <= b)
        tw, yw = t[inside], y[inside]
        amps.append(np.max(yw) - np.min(yw))
        dt = np.diff(tw)
        mid = 0.5 * (yw[1:] + yw[:-1])
        duty.append(np.sum(dt[mid > level]) / (b - a))
        rise.append(np.sum(dt[np.diff(yw) > 0]) / (b - a))
    amps = np.array(amps)
    ratio = float(amps[-1] / amps[-2]) if len(amps) > 1 and amps[-2] > 0 else 1.0
    change = float(abs(periods[-1] - periods[-2]) / periods[-1]) if len(periods) > 1 else nan
    # is the signal still alive after the last rising crossing?
    tail = t >= rises[-1]
    tail_amp = np.max(y[tail]) - np.min(y[tail])
    if ratio < 1 - 10 * rtol and ratio < 0.98 or tail_amp < 0.5 * amps[-1] and t[-1] - rises[-1] > 1.5 * periods[-1]:
        kind = "decaying"
    elif ratio > 1 + 10 * rtol and ratio > 1.02:
        kind = "growing"
    else:
        kind = "limit_cycle"
    k = min(cycles, len(periods))
    period = float(np.mean(periods[-k:]))
    window = t >= rises[-k - 1]
    converged = bool(kind == "limit_cycle" and np.isfinite(change) and change <= rtol
                     and abs(ratio - 1) <= max(rtol, 1e-3))
    end = t <= rises[-1]
    w = window & end
    return Oscillation(kind, period, 1.0 / period, float(np.mean(duty[-k:])),
                       float(np.mean(rise[-k:])), float(np.min(y[w])), float(np.max(y[w])), final,
                       len(periods), ratio, change, converged)


@dataclass(frozen=True, repr=False)
class PeriodResult(Summarized):
    """Result of :func:`oscillator_period`: the analysis, the solution and the time
    simulated (s) over ``runs`` transients."""

    oscillation: Oscillation
    solution: object
    t_simulated: float
    runs: int

    def _summary(self):
        title, rows, _ = self.oscillation._summary()
        rows.append(("simulated", f"{self.t_simulated:g} s in {self.runs} run(s)"))
        return title, rows, ".oscillation (all measures), .solution (the last transient)"

    @property
    def period_s(self) -> float:
        return self.oscillation.period_s


def oscillator_period(circuit, node: str = "tank", *, rtol: float = 1e-4, t_initial: float = 20.0,
                      t_max: float = 640.0, min_cycles: int = 2, min_amplitude: float = 1.0,
                      progress: bool = False) -> PeriodResult:
    """Period of ``circuit``'s oscillation at ``node``, simulated until the cycle converges.

    Starts with ``t_initial`` seconds and doubles the simulated time until at least
    ``min_cycles`` cycles are seen and the last two periods and amplitudes agree to
    ``rtol`` (a settled equilibrium also ends the search).  The total cost is at most
    twice that of the final run.  Raises :class:`PneunetError` when ``t_max`` is reached
    without convergence (the last analysis is attached as ``err.partial``).
    """
    if not callable(getattr(circuit, "tran", None)):
        raise PneunetError(f"oscillator_period takes a Circuit to simulate, got "
                           f"{type(circuit).__name__}",
                           hint="for a Solution you have: analyze_oscillation(sol.t, "
                                "sol.pressure(node))")
    t_stop, runs = t_initial, 0
    while True:
        sol = circuit.tran(t_stop, progress=progress)
        runs += 1
        osc = analyze_oscillation(sol.t, sol.pressure(node), rtol=rtol, min_amplitude=min_amplitude)
        settled = osc.kind == "equilibrium" and _settled(sol.t, sol.pressure(node), min_amplitude)
        if settled or (osc.kind == "decaying" and osc.cycles >= min_cycles):
            return PeriodResult(osc, sol, t_stop, runs)
        if osc.converged and osc.cycles >= min_cycles:
            return PeriodResult(osc, sol, t_stop, runs)
        if t_stop >= t_max:
            err = PneunetError(f"the oscillation at node {node} did not converge within {t_max:g} s "
                               f"(kind {osc.kind}, {osc.cycles} cycles, period change "
                               f"{osc.period_change:.2g})", hint="raise t_max or loosen rtol")
            err.partial = PeriodResult(osc, sol, t_stop, runs)
            raise err
        if osc.oscillating and np.isfinite(osc.period_s):
            # jump straight to a run long enough for the cycles still needed
            need = (min_cycles + 3) * osc.period_s
            t_stop = min(t_max, max(2 * t_stop, need))
        else:
            t_stop = min(t_max, 2 * t_stop)


def _settled(t, y, tol):
    tail = t >= t[0] + 0.75 * (t[-1] - t[0])
    return float(np.max(y[tail]) - np.min(y[tail])) < 0.1 * tol


def classify(t, y, **kw) -> str:
    """'oscillation' or 'equilibrium' (a decaying oscillation counts as equilibrium)."""
    return "oscillation" if analyze_oscillation(t, y, **kw).oscillating else "equilibrium"
