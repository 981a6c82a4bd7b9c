"""The netlist time of a driven recording's first sample, when the logger kept its own clock.

A circuit driven by its sources is simulated on the sources' clock: the first sample
sits at some netlist time, by default the file's first time stamp.  A logger started
by hand counts from its own zero (or writes the wall clock), and then the sources
switch at the wrong moments in the simulation: every fit misses by the whole swing.

For periodic sources (PULSE with a period, undamped SIN; several of them with a common
period P) one simulation from rest through two periods gives the circuit's response at
every phase.  The record's first period is compared with it at every start on the
sample grid (each signal in units of its own noise): every phase of the settled cycle,
and every time within one period of switch-on (a logger started just before the
supply or the sources' first switching: no settled history).
The file's clock is kept when it gives the best start or an rms misfit within
:data:`CLOCK_SLACK` × the best start's.  Else the best start is used (a phase of the
settled cycle placed ⌈span/P⌉ periods after the sources' delay, a history of at least
the record's length), and the start state says so.

Sources that change once (a STEP, a PULSE without a period, a PWL) are placed the same
way by the change the record shows (:func:`_one_shot_clock`): every start from a record's
length before the first change to one after the last, the whole record compared; so are
periodic sources beside such a change (a supply switched on while the valves pulse), the
starts after it then spanning a period of theirs at least.

That phase is found at the parameter guesses.  :func:`fit_clock` then fits the clock
with the parameters (a last least-squares unknown: its shift in sample spacings), from
that phase and from a sample either way where the first fit is not at the record's
noise, and again from the phase found at the fitted values (an effect included) when
that is a sample away; :func:`clock_fitted` gives the start state with the fitted clock
and its interval.  Used by :func:`~pneunet.truth.circuits.fit.fit_trace`.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...common.errors import PneunetError
from ..core.lsq import least_squares_log
from ..core.noise import record_sigma, segments

#: the file's clock is kept unless its rms misfit is more than this factor of the best
#: start's: the user's clock stands unless the record contradicts it (a missing effect,
#: such as a tube delaying a valve, moves the best phase too, but by a misfit ratio near 1;
#: a logger's own clock misplaces the switching by tens of times the noise)
CLOCK_SLACK = 2.0
#: most periods of the longest source tried for a common period of several
MAX_PERIODS = 100
#: simulation output points per sample spacing (the phase is found to a fifth of it)
FINER = 5
#: most phases compared at once, and most samples of the record compared at each
SCAN_POINTS = 1000


def common_period(waveforms) -> float | None:
    """The common period (s) of periodic waveforms, None when one is not periodic or
    they have none within :data:`MAX_PERIODS` of the longest."""
    from ...physics.waveforms import Pulse, Sine

    periods = []
    for w in waveforms:
        if isinstance(w, Pulse) and w.period > 0:
            periods.append(float(w.period))
        elif isinstance(w, Sine) and w.frequency > 0 and w.damping == 0:
            periods.append(1.0 / float(w.frequency))
        else:
            return None
    if not periods:
        return None
    longest = max(periods)
    for k in range(1, MAX_PERIODS + 1):
        p = k * longest
        if all(abs(p / q - round(p / q)) < 1e-9 * (p / q) for q in periods):
            return p
    return None


def _waveforms(circuit):
    """The waveforms of ``circuit``'s sources that are not constant by definition."""
    from ...physics.waveforms import Constant, Waveform

    return [v for spec in circuit.elements.values() for v in spec.params.values()
            if isinstance(v, Waveform) and not isinstance(v, Constant)]


def varying_waveforms(circuit, t0: float, t1: float) -> list:
    """The waveforms of ``circuit``'s sources that change within [t0, t1] (s)."""
    grid = np.linspace(t0, t1, 400)
    out = []
    for v in _waveforms(circuit):
        ts = np.unique(np.concatenate([grid, np.asarray(v.breakpoints(t0, t1), float)]))
        ts = ts[(ts >= t0) & (ts <= t1)]
        if np.ptp([float(v.value(x)) for x in ts]) > 0:
            out.append(v)
    return out


