"""Steady cycles: the transient of an autonomous circuit, ended once its cycle repeats.

A circuit whose sources are all constant is autonomous: from the same state it does the
same thing.  When the state just after a branch jump (a valve switching) repeats the
state just after an earlier jump, to within :data:`CYCLE_TOL` times the integrator's own
tolerance (atol + rtol·|p|) in every unknown, what follows is that cycle again, shifted
by its period T — the periodic steady state.  :func:`steady_transient` integrates in
pieces (:data:`FIRST` of the span, then :data:`PIECE`), stops at the end of the piece
where the first repeat is seen, and fills the rest of [t_start, t_stop] with copies of
the last cycle's rows (the integrator's own rows, at their times + kT).  ``.meas``
statements then read the signal the whole transient would give, to within the
integrator's error.

Used for the samples of a design (:class:`~pneunet.design.metrics.SpecMeasure`): for the
oscillator of ``netlists/oscillator_design.pn`` the 12 s transient is simulated to
4.5–5 s.  A circuit with time-varying sources, or that the single-rate integrator does
not run (multirate cells), gets None; one whose cycle does not repeat within the first
:data:`GIVE_UP` of the span is simulated again by the plain transient, whose results
are then exactly those of ``circuit.tran``.
"""
from __future__ import annotations

import numpy as np

from ..common.solver_messages import captured

#: a repeat: every unknown within CYCLE_TOL·(atol + rtol·|p|) of the earlier jump's state
CYCLE_TOL = 10.0
#: the first piece integrated, and each next one, as fractions of the span (every piece
#: restarts IDA: ~3 ms and ~10 steps for the oscillator)
FIRST, PIECE = 1 / 3, 1 / 24
#: without a repeat by this fraction of the span (no jump in the first piece), the pieces
#: are dropped and the plain transient runs: its results are then exactly the plain ones
GIVE_UP = 0.5


def autonomous(circuit) -> bool:
    """Whether every waveform of ``circuit`` is a constant (nothing depends on time)."""
    from ..physics.waveforms import Constant, Waveform

    return not any(isinstance(v, Waveform) and not isinstance(v, Constant)
                   for spec in circuit.elements.values() for v in spec.params.values())


def steady_transient(circuit, t_stop: float, t_step: float | None = None,
                     t_start: float = 0.0, max_output_points: float | None = None):
    """A :class:`~pneunet.engine.solution.Solution` on [t_start, t_stop] as
    ``circuit.tran`` gives it, its periodic part after the first repeated cycle copied
    rather than integrated (module docstring); None when the circuit is not one this
    applies to (time-varying sources, multirate, too many unknowns or outputs): then run
    the transient itself.  ``stats['steady_cycle']``: the period (s) and the time
    simulated to (s); absent when the cycle did not repeat by :data:`GIVE_UP` of the
    span and the plain transient was run."""
    from ..engine.assembly import CircuitDAE
    from ..engine.partition import AUTO_MIN_CELLS
    from ..engine.simulate import MAX_OUTPUT_POINTS
    from ..engine.single_rate import STEP_STORE_LIMIT

    limit = MAX_OUTPUT_POINTS if max_output_points is None else max_output_points
    span = t_stop - t_start
    if not autonomous(circuit) or not span > 0 or (t_step is not None and (
            not 0 < t_step <= span or span / t_step > limit)):
        return None
    dae = CircuitDAE(circuit)
    method = circuit.options.method
    if not 0 < dae.n <= STEP_STORE_LIMIT or not (
            method == "single" or method == "auto" and dae.n < AUTO_MIN_CELLS) \
            or dae.breakpoints(t_start, t_stop).size:
        return None
    return _integrate(circuit, dae, t_start, t_stop, t_step, max_output_points)


