"""Analyses: operating point and transient.

``transient`` integrates the circuit's DAE from a consistent initial state: with
SUNDIALS IDA over the whole circuit (:mod:`~pneunet.engine.single_rate`), or for large
networks of cells each cell on its own steps (:mod:`~pneunet.engine.multirate`,
:mod:`~pneunet.engine.hub_first`).
"""
from __future__ import annotations

import time as _time

import numpy as np

from .assembly import CircuitDAE, distinct_times
from ..common.solver_messages import captured
from ..common.errors import ParameterError, SolverError
from .solution import OperatingPoint, Solution, build_solution
from .stability import linear_stability
from .single_rate import consistent_state, integrate, pseudo_capacitance, residual_and_jacobian
from .solvers.newton import newton


def _steady_state(dae, t):
    """Newton's steady state (ẏ = 0) of every unknown at time ``t``, or SolverError."""
    y0 = dae.initial_state(t)
    everything = np.arange(dae.n)
    result = newton(residual_and_jacobian(dae, t), y0, everything,
                    capacitance=pseudo_capacitance(dae, t, y0))
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
    size.  Circuits above :data:`~pneunet.engine.single_rate.STEP_STORE_LIMIT`
    unknowns let IDA interpolate onto the grid itself, so that memory follows the
    outputs.
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
    _check_corners(circuit, t_start, t_stop, limit)
    wall = _time.perf_counter()
    dae = CircuitDAE(circuit)
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
        if part.read_only_hub:
            from .hub_first import transient as multirate
        else:
            from .multirate import transient as multirate

        algebraic = {dae.node_names[i] for i in dae.algebraic_idx}
        return multirate(circuit, dae, part, t_stop, t_step, t_start, y, algebraic, _single_rate)

    outputs = (np.append(np.arange(t_start, t_stop, t_step)[1:], t_stop) if t_step else None)
    record, steps, integrator = integrate(dae, t_start, t_stop, y, yp, outputs, backend,
                                          progress)
    times, states = record.arrays()
    stats = dict(integrator.counters(), backend=integrator.name, steps=steps,
                 output_points=len(times),
                 branch_jumps=len(record.jumps), unknowns=dae.n,
                 algebraic=int(dae.algebraic_idx.size), wall_time_s=_time.perf_counter() - wall)
    return build_solution(dae, times, states, stats, tuple(record.jumps))


#: ``method=auto`` integrates cells on their own steps from this many unknowns, when the
#: sources switch on at least AUTO_MULTIRATE_SCHEDULES different schedules (cells that
#: switch together are cheap for one global step); cells that only read their hub (it
#: pins them: no relaxation) from AUTO_MIN_CELLS cells driven in at least
#: AUTO_MULTIRATE_SCHEDULES different ways
AUTO_MULTIRATE_UNKNOWNS = 400
AUTO_MULTIRATE_SCHEDULES = 32


def _partition_for(circuit, dae, backend, span):
    """The circuit's hub and cells when the multirate method integrates it over ``span``
    (t_start, t_stop), else None."""
    from .partition import AUTO_MIN_CELLS, partition, unsupported, worth_partitioning

    method = circuit.options.method
    if method == "single" or method == "auto" and (backend is not None
                                                   or dae.n < AUTO_MIN_CELLS):
        return None
    part = partition(circuit)
    algebraic = {dae.node_names[i] for i in dae.algebraic_idx}
    if method == "auto":
        if worth_partitioning(part, algebraic):
            return None
        scheduled = dae.n >= AUTO_MULTIRATE_UNKNOWNS and \
            _schedules(dae, *span) >= AUTO_MULTIRATE_SCHEDULES
        if scheduled or part.read_only_hub and \
                _drives(dae, part, span) >= AUTO_MULTIRATE_SCHEDULES:
            return part
        return None
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
            + (f", hub nodes {hub}" if part.hub_nodes else ", no hub (independent cells)")
            + (" (read only by the cells: integrated first)" if part.read_only_hub else ""))


def _schedules(dae, t_start, t_stop) -> float:
    """How many different switching schedules the inputs follow: their distinct corners
    in (t_start, t_stop) over the mean number of one element's corners (0: none)."""
    own = [c[0] for c in dae.instance_corners(t_start, t_stop).values()]
    mean = np.mean([len(c) for c in own]) if own else 0.0
    return distinct_times(own).size / mean if mean > 0 else 0.0


def _drives(dae, part, span) -> int:
    """How many different ways the cells are driven: distinct sets of the hub nodes and
    the source schedules (corners in ``span``) each cell reads."""
    corners = dae.instance_corners(*span)
    drives = {(tuple(sorted(cell.hub_nodes)),
               tuple(sorted(tuple(np.round(corners[s][0], 12)) if s in corners else ()
                            for s in cell.sources)))
              for cell in part.cells}
    return len(drives)


def _single_rate(circuit, t_stop, t_step, t_start):
    """One independent cell (a circuit of its own) on the single-rate integrator."""
    circuit.options = circuit.options.replace(method="single")
    return transient(circuit, t_stop, t_step=t_step, t_start=t_start)


#: output points a transient may ask for (8 bytes per point and unknown)
MAX_OUTPUT_POINTS = 10_000_000


def _check_corners(circuit, t_start, t_stop, limit) -> None:
    """A ParameterError naming the source whose waveform has more corners in
    (t_start, t_stop) than ``limit`` (each one a stop of the integrator), before any
    is made: PULSE with a 4 ns period over 10^4 s would be 10^13."""
    from ..physics.waveforms import Waveform

    for name, spec in circuit.elements.items():
        for value in spec.params.values():
            if isinstance(value, Waveform):
                count = value.corner_count(t_start, t_stop)
                if count > limit:
                    raise ParameterError(
                        f"{value.netlist()} has {count:.3g} corners in {t_stop - t_start:g} s, "
                        f"each a stop of the integrator (limit max_output_points = "
                        f"{limit:.0e})", where=name,
                        hint="a longer period or a shorter transient; or a larger "
                             "max_output_points (--limit max_output_points=N)")


def _sources_only(dae, t_start, t_stop, t_step, wall) -> Solution:
    """The solution of a circuit without unknowns: the sources' pressures and the flows
    they drive, on the output grid (or at the sources' corners), no integrator."""
    corners = np.concatenate([[t_start, t_stop], dae.breakpoints(t_start, t_stop),
                              dae.jumps(t_start, t_stop)])
    times = (np.append(np.arange(t_start, t_stop, t_step), t_stop) if t_step
             else np.unique(corners))
    jumps = dae.jumps(t_start, t_stop)  # each twice: both sides (solution.left_limits)
    times = np.sort(np.concatenate([times[~np.isin(times, jumps)], jumps, jumps]))
    stats = dict(backend="none (no unknowns)", steps=0, output_points=len(times),
                 branch_jumps=0, unknowns=0, algebraic=0,
                 wall_time_s=_time.perf_counter() - wall)
    return build_solution(dae, times, np.empty((len(times), 0)), stats, ())