def source_changes(circuit) -> tuple[float, float] | None:
    """(first, last) netlist times (s) at which those of ``circuit``'s sources that change
    a finite number of times (a STEP, a PULSE without a period, a PWL) change; periodic
    sources beside them (a PULSE with a period, an undamped SIN) are left out: the one-off
    change alone fixes the netlist time (a supply switched on while the valves pulse).
    None when none changes a finite number of times, or a source is not known in closed
    form (a Python function, a damped SIN)."""
    corners = []
    for v in _waveforms(circuit):
        if common_period([v]) is not None:
            continue
        if not _one_shot(v):
            return None
        corners.extend(_changing_corners(v))
    return (float(min(corners)), float(max(corners))) if corners else None


def _one_shot(wave) -> bool:
    """Whether ``wave`` changes a finite number of times, known in closed form (a STEP, a
    PWL, a PULSE without a period)."""
    from ...physics.waveforms import PiecewiseLinear, Pulse, Step

    return isinstance(wave, (Step, PiecewiseLinear)) or \
        (isinstance(wave, Pulse) and not wave.period > 0)


def repeating_drive(circuit, origin: float, span: float) -> float:
    """The common period (s) of ``circuit``'s sources where they only repeat within the
    file's window [``origin``, ``origin`` + ``span``] (s): every source that varies there
    periodic, none changing once; 0 otherwise (a step, a PWL, a Python function)."""
    waves = varying_waveforms(circuit, origin, origin + span)
    if not waves or source_changes(circuit) is not None:
        return 0.0
    return common_period(waves) or 0.0


def unplaced_sources(circuit, origin: float, span: float) -> list[str]:
    """Names of ``circuit``'s sources that vary within the file's window [``origin``,
    ``origin`` + ``span``] (s) but that a record cannot place on the netlist's clock:
    neither periodic nor changing a finite number of times in closed form (a Python
    function, a damped SIN, a sampled waveform).  With one, the file's clock is taken
    as the netlist's, and a logger started elsewhere misplaces them unnoticed."""
    varying = {id(w) for w in varying_waveforms(circuit, origin, origin + span)}
    return [name for name, spec in circuit.elements.items()
            if any(id(v) in varying and common_period([v]) is None and not _one_shot(v)
                   for v in spec.params.values())]


def _changing_corners(wave) -> list[float]:
    """The corners (s) of a waveform that changes a finite number of times at which its
    value changes on one side (not a PWL's first point, held from before)."""
    ts = np.unique(np.asarray(wave.breakpoints(-math.inf, math.inf), float))
    gaps = np.diff(ts)
    out = []
    for i, t in enumerate(ts):
        near = [g for g in (gaps[i - 1] if i else None, gaps[i] if i < gaps.size else None)
                if g is not None]
        d = 0.5 * min(near + [1.0])
        here = float(wave.value(t))
        if float(wave.value(t - d)) != here or float(wave.value(t + d)) != here:
            out.append(float(t))
    return out


def _periodic_sources_period(circuit) -> float:
    """The common period (s) of ``circuit``'s periodic sources, 0 when there are none
    (or they have none)."""
    waves = [v for v in _waveforms(circuit) if common_period([v]) is not None]
    return (common_period(waves) or 0.0) if waves else 0.0


def clock_from_record(circuit, origin: float, span: float) -> bool:
    """Whether the netlist time of a record's first sample is read from the record
    (:func:`source_clock`) for ``circuit``: its sources vary within the file's window
    [``origin``, ``origin`` + ``span``] (s), or change once at all (a logger's own clock
    may place the record anywhere; periodic corners are not listed from switch-on: a
    Unix time would be 10⁸ periods)."""
    return bool(varying_waveforms(circuit, origin, origin + span)) \
        or source_changes(circuit) is not None