@captured
def _integrate(circuit, dae, t_start, t_stop, t_step, max_output_points):
    import time

    from ..engine.single_rate import consistent_state, integrate
    from ..engine.solution import build_solution

    wall = time.perf_counter()
    y, yp = consistent_state(dae, t_start, dae.initial_state(t_start))
    grid = np.append(np.arange(t_start, t_stop, t_step)[1:], t_stop) if t_step else None
    ends = t_start + (t_stop - t_start) * np.arange(FIRST, GIVE_UP + PIECE / 2, PIECE)
    times, states, jumps, after = [], [], [], []  # after: the row just after each jump
    steps, t, counters = 0, t_start, {}
    for end in ends:
        outputs = None if grid is None else np.append(grid[(grid > t) & (grid < end)], end)
        record, n, integrator = integrate(dae, t, end, y, yp, outputs)
        steps += n
        counters = {k: counters.get(k, 0) + v for k, v in integrator.counters().items()
                    if isinstance(v, (int, float))}
        rows_t, rows_y = record.arrays()
        skip = 1 if times else 0  # a piece's first row is the previous piece's last
        offset = sum(map(len, times)) - skip
        times.append(rows_t[skip:])
        states.append(rows_y[skip:])
        for tj in record.jumps:
            jumps.append(tj)
            after.append(offset + int(np.flatnonzero(rows_t == tj)[-1]))
        t, y = rows_t[-1], rows_y[-1]
        yp = dae.derivative(t, y)
        cycle = _repeat(dae, np.concatenate(states), jumps, after)
        if cycle is not None:
            break
        if end >= ends[-1] or not jumps:
            return circuit.tran(t_stop, t_step=t_step, t_start=t_start,  # the plain one
                                max_output_points=max_output_points)
    i, j = cycle
    period = jumps[j] - jumps[i]
    times, states, jumps = _extend(np.concatenate(times), np.concatenate(states), jumps,
                                   after, i, j, t_stop)
    stats = dict(counters, steps=steps, unknowns=dae.n, algebraic=int(dae.algebraic_idx.size),
                 steady_cycle={"period_s": float(period), "simulated_to_s": float(t)},
                 output_points=len(times), branch_jumps=len(jumps),
                 wall_time_s=time.perf_counter() - wall)
    return build_solution(dae, times, states, stats, tuple(jumps))


def _repeat(dae, states, jumps, after):
    """(i, j): the latest jump j whose state repeats an earlier jump i's (the nearest i),
    or None."""
    opts = dae.options
    for j in range(len(jumps) - 1, 0, -1):
        yj = states[after[j]]
        for i in range(j - 1, -1, -1):
            yi = states[after[i]]
            if np.all(np.abs(yj - yi) <= CYCLE_TOL * (opts.atol + opts.rtol * np.abs(yi))):
                return i, j
    return None


def _extend(times, states, jumps, after, i, j, t_stop):
    """Rows up to jump j's, then the rows from jump i to jump j again, shifted by the
    period, until t_stop (its row interpolated in the cycle); the jumps likewise."""
    period = jumps[j] - jumps[i]
    first, last = after[i], after[j]  # the cycle: rows first .. last - 1
    cycle_t, cycle_y = times[first:last] - jumps[i], states[first:last]
    copies = int(np.ceil((t_stop - jumps[j]) / period)) + 1
    out_t, out_y = [times[:last]], [states[:last]]
    for k in range(copies):
        shifted = jumps[j] + k * period + cycle_t
        keep = shifted < t_stop
        out_t.append(shifted[keep])
        out_y.append(cycle_y[keep])
        if not keep.all():
            break
    tau = t_stop - jumps[j] - k * period  # where t_stop falls in the cycle
    a = min(max(int(np.searchsorted(cycle_t, tau, side="right")) - 1, 0), len(cycle_t) - 2)
    w = (tau - cycle_t[a]) / (cycle_t[a + 1] - cycle_t[a]) if cycle_t[a + 1] > cycle_t[a] else 0.0
    out_t.append(np.array([t_stop]))
    out_y.append((cycle_y[a] + w * (cycle_y[a + 1] - cycle_y[a]))[None, :])
    cycle_jumps = [tj - jumps[i] for tj in jumps[i:j]]
    extended = list(jumps[:j]) + [jumps[j] + m * period + c for m in range(k + 1)
                                  for c in cycle_jumps if jumps[j] + m * period + c < t_stop]
    return np.concatenate(out_t), np.concatenate(out_y), extended
