"""The netlist time of a driven recording's first sample, when the logger kept its own clock.

A circuit driven by its sources is simulated on the sources' clock: the first sample
sits at some netlist time, by default the file's first time stamp.  A logger started
by hand counts from its own zero (or writes the wall clock), and then the sources
switch at the wrong moments in the simulation: every fit misses by the whole swing.

For periodic sources (PULSE with a period, undamped SIN; several of them with a common
period P) one simulation from rest through two periods gives the circuit's response at
every phase.  The record's first period is compared with it at every phase on the
sample grid (each signal in units of its own noise); the file's clock is kept when it
gives the best phase or an rms misfit within :data:`CLOCK_SLACK` × the best phase's.
Else the best phase is used, placed ⌈span/P⌉ periods after the sources' delay (a settled
history of at least the record's length), and the start state says so.  The phase is
found at the parameter guesses; :func:`~pneunet.truth.circuits.fit.fit_trace` then fits
it with the parameters.
"""
from __future__ import annotations

import math

import numpy as np

#: the file's clock is kept unless its rms misfit is more than this factor of the best
#: phase's: the user's clock stands unless the record contradicts it (a missing effect,
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


def varying_waveforms(circuit, t0: float, t1: float) -> list:
    """The waveforms of ``circuit``'s sources that change within [t0, t1] (s)."""
    from ...physics.waveforms import Constant, Waveform

    grid = np.linspace(t0, t1, 400)
    out = []
    for spec in circuit.elements.values():
        for v in spec.params.values():
            if not isinstance(v, Waveform) or isinstance(v, Constant):
                continue
            ts = np.unique(np.concatenate([grid, np.asarray(v.breakpoints(t0, t1), float)]))
            ts = ts[(ts >= t0) & (ts <= t1)]
            if np.ptp([float(v.value(x)) for x in ts]) > 0:
                out.append(v)
    return out


def source_clock(circuit, data, origin: float) -> tuple[float, str, float]:
    """(netlist time of the first sample, s; a note, '' when the file's clock is kept;
    the sources' common period, s, 0 when none) for a recording ``data`` (time_s from 0, p_<node>_kPa columns; the file's first time
    stamp ``origin``) of ``circuit`` (at the parameter guesses) driven by its sources."""
    from ..core.noise import record_sigma
    from .data import signal_of_column
    from .model import sample_at

    times = data["time_s"].to_numpy(float)
    span = float(times[-1]) if len(times) else 0.0
    waves = varying_waveforms(circuit, origin, origin + span)
    period = common_period(waves)
    if period is None or len(times) < 10:
        return origin, "", 0.0
    delay = max(float(getattr(w, "delay", 0.0)) for w in waves)
    dt = float(np.median(np.diff(times)))
    window = times <= min(span, period)
    t_w = times[window]
    cols = [c for c in data.columns if c != "time_s"]
    # output finer than the samples: the phase is refined between them
    sol = circuit.tran(delay + 2 * period + t_w[-1] + dt, t_step=dt / FINER)
    settled = delay + period  # netlist time of phase 0 one period into the cycle
    signals = []
    for c in cols:
        s = signal_of_column(c)
        if s not in sol.signals:
            continue
        y = data[c].to_numpy(float)[window]
        ok = np.isfinite(y)
        ok[np.arange(len(ok)) % max(1, len(ok) // SCAN_POINTS) != 0] = False
        scale = record_sigma(data[c].to_numpy(float))
        scale = scale if math.isfinite(scale) and scale > 0 else max(float(np.ptp(y[ok])), 1.0)
        signals.append((np.asarray(sol[s], float), y[ok], t_w[ok], scale))

    def misfit(starts):
        """Σ over signals of ((simulated − recorded)/noise)² for each netlist start time."""
        total = np.zeros(len(starts))
        for model, y, t, scale in signals:
            at = np.asarray(starts, float)[:, None] + t[None, :]
            sim = sample_at(sol.t, model, at.ravel()).reshape(at.shape)
            total += np.sum(((sim - y) / scale) ** 2, axis=1)
        return total

    if not signals:
        return origin, "", period
    # every phase on a grid of at most SCAN_POINTS, then zoomed in tenfold around the
    # best until the grid is a FINER-th of a sample
    step = max(dt, period / SCAN_POINTS)
    phases = np.arange(0.0, period, step)
    while True:
        cost = misfit(settled + phases)
        phase, least = float(phases[int(np.argmin(cost))]), float(np.min(cost))
        if step <= dt / FINER * (1 + 1e-9):
            break
        width, step = step, max(step / 10, dt / FINER)
        phases = phase + step * np.arange(-math.ceil(width / step), math.ceil(width / step) + 1)
    phase %= period
    # the file's clock: kept at the phase found (a record from switch-on is no settled
    # cycle), else compared on the run from rest where it covers it, else at its phase
    apart = abs(phase - (origin - delay) % period)
    if min(apart, period - apart) <= dt:
        return origin, "", period
    direct = origin + t_w[-1] <= float(sol.t[-1])
    at_origin = origin if direct else settled + (origin - delay) % period
    at_file = float(misfit([at_origin])[0])
    if at_file <= CLOCK_SLACK ** 2 * least:
        return origin, "", period
    offset = delay + phase + period * max(1, math.ceil(span / period))
    ratio = math.sqrt(at_file / least)
    note = (f"the file's clock puts the sources' switching {ratio:.3g}× further from the "
            f"record than the best phase: the first sample's netlist time is estimated from "
            f"the record (the sources repeat every {period:g} s; give a time offset to set "
            f"it)")
    return offset, note, period