def source_clock(circuit, data, origin: float,
                 slack: float = CLOCK_SLACK) -> tuple[float, str, float]:
    """(netlist time of the first sample, s; a note, '' when the file's clock is kept;
    the range of the clock, s: the sources' common period, for sources that change once
    twice the starts scanned, 0 when neither) for a recording ``data`` (time_s from 0,
    p_<node>_kPa columns; the file's first time stamp ``origin``) of ``circuit`` (at the
    parameter guesses) driven by its sources; the file's clock is kept within ``slack``
    × the best start's rms misfit."""
    times = data["time_s"].to_numpy(float)
    span = float(times[-1]) if len(times) else 0.0
    waves = varying_waveforms(circuit, origin, origin + span)
    changes = source_changes(circuit)  # a one-off change fixes the netlist time
    period = repeating_drive(circuit, origin, span) or None
    if (period is None and changes is None) or len(times) < 10:
        return origin, "", 0.0
    dt = float(np.median(np.diff(times)))
    if changes is not None:
        return _one_shot_clock(circuit, data, origin, slack, changes, dt,
                               _periodic_sources_period(circuit))
    delay = max(float(getattr(w, "delay", 0.0)) for w in waves)
    window = times <= min(span, period)
    # output finer than the samples: the phase is refined between them
    scan = _Scan(circuit, data, window, delay + 2 * period + times[window][-1] + dt, dt)
    if not scan.signals:
        return origin, "", period
    settled = delay + period  # netlist time of phase 0 one period into the cycle
    # a settled cycle at any phase, or the run from switch-on within one period of it
    # (a logger started just before the supply: no settled history)
    phase, least = scan.best_start(settled, period)
    phase = (phase - settled) % period
    early, least_early = scan.best_start(0.0, period)
    from_rest = least_early < least
    least = min(least, least_early)
    # the file's clock: kept at the start found, else compared on the run from rest
    # where it covers it, else at its phase of the settled cycle
    apart = abs(phase - (origin - delay) % period)
    if (abs(early - origin) if from_rest else min(apart, period - apart)) <= dt:
        return origin, "", period
    direct = origin + scan.t_w[-1] <= scan.t_end
    at_origin = origin if direct else settled + (origin - delay) % period
    at_file = float(scan.misfit([at_origin])[0])
    if at_file <= slack ** 2 * least:
        return origin, "", period
    ratio = math.sqrt(at_file / least)
    found = (f"{early:.4g} s after switch-on, within a period of it" if from_rest
             else "on their settled cycle")
    note = (f"the file's clock puts the sources' switching {ratio:.3g}× further from the "
            f"record than the best start: the first sample's netlist time is estimated from "
            f"the record, {found} (the sources repeat every {period:g} s; give a time offset "
            f"to set it)")
    if from_rest:
        return early, note, period
    return delay + phase + period * max(1, math.ceil(span / period)), note, period


def _one_shot_clock(circuit, data, origin, slack, changes, dt, repeat=0.0):
    """:func:`source_clock` for sources that change once between netlist times
    ``changes`` (first, last; s), beside periodic ones of common period ``repeat`` (s; 0:
    none): one run from rest gives the response at every start from a record's length
    before the first change (the logger started early: samples before switch-on are at
    rest) to one after the last, or a period of the periodic sources if longer (the
    record holds only what follows: its phase); the whole record is compared at each."""
    first, last = changes
    times = data["time_s"].to_numpy(float)
    span = float(times[-1])
    after = max(span, repeat)
    scan = _Scan(circuit, data, np.ones(len(times), bool), last + after + span + dt, dt)
    low, width = first - span, last - first + span + after
    if not scan.signals:
        return origin, "", 0.0
    best, least = scan.best_start(low, width, lowest=-math.inf)
    at_file = float(scan.misfit([origin])[0])
    if abs(best - origin) <= dt or at_file <= slack ** 2 * least:
        return origin, "", 0.0
    ratio = math.sqrt(at_file / least)
    found = f"{best:.4g} s" + (", after the sources' last change" if best > last else "")
    note = (f"the file's clock puts the sources' changes {ratio:.3g}× further from the "
            f"record than the best start: the first sample's netlist time is estimated from "
            f"the record, {found} (the sources change between {first:g} and {last:g} s; "
            f"give a time offset to set it)")
    return best, note, 2 * width


