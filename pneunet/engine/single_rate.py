"""Single-rate integration of a whole circuit with IDA: consistent states, segments
between source breakpoints, restarts after source jumps, folds crossed by jumps.

:func:`integrate` is the loop behind :func:`pneunet.engine.simulate.transient` (and the
hub of :mod:`~pneunet.engine.hub_first`): it returns the rows it recorded, every
internal step or the output grid, with the rates ẏ when asked.
"""
from __future__ import annotations

import numpy as np

from ..common.errors import SolverError
from ..physics.waveforms import SampleTable
from .solution import build_solution
from .solvers import available_backends
from .solvers.base import EVENT, FAILED, Segment
from .solvers.newton import DENSE_LIMIT, newton

VACUUM_KPA = 0.1  # absolute pressure below which a circuit has left its physical range
STEP_STORE_LIMIT = 512  # unknowns up to which internal steps are stored and interpolated


def residual_and_jacobian(dae, t):
    """F(t, y, ẏ = 0) and, when asked, ∂F/∂y (dense for small circuits) for :func:`newton`."""
    zeros = np.zeros(dae.n)

    def fn(y, jacobian):
        if not jacobian:
            return dae.evaluate(t, y, zeros)[0], None
        res, data = dae.evaluate(t, y, zeros, cj=0.0)
        return res, dae.dense(data) if dae.n <= DENSE_LIMIT else dae.csc(data)
    return fn


def pseudo_capacitance(dae, t, y):
    """Capacitances for continuation: real ones, and 1 mL of gas where there is none."""
    cap = dae.capacitance(t, y)
    small = dae.options.gas_model.capacitance(1.0, dae.options.temperature)
    return np.where(cap > 0, cap, small)


def consistent_state(dae, t, y_guess):
    """Solve the algebraic nodes for given differential ones; return (y, ẏ)."""
    result = newton(residual_and_jacobian(dae, t), y_guess, dae.algebraic_idx,
                    capacitance=pseudo_capacitance(dae, t, y_guess))
    if not result.converged:
        worst = dae.node_names[dae.algebraic_idx[np.argmax(np.abs(
            dae.evaluate(t, result.y, np.zeros(dae.n))[0][dae.algebraic_idx]))]]
        raise SolverError(f"no consistent initial state at t = {t:g} s "
                          f"(flow imbalance {result.residual:.3g} mg/s at node {worst})",
                          time=t, where=f"node {worst}",
                          hint="give the node an initial pressure with .ic, or add a dead volume")
    return result.y, dae.derivative(t, result.y)


