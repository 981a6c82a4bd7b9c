"""Analyses: operating point and transient.

``transient`` integrates the circuit's DAE with SUNDIALS IDA from a consistent
initial state, stepping onto every source breakpoint, restarting after source
jumps, and crossing folds of relaxation oscillations by explicit jumps (see
:mod:`pneunet.solvers.folds`) unless dead volumes make every node differential.
"""
from __future__ import annotations

import time as _time

import numpy as np

from .assembly import CircuitDAE
from .errors import SolverError
from .solution import LazySignals, OperatingPoint, Solution
from .solvers.base import EVENT, FAILED, StepResult, available_backends
from .solvers.newton import newton

VACUUM_KPA = 0.1  # absolute pressure below which a circuit has left its physical range


def _residual_jac(dae, t, ydot=None):
    zeros = np.zeros(dae.n) if ydot is None else ydot

    def fn(y):
        res, data = dae.evaluate(t, y, zeros, cj=0.0)
        return res, dae.csc(data)
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


def operating_point(circuit, *, t: float = 0.0) -> OperatingPoint:
    """Steady state (ẏ = 0) of the circuit with its sources at time ``t``."""
    dae = CircuitDAE(circuit)
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
    sol = _build_solution(dae, np.array([t]), result.y[None, :], {}, ())
    pressures = {k[2:]: float(v[0]) for k, v in sol.signals.items() if sol.units[k] == "kPa"
                 and k.startswith("p_")}
    flows = {k[5:]: float(v[0]) for k, v in sol.signals.items() if k.startswith("mdot_")}
    return OperatingPoint(pressures, flows, result.residual)


def transient(circuit, t_stop: float, *, t_step: float | None = None, t_start: float = 0.0,
              start: str = "ic", backend: str | None = None, progress: bool = False) -> Solution:
    """Simulate from ``t_start`` to ``t_stop`` (s).

    t_step   output interval (s); None stores every internal step of IDA
    start    'ic': volumes start at their .ic / p0 / ambient pressure;
             'op': from the operating point at ``t_start``
    backend  'sksundae' (default) or 'odes' (scikits.odes, when installed)
    progress show a progress bar (tqdm) over simulated time
    """
    if not t_stop > t_start:
        raise SolverError(f"t_stop ({t_stop} s) must be after t_start ({t_start} s)")
    if t_step is not None and not 0 < t_step <= t_stop - t_start:
        raise SolverError(f"t_step must lie in (0, {t_stop - t_start}] s, got {t_step}")
    wall = _time.perf_counter()
    dae = CircuitDAE(circuit)
    opts = circuit.options
    if start == "op":
        op = operating_point(circuit, t=t_start)
        y0 = np.array([op.pressures[n] for n in dae.node_names])
    elif start == "ic":
        y0 = dae.initial_state(t_start)
    else:
        raise SolverError(f"start must be 'ic' or 'op', got {start!r}")
    y, yp = consistent_state(dae, t_start, y0)

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
    integrator = backends[name](dae, rtol=opts.rtol, atol=opts.atol, max_step=opts.max_step,
                                events=folds.event if folds else None)
    integrator.init(t_start, y, yp)

    jumps = set(np.round(dae.jumps(t_start, t_stop), 12))
    stops = np.unique(np.concatenate([dae.breakpoints(t_start, t_stop), [t_stop]]))
    outputs = (np.append(np.arange(t_start, t_stop, t_step)[1:], t_stop) if t_step else None)
    times, states, branch_jumps = [t_start], [y.copy()], []
    t = t_start
    bar = _progress(progress, t_start, t_stop)
    out_i = 0
    retried_at = None
    tiny_steps = 0
    try:
        while t < t_stop:
            next_stop = stops[np.searchsorted(stops, t, side="right")]
            target = min(outputs[out_i], next_stop) if outputs is not None else next_stop
            step = integrator.step(target, next_stop, onestep=outputs is None)
            if step.status == FAILED and folds is not None and len(times) > 1:
                past_fold = False
                if retried_at != times[-1]:
                    # a large step ran past a fold: restart with small steps so that
                    # the fold indicator can stop the integration in time
                    retried_at = times[-1]
                    try:
                        states[-1], _ = consistent_state(dae, times[-1], states[-1])
                    except SolverError:
                        past_fold = True  # the branch has already ended here: jump
                    else:
                        _restart(integrator, None, dae, times[-1], states[-1])
                        continue
                if past_fold or folds.near_fold(times[-1], states[-1]):
                    step = StepResult(EVENT, times.pop(), states.pop(),
                                      dae.derivative(times[-1], states[-1]), step.message)
            if step.status == FAILED:
                raise _failure(dae, step, times, states, branch_jumps, integrator)
            tiny_steps = tiny_steps + 1 if step.t - t < 1e-7 * (t_stop - t_start) else 0
            stalled = tiny_steps > 1000 or (dae.n and step.y.min() < VACUUM_KPA)
            if stalled and step.status != FAILED:
                why = (f"a pressure fell below {VACUUM_KPA} kPa abs (vacuum)"
                       if dae.n and step.y.min() < VACUUM_KPA else
                       f"the time step collapsed (1000 steps below {1e-7 * (t_stop - t_start):.1e} s)")
                raise _failure(dae, StepResult(FAILED, step.t, step.y, step.yp, why),
                               times, states, branch_jumps, integrator)
            t, y = step.t, step.y
            times.append(t)
            states.append(y.copy())
            if step.status == EVENT:
                t, y = folds.jump(t, y, step.yp, previous=(times[-2], states[-2]))
                branch_jumps.append(t)
                times.append(t)
                states.append(y.copy())
                _restart(integrator, folds, dae, t, y)
            elif round(t, 12) in jumps and t < t_stop:
                y, _ = consistent_state(dae, t, y)
                times.append(t)
                states.append(y.copy())
                _restart(integrator, folds, dae, t, y)
            if outputs is not None:  # after a jump t may have passed further outputs
                while out_i < len(outputs) - 1 and outputs[out_i] <= t + 1e-12:
                    out_i += 1
            if bar is not None:
                bar.update(t - bar.n)
    finally:
        if bar is not None:
            bar.close()
    stats = dict(integrator.counters(), backend=integrator.name, output_points=len(times),
                 branch_jumps=len(branch_jumps), unknowns=dae.n,
                 algebraic=int(dae.algebraic_idx.size), wall_time_s=_time.perf_counter() - wall)
    return _build_solution(dae, np.array(times), np.array(states), stats, tuple(branch_jumps))