class _Scan:
    """The recorded ``window`` of ``data`` against ``circuit``'s run from rest to
    ``t_end`` (s, output a :data:`FINER`-th of the sample spacing ``dt``), each signal in
    units of its own noise."""

    def __init__(self, circuit, data, window, t_end, dt):
        from .data import signal_of_column

        self.dt = dt
        self.t_w = data["time_s"].to_numpy(float)[window]
        self.sol = circuit.tran(t_end, t_step=dt / FINER)
        self.t_end = float(self.sol.t[-1])
        self.signals = []
        for c in (c for c in data.columns if c != "time_s"):
            s = signal_of_column(c)
            if s not in self.sol.signals:
                continue
            y = data[c].to_numpy(float)[window]
            ok = np.isfinite(y)
            ok[np.arange(len(ok)) % max(1, len(ok) // SCAN_POINTS) != 0] = False
            scale = record_sigma(data[c].to_numpy(float))
            scale = scale if math.isfinite(scale) and scale > 0 else max(float(np.ptp(y[ok])), 1.0)
            self.signals.append((np.asarray(self.sol[s], float), y[ok], self.t_w[ok], scale))

    def misfit(self, starts):
        """Σ over signals of ((simulated − recorded)/noise)² for each netlist start time
        (before the run's start: its first value, the rest state)."""
        from .model import sample_at

        total = np.zeros(len(starts))
        for model, y, t, scale in self.signals:
            at = np.asarray(starts, float)[:, None] + t[None, :]
            sim = sample_at(self.sol.t, model, at.ravel()).reshape(at.shape)
            total += np.sum(((sim - y) / scale) ** 2, axis=1)
        return total

    def best_start(self, first, width, lowest=0.0):
        """(netlist start time, its misfit): every start in [first, first + width) on a
        grid of at most SCAN_POINTS, then zoomed in tenfold around the best until the
        grid is a FINER-th of a sample (none before ``lowest``, s)."""
        dt = self.dt
        step = max(dt, width / SCAN_POINTS)
        starts = first + np.arange(0.0, width, step)
        while True:
            cost = self.misfit(starts)
            best, least = float(starts[int(np.argmin(cost))]), float(np.min(cost))
            if step <= dt / FINER * (1 + 1e-9):
                return best, least
            reach, step = step, max(step / 10, dt / FINER)
            starts = best + step * np.arange(-math.ceil(reach / step),
                                             math.ceil(reach / step) + 1)
            starts = starts[starts >= lowest]


#: the name under which a clock estimated from the record is fitted with the parameters
CLOCK = "t0@clock"
#: a start's clock moved from its fit's by this many sample spacings (a screen point's)
SHIFT = "shift@clock"


def clock_unit(state, times) -> float:
    """s per unit of the clock's fitted shift (the sample spacing) when ``state``'s
    clock was estimated from the record, else 0: the phase a grid found at the
    parameter guesses is off by as much as the guesses move the sources' response (a
    pull-up 15 % off: most of a sample, where a 400 kPa edge within one sample turns
    that into a misfit of tens of kPa), so it is fitted with the parameters."""
    if not state.clock or not state.clock_period or not state.driven or len(times) < 2:
        return 0.0
    return float(np.median(np.diff(times)))


#: most sample spacings a start of the clock's fit is moved from the phase found
CLOCK_STARTS = 3
#: a fit from the phase found whose rms is within this factor of the record's own noise
#: needs no other start
CLOCK_AT_NOISE = 2.0


def _cost(res) -> float:
    """Sum of squares of a least-squares result's residual."""
    return float(res.fun @ res.fun)


def _clock_starts(res, fun, x0, lb, ub, **lsq):
    """``res`` (the fit from the clock's phase found at the guesses) when it is at the
    record's noise, else the best of it and fits from that clock moved by one sample
    spacing either way, then further in the better direction while that improves (at
    most :data:`CLOCK_STARTS`): the cost is a narrow valley in the clock and the
    parameters together, and from the phase found at the guesses LM may not find it (the
    inverter chain's own-clock recording: 18 kPa rms from the phase found, 0.30 from one
    sample earlier)."""
    noise = [record_sigma(fun.measured[s], segments(fun.keep[s])) / fun.scales[s]
             for s in fun.signals]
    noise = math.sqrt(np.nanmean(np.square(noise))) if np.isfinite(noise).any() else math.nan
    if math.sqrt(_cost(res) / max(len(res.fun), 1)) <= CLOCK_AT_NOISE * noise:
        return res

    def moved(k):
        x = x0.copy()
        x[-1] = float(np.clip(x0[-1] + k, lb[-1], ub[-1]))
        return least_squares_log(fun, x, lb, ub, **lsq)

    used = res.nfev
    tried = {0: res}
    for k in (-1, 1):
        tried[k] = moved(k)
        used += tried[k].nfev
    step = -1 if _cost(tried[-1]) <= _cost(tried[1]) else 1
    k = step
    while abs(k) < CLOCK_STARTS and _cost(tried[k]) < _cost(tried[k - step]):
        k += step
        tried[k] = moved(k)
        used += tried[k].nfev
    best = min(tried.values(), key=_cost)
    return replace(best, nfev=used)


def fit_clock(res, fun, x0, lb, ub, model, df, state, starts: bool, **lsq):
    """``res`` (a fit with the clock, from ``x0``) or a better one: with ``starts`` (a
    first fit, its phase found at the guesses) from other starts of the clock
    (:func:`_clock_starts`); then from the phase the record shows for the circuit at the
    fitted values, effects included, when that is more than a sample away (a control-line
    tube delays one valve: at the base model's values the phase found absorbs that delay,
    21 samples of the driven amplifier's, too far for LM to undo).  The simulations of
    every fit tried are counted."""
    if starts:
        res = _clock_starts(res, fun, x0, lb, ub, **lsq)
    values = dict(zip(fun.names, np.exp(res.x[:-1])))
    moved = _clock_refound(model.with_state(state), values, df, state, fun.clock_step)
    if moved is None:
        return res
    x1 = res.x.copy()
    x1[-1] = float(np.clip(moved, lb[-1], ub[-1]))
    again = _clock_starts(least_squares_log(fun, x1, lb, ub, **lsq), fun, x1, lb, ub, **lsq)
    best = again if _cost(again) < _cost(res) else res
    return replace(best, nfev=res.nfev + again.nfev)


def _clock_refound(model, values, df, state, step) -> float | None:
    """The clock's shift (sample spacings of ``step`` s from ``state``'s) at the phase the
    record shows for ``model`` at ``values`` (:func:`~pneunet.truth.circuits.clock.
    source_clock`), None when within a sample of ``state``'s or not found."""
    try:
        offset, note, period = source_clock(model.circuit(values), df,
                                            float(df.attrs.get("time_origin", 0.0)))
    except PneunetError:
        return None
    if not note or not period:
        return None
    apart = (offset - state.first_time + 0.5 * period) % period - 0.5 * period
    return apart / step if abs(apart) > step else None


#: sample spacings a fitted clock is moved for a fit's other starts where it stopped
#: above the floor (:func:`~pneunet.truth.circuits.candidate_fits.clock_restarts`)
CLOCK_NUDGES = (-0.5, 0.5)


def clock_moved(state, shift, step):
    """``state`` with its clock moved by ``shift`` sample spacings of ``step`` s (the
    interval of a fitted clock dropped: it belongs to the clock before)."""
    return replace(state, time_offset=state.time_offset + float(shift) * step, clock_ci=())


def clock_fitted(state, shift, ci, step):
    """``state`` with the fitted clock: moved by ``shift`` sample spacings of ``step`` s,
    the first sample's netlist time and its interval (``ci``: the interval of exp(shift))."""
    moved = clock_moved(state, shift, step)
    lo, hi = (moved.first_time + (math.log(c) - float(shift)) * step if c > 0 else -math.inf
              for c in ci)
    return replace(moved, clock_ci=(lo, hi))
