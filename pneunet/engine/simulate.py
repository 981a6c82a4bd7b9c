"""Analyses: operating point and transient.

``transient`` integrates the circuit's DAE with SUNDIALS IDA from a consistent
initial state, stepping onto every source breakpoint, restarting after source
jumps, and crossing folds of relaxation oscillations by explicit jumps (see
:mod:`pneunet.engine.solvers.folds`) unless dead volumes make every node differential.
"""
from __future__ import annotations

import time as _time

import numpy as np

from .assembly import CircuitDAE
from .diagnostics import captured
from ..errors import ParameterError, SolverError
from .solution import OperatingPoint, Solution, build_solution
from .stability import linear_stability
from .solvers import available_backends
from .solvers.base import EVENT, FAILED, Segment
from .solvers.newton import DENSE_LIMIT, newton

VACUUM_KPA = 0.1  # absolute pressure below which a circuit has left its physical range


def _residual_jac(dae, t):
    """F(t, y, ẏ = 0) and, when asked, ∂F/∂y (dense for small circuits) for :func:`newton`."""
    zeros = np.zeros(dae.n)

    def fn(y, jacobian):
        if not jacobian:
            return dae.evaluate(t, y, zeros)[0], None
        res, data = dae.evaluate(t, y, zeros, cj=0.0)
        return res, dae.dense(data) if dae.n <= DENSE_LIMIT else dae.csc(data)
    return fn


def _pseudo_capacitance(dae, t, y):
    """Capacitances for continuation: real ones, and 1 mL of gas where there is none."""
    cap = dae.capacitance(t, y)
    small = dae.options.gas_model.capacitance(1.0, dae.options.temperature)
    return np.where(cap > 0, cap, small)


def consistent_state(dae, t, y_guess):
    """Solve the algebraic nodes for given differential ones; return (y, ẏ)."""
    result = newton(_residual_jac(dae, t), y_guess, dae.algebraic_idx,
                    capacitance=_pseudo_capacitance(dae, t, y_guess))
    if not result.converged:
        worst = dae.node_names[dae.algebraic_idx[np.argmax(np.abs(
            dae.evaluate(t, result.y, np.zeros(dae.n))[0][dae.algebraic_idx]))]]
        raise SolverError(f"no consistent initial state at t = {t:g} s "
                          f"(flow imbalance {result.residual:.3g} mg/s at node {worst})",
                          time=t, where=f"node {worst}",
                          hint="give the node an initial pressure with .ic, or add a dead volume")
    return result.y, dae.derivative(t, result.y)


def _steady_state(dae, t):
    """Newton's steady state (ẏ = 0) of every unknown at time ``t``, or SolverError."""
    y0 = dae.initial_state(t)
    everything = np.arange(dae.n)
    result = newton(_residual_jac(dae, t), y0, everything,
                    capacitance=_pseudo_capacitance(dae, t, y0))
    if not result.converged:
        res = dae.evaluate(t, result.y, np.zeros(dae.n))[0]
        worst = dae.node_names[int(np.argmax(np.abs(res)))]
        raise SolverError(f"operating point not found (flow imbalance {result.residual:.3g} mg/s "
                          f"at node {worst})", time=t, where=f"node {worst}",
                          hint="the circuit may have no steady state it can settle in (an "
                               "oscillator, or a closed volume): run a transient instead, or "
                               "give .ic values close to the expected state")
    return result


def operating_point(circuit, *, t: float = 0.0, stability: bool = True) -> OperatingPoint:
    """Steady state (ẏ = 0) of the circuit with its sources at time ``t``, and (unless
    ``stability`` is False) whether it settles there (:mod:`~pneunet.engine.stability`)."""
    dae = CircuitDAE(circuit)
    result = _steady_state(dae, t)
    sol = build_solution(dae, np.array([t]), result.y[None, :], {}, ())
    pressures = {k[2:]: float(v[0]) for k, v in sol.signals.items() if sol.units[k] == "kPa"
                 and k.startswith("p_")}
    flows = {k[5:]: float(v[0]) for k, v in sol.signals.items() if k.startswith("mdot_")}
    return OperatingPoint(pressures, flows, result.residual,
                          linear_stability(dae, t, result.y) if stability else None)