def _restart(integrator, folds, dae, t, y):
    integrator.init(t, y, dae.derivative(t, y))
    if folds is not None:
        folds.restart(t, y)


def _progress(enabled, t0, t1):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=t1 - t0, unit="s", desc="transient",
                bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]")


def _failure(dae, step, times, states, branch_jumps, integrator):
    if not step.t >= times[-1]:  # some IDA failures report no time: use the last good one
        step = StepResult(step.status, times[-1], states[-1],
                          dae.derivative(times[-1], states[-1]), step.message)
    res = dae.evaluate(step.t, step.y, step.yp)[0]
    rate = np.abs(step.yp) / np.maximum(np.abs(step.y), 1.0)
    worst = dae.node_names[int(np.argmax(rate + np.abs(res) + (step.y < VACUUM_KPA) * 1e300))] \
        if dae.n else "?"
    partial = _build_solution(dae, np.array(times), np.array(states),
                              dict(integrator.counters(), failed=True), tuple(branch_jumps))
    return SolverError(
        f"IDA stopped at t = {step.t:.6g} s: {step.message}", time=step.t,
        where=f"node {worst}", partial=partial,
        hint="the pressure at this node changes fastest; try a tighter rtol, a larger "
             "flow_band (.options flow_band=50), or a small dead volume (.options dead_volume=0.05mL)")


def _build_solution(dae, times, states, stats, branch_jumps) -> Solution:
    """Pressures of the unknown nodes now (the states); the pressures sources impose,
    source flows and element signals when first read (:class:`LazySignals`)."""
    import functools

    states = states.reshape(len(times), dae.n)
    states.setflags(write=False)  # the pressure signals are views of it, handed over uncopied
    history = functools.cache(lambda: dae.full_pressures(times, states))
    ready, units, pending = {}, {}, {}
    for i, name in enumerate(dae.node_names):
        ready[f"p_{name}"] = states[:, i]
    fixed = [f"p_{name}" for name in dae.fixed_names if not dae.circuit.is_reference(name)]

    def fixed_pressures():
        return {key: history()[:, dae.node_index(key[2:])] for key in fixed}
    pending.update(dict.fromkeys(fixed, fixed_pressures))
    units.update(dict.fromkeys(list(ready) + fixed, "kPa"))
    sources = [f"mdot_{name}" for name in dae.pinned_sources()]

    def source_flows():
        return {f"mdot_{name}": flow for name, flow in dae.source_flows(times, history()).items()}
    pending.update(dict.fromkeys(sources, source_flows))
    units.update(dict.fromkeys(sources, "mg/s"))
    for names, signal_units, compute in dae.element_signal_groups(times, states, history):
        pending.update(dict.fromkeys(names, compute))
        units.update(zip(names, signal_units))
    ordered = {k: pending[k] for k in fixed}  # node pressures first, as before
    ordered.update((k, v) for k, v in pending.items() if k not in ordered)
    return Solution(times, LazySignals(ready, ordered), units, stats, dae.circuit.title,
                    branch_jumps)