def integrate(dae, t_start, t_stop, y, yp, outputs=None, backend=None, progress=False,
              rates=False):
    """Integrate ``dae`` from the consistent state (y, ẏ) at t_start to t_stop with IDA:
    segment by segment between source breakpoints, restarted after source jumps, folds
    crossed by jumps.  Returns the :class:`_Record` of the rows (every internal step, or
    the ``outputs`` times; with ``rates`` also ẏ at each row), the number of IDA steps
    and the integrator (for its counters)."""
    opts = dae.options
    backends = available_backends()
    name = backend or "sksundae"
    if name not in backends:
        raise SolverError(f"IDA backend {name!r} is not installed",
                          hint="available: " + (", ".join(backends) or "none") +
                               "; pip install pneunet[odes] for scikits.odes")
    folds = None
    if dae.algebraic_idx.size:
        from .solvers.folds import FoldMonitor

        folds = FoldMonitor(dae, opts.fold_threshold)
        folds.restart(t_start, y)
    watch = _Watch(folds, 1e-7 * (t_stop - t_start))
    integrator = backends[name](dae, rtol=opts.rtol, atol=opts.atol, max_step=opts.max_step,
                                events=watch)

    jumps = set(np.round(dae.jumps(t_start, t_stop), 12))
    stops = np.unique(np.concatenate([dae.breakpoints(t_start, t_stop), [t_stop]]))
    record = _Record(t_start, y, yp, outputs,
                     store_steps=outputs is None or dae.n <= STEP_STORE_LIMIT, rates=rates)
    t = t_start
    bar = _progress(progress, t_start, t_stop)
    retried_at = None
    steps = 0
    restart = True  # from (t, y, yp); False: IDA continues across a corner of a slope
    try:
        while t < t_stop:
            next_stop = stops[np.searchsorted(stops, t, side="right")]
            seg = integrator.segment(t, y, yp, next_stop, record.grid_in(t, next_stop),
                                     restart=restart,
                                     final=next_stop >= t_stop or round(next_stop, 12) in jumps)
            steps += seg.t.size
            restart = False
            status = seg.status
            alarm = watch.alarm(seg.t[-1], seg.y[-1]) if status == EVENT else ""
            if alarm:
                seg.status, seg.message = FAILED, alarm
                record.add(t, y, yp, seg, keep_end=False)
                raise _failure(dae, seg, t, y, record, integrator)
            if status == FAILED and folds is not None:
                last_t, last_y = (seg.t[-1], seg.y[-1]) if seg.t.size else (t, y)
                record.add(t, y, yp, seg, keep_end=False)
                if retried_at != last_t:
                    # a large step ran past a fold: restart with small steps so that
                    # the fold indicator can stop the integration in time
                    retried_at = last_t
                    try:
                        y, yp = consistent_state(dae, last_t, last_y)
                    except SolverError:
                        status = EVENT  # the branch has already ended here: jump
                    else:
                        t, restart = last_t, True
                        folds.restart(t, y)
                        continue
                elif folds.near_fold(last_t, last_y):
                    status = EVENT
                if status == EVENT:
                    seg = Segment(EVENT, np.array([last_t]), last_y[None, :],
                                  dae.derivative(last_t, last_y)[None, :], seg.message)
            if status == FAILED:
                record.add(t, y, yp, seg, keep_end=False)
                raise _failure(dae, seg, t, y, record, integrator)
            previous = record.last() if seg.t.size < 2 else (seg.t[-2], seg.y[-2])
            record.add(t, y, yp, seg, keep_end=True)
            t, y, yp = seg.t[-1], seg.y[-1], seg.yp[-1]
            if status == EVENT:
                t_fold, y_fold, yp_fold = t, y, yp
                t, y, jumped = folds.jump(t, y, yp, previous=previous)
                yp = dae.derivative(t, y)
                if jumped:
                    record.jump(t, y, yp)
                    folds.restart(t, y)
                elif t > t_fold:  # a near-fold: on along the branch from where κ is least
                    record.add(t_fold, y_fold, yp_fold,
                               Segment(EVENT, np.array([t]), y[None, :], yp[None, :], ""),
                               keep_end=True)
                restart = True
            elif round(t, 12) in jumps and t < t_stop:
                y, yp = consistent_state(dae, t, y)
                record.point(t, y, yp)
                restart = True
                if folds is not None:
                    folds.restart(t, y)
            if bar is not None:
                bar.update(t - bar.n)
    finally:
        if bar is not None:
            bar.close()
    return record, steps, integrator