@captured
def transient(circuit, t_stop: float, *, t_step: float | None = None, t_start: float = 0.0,
              start: str = "ic", backend: str | None = None, progress: bool = False,
              max_output_points: float | None = None) -> Solution:
    """Simulate from ``t_start`` to ``t_stop`` (s).

    t_step   output interval (s); None stores every internal step of IDA;
             at most ``max_output_points`` outputs (default :data:`MAX_OUTPUT_POINTS`)
    start    'ic': volumes start at their .ic / p0 / ambient pressure;
             'op': from the operating point at ``t_start``
    backend  'sksundae' (default) or 'odes' (scikits.odes, when installed)
    progress show a progress bar (tqdm) over simulated time

    The integrator runs segment by segment between source breakpoints and branch
    jumps (restarted only after a jump), storing its internal steps; outputs on the
    ``t_step`` grid are cubic Hermite interpolants of them
    (:mod:`pneunet.engine.solvers.interpolate`), so the grid does not set the step
    size.  Circuits above ``STEP_STORE_LIMIT`` unknowns let IDA interpolate onto
    the grid itself, so that memory follows the outputs.
    """
    if not t_stop > t_start:
        raise SolverError(f"t_stop ({t_stop} s) must be after t_start ({t_start} s)")
    if t_step is not None and not 0 < t_step <= t_stop - t_start:
        raise SolverError(f"t_step must lie in (0, {t_stop - t_start}] s, got {t_step}")
    limit = MAX_OUTPUT_POINTS if max_output_points is None else max_output_points
    if t_step is not None and (t_stop - t_start) / t_step > limit:
        raise ParameterError(f"t_step {t_step:g} s over {t_stop - t_start:g} s asks for "
                             f"{(t_stop - t_start) / t_step:.3g} output points (limit "
                             f"max_output_points = {limit:.0e})",
                             hint="a larger output step: the integrator's own steps do "
                                  "not depend on it; or a larger max_output_points")
    wall = _time.perf_counter()
    dae = CircuitDAE(circuit)
    opts = circuit.options
    if start == "op":
        y0 = _steady_state(dae, t_start).y  # element states too (no pressures)
    elif start == "ic":
        y0 = dae.initial_state(t_start)
    else:
        raise SolverError(f"start must be 'ic' or 'op', got {start!r}")
    y, yp = consistent_state(dae, t_start, y0)
    if dae.n == 0:  # every node held by a source: nothing to integrate
        return _sources_only(dae, t_start, t_stop, t_step, wall)
    part = _partition_for(circuit, dae, backend, (t_start, t_stop))
    if part is not None:
        from .multirate import transient as multirate

        algebraic = {dae.node_names[i] for i in dae.algebraic_idx}
        return multirate(circuit, part, t_stop, t_step, t_start, y, algebraic, _single_rate)

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
    outputs = (np.append(np.arange(t_start, t_stop, t_step)[1:], t_stop) if t_step else None)
    record = _Record(t_start, y, outputs, store_steps=outputs is None or dae.n <= STEP_STORE_LIMIT)
    t = t_start
    bar = _progress(progress, t_start, t_stop)
    retried_at = None
    steps = 0
    restart = True  # from (t, y, yp); False: IDA continues across a corner of a slope
    try:
        while t < t_stop:
            next_stop = stops[np.searchsorted(stops, t, side="right")]
            seg = integrator.segment(t, y, yp, next_stop, record.grid_in(t, next_stop),
                                     restart=restart)
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
                t, y = folds.jump(t, y, yp, previous=previous)
                record.jump(t, y)
                yp = dae.derivative(t, y)
                folds.restart(t, y)
                restart = True
            elif round(t, 12) in jumps and t < t_stop:
                y, yp = consistent_state(dae, t, y)
                record.point(t, y)
                restart = True
                if folds is not None:
                    folds.restart(t, y)
            if bar is not None:
                bar.update(t - bar.n)
    finally:
        if bar is not None:
            bar.close()
    times, states = record.arrays()
    stats = dict(integrator.counters(), backend=integrator.name, steps=steps,
                 output_points=len(times),
                 branch_jumps=len(record.jumps), unknowns=dae.n,
                 algebraic=int(dae.algebraic_idx.size), wall_time_s=_time.perf_counter() - wall)
    return build_solution(dae, times, states, stats, tuple(record.jumps))


#: ``method=auto`` integrates cells on their own steps from this many unknowns, when the
#: sources switch on at least AUTO_MULTIRATE_SCHEDULES different schedules (cells that
#: switch together are cheap for one global step)
AUTO_MULTIRATE_UNKNOWNS = 400
AUTO_MULTIRATE_SCHEDULES = 32


def _partition_for(circuit, dae, backend, span):
    """The circuit's hub and cells when the multirate method integrates it over ``span``
    (t_start, t_stop), else None."""
    method = circuit.options.method
    if method == "single" or method == "auto" and (
            backend is not None or dae.n < AUTO_MULTIRATE_UNKNOWNS
            or _schedules(dae, *span) < AUTO_MULTIRATE_SCHEDULES):
        return None
    from .partition import partition, unsupported, worth_partitioning

    part = partition(circuit)
    algebraic = {dae.node_names[i] for i in dae.algebraic_idx}
    if method == "auto":
        return None if worth_partitioning(part, algebraic) else part
    why = unsupported(part, algebraic)
    if why:
        raise ParameterError(f"method=multirate cannot split this circuit: {why}",
                             hint=".options method=single")
    return part


def transient_method(circuit, span=(0.0, 1.0)) -> str:
    """Which integration a transient of ``circuit`` over ``span`` (s) uses, in one line
    (``pneunet check``)."""
    dae = CircuitDAE(circuit)
    try:
        part = _partition_for(circuit, dae, None, span)
    except ParameterError as err:
        return f"multirate impossible: {err.message}"
    if part is None:
        return f"single-rate IDA ({dae.n} unknowns, method={circuit.options.method})"
    hub = ", ".join(part.hub_nodes[:3]) + (" …" if len(part.hub_nodes) > 3 else "")
    return (f"multirate: {len(part.cells)} cells in {len(part.groups)} group(s)"
            + (f", hub nodes {hub}" if part.hub_nodes else ", no hub (independent cells)"))


def _schedules(dae, t_start, t_stop) -> float:
    """How many different switching schedules the inputs follow: their distinct corners
    in (t_start, t_stop) over the mean number of one element's corners (0: none)."""
    own = [len(c[0]) for c in dae.instance_corners(t_start, t_stop).values()]
    mean = np.mean(own) if own else 0.0
    return dae.breakpoints(t_start, t_stop).size / mean if mean > 0 else 0.0


def _single_rate(circuit, t_stop, t_step, t_start):
    """One independent cell (a circuit of its own) on the single-rate integrator."""
    circuit.options = circuit.options.replace(method="single")
    return transient(circuit, t_stop, t_step=t_step, t_start=t_start)


#: output points a transient may ask for (8 bytes per point and unknown)
MAX_OUTPUT_POINTS = 10_000_000
STEP_STORE_LIMIT = 512  # unknowns up to which internal steps are stored and interpolated


def _sources_only(dae, t_start, t_stop, t_step, wall) -> Solution:
    """The solution of a circuit without unknowns: the sources' pressures and the flows
    they drive, on the output grid (or at the sources' corners), no integrator."""
    corners = np.concatenate([[t_start, t_stop], dae.breakpoints(t_start, t_stop),
                              dae.jumps(t_start, t_stop)])
    times = (np.append(np.arange(t_start, t_stop, t_step), t_stop) if t_step
             else np.unique(corners))
    stats = dict(backend="none (no unknowns)", steps=0, output_points=len(times),
                 branch_jumps=0, unknowns=0, algebraic=0,
                 wall_time_s=_time.perf_counter() - wall)
    return build_solution(dae, times, np.empty((len(times), 0)), stats, ())


class _Record:
    """The rows a transient returns: output-grid points (or every internal step),
    source stops, and the states on both sides of each branch jump."""

    def __init__(self, t0, y0, outputs, store_steps):
        self.outputs = outputs
        self.store_steps = store_steps
        self.chunks_t, self.chunks_y = [np.array([t0])], [y0[None, :].copy()]
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
        else:
            t_end = seg.t[-1]
            want = self.outputs[(self.outputs > self.emitted) & (self.outputs < t_end)]
            if want.size:
                from .solvers.interpolate import hermite

                ts = np.concatenate([[t0], seg.t])
                self.chunks_t.append(want)
                self.chunks_y.append(hermite(ts, np.vstack([y0, seg.y]),
                                             np.vstack([yp0, seg.yp]), want))
                self.emitted = want[-1]
            if keep_end:
                self.point(t_end, seg.y[-1])
        if keep_end:
            self.emitted = max(self.emitted, seg.t[-1])

    def point(self, t, y):
        self.chunks_t.append(np.array([t]))
        self.chunks_y.append(np.array(y, dtype=float)[None, :])

    def jump(self, t, y):
        self.jumps.append(t)
        self.point(t, y)
        self.emitted = max(self.emitted, t)

    def last(self):
        return self.chunks_t[-1][-1], self.chunks_y[-1][-1]

    def arrays(self):
        return np.concatenate(self.chunks_t), np.concatenate(self.chunks_y)


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
    from ..progress import progress_bar

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