class _Record:
    """The rows a transient returns: output-grid points (or every internal step),
    source stops, and the states on both sides of each branch jump; with ``rates``
    (every internal step only) also the rates ẏ at each row."""

    def __init__(self, t0, y0, yp0, outputs, store_steps, rates=False):
        self.outputs = outputs
        self.store_steps = store_steps
        self.chunks_t, self.chunks_y = [np.array([t0])], [y0[None, :].copy()]
        self.chunks_yp = [yp0[None, :].copy()] if rates else None
        self.emitted = t0  # outputs up to here are recorded
        self.jumps = []

    def grid_in(self, t0, t1):
        """Output times IDA must interpolate onto in (t0, t1), or None (store steps)."""
        if self.store_steps:
            return None
        return self.outputs[(self.outputs > t0) & (self.outputs < t1)]

    def add(self, t0, y0, yp0, seg, keep_end):
        """Rows of a segment started at (t0, y0, yp0); ``keep_end`` records its last row."""
        if not seg.t.size:
            return
        if self.outputs is None or not self.store_steps:
            self.chunks_t.append(seg.t)  # every row is an output or an internal step
            self.chunks_y.append(seg.y)
            if self.chunks_yp is not None:
                self.chunks_yp.append(seg.yp)
        else:
            t_end = seg.t[-1]
            want = self.outputs[(self.outputs > self.emitted) & (self.outputs < t_end)]
            if want.size:
                ts = np.concatenate([[t0], seg.t])
                self.chunks_t.append(want)
                self.chunks_y.append(SampleTable(ts, np.vstack([y0, seg.y]),
                                                 np.vstack([yp0, seg.yp])).value(want))
                self.emitted = want[-1]
            if keep_end:
                self.point(t_end, seg.y[-1], seg.yp[-1])
        if keep_end:
            self.emitted = max(self.emitted, seg.t[-1])

    def point(self, t, y, yp):
        self.chunks_t.append(np.array([t]))
        self.chunks_y.append(np.array(y, dtype=float)[None, :])
        if self.chunks_yp is not None:
            self.chunks_yp.append(np.array(yp, dtype=float)[None, :])

    def jump(self, t, y, yp):
        self.jumps.append(t)
        self.point(t, y, yp)
        self.emitted = max(self.emitted, t)

    def last(self):
        return self.chunks_t[-1][-1], self.chunks_y[-1][-1]

    def arrays(self):
        return np.concatenate(self.chunks_t), np.concatenate(self.chunks_y)

    def rates(self):
        """ẏ at every row of :meth:`arrays` (kPa/s); the record must keep rates."""
        return np.concatenate(self.chunks_yp)


class _Watch:
    """The integrator's event function: it crosses zero downwards at a fold (see
    :class:`~pneunet.engine.solvers.folds.FoldMonitor`), where a pressure falls to
    VACUUM_KPA, or once 1000 steps in a row were shorter than ``tiny`` s — a
    stalled integration — so that IDA's step loop always returns."""

    def __init__(self, folds, tiny):
        self.folds, self.tiny = folds, tiny
        self.last_t, self.tiny_steps = -np.inf, 0

    def __call__(self, t, y):
        if t > self.last_t:  # a new step (root finding probes earlier times)
            self.tiny_steps = self.tiny_steps + 1 if t - self.last_t < self.tiny else 0
            self.last_t = t
        g = min(float(y.min()) - VACUUM_KPA, 1.0 if self.tiny_steps < 1000 else -1.0)
        return g if self.folds is None else min(g, self.folds.event(t, y))

    def alarm(self, t, y) -> str:
        """Why the integration must stop at this root ('' for a fold)."""
        if y.min() <= VACUUM_KPA * (1 + 1e-3):
            return f"a pressure fell below {VACUUM_KPA} kPa abs (vacuum)"
        if self.tiny_steps >= 1000:
            return f"the time step collapsed (1000 steps below {self.tiny:.1e} s)"
        return ""


def _progress(enabled, t0, t1):
    if not enabled:
        return None
    from ..common.progress import progress_bar

    return progress_bar(total=t1 - t0, unit="s", desc="transient",
                        bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]")


def _failure(dae, seg, t, y, record, integrator):
    """The SolverError of a failed segment, with the solution up to its last good row."""
    t_fail, y_fail = (seg.t[-1], seg.y[-1]) if seg.t.size else (t, y)
    res = dae.evaluate(t_fail, y_fail, np.zeros(dae.n))[0]
    rate = np.abs(seg.yp[-1]) / np.maximum(np.abs(y_fail), 1.0) if seg.t.size else 0.0
    worst = dae.node_names[int(np.argmax(rate + np.abs(res) + (y_fail < VACUUM_KPA) * 1e300))] \
        if dae.n else "?"
    times, states = record.arrays()
    partial = build_solution(dae, times, states, dict(integrator.counters(), failed=True),
                              tuple(record.jumps))
    return SolverError(
        f"IDA stopped at t = {t_fail:.6g} s: {seg.message}", time=t_fail,
        where=f"node {worst}", partial=partial,
        hint="the pressure at this node changes fastest; try a tighter rtol, a larger "
             "flow_band (.options flow_band=50), or a small dead volume (.options dead_volume=0.05mL)")
