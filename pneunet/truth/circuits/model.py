"""A circuit (+ effects) simulated at the recorded times, and synthetic recordings.

:class:`TraceModel` builds the circuit for a parameter point, adds circuit effects,
simulates with the fit's solver settings and samples the signals at given times.
:class:`TraceResidual` is the picklable residual (scaled, jump samples left out) that
a process pool evaluates in parallel.
"""
from __future__ import annotations

import contextlib
import time
from dataclasses import replace
from typing import Callable

import numpy as np

from ...common.errors import PneunetError, SolverError

#: simulator settings of the fit's simulations: the Jacobian is taken by forward
#: differences with a step of :data:`DIFF_STEP` in ln value, so the simulator's own
#: error (rtol 1e-6: < 0.005 kPa on sampled tank pressures of the oscillator) must be
#: far below the response to a 0.5 % change (~0.5 kPa).  Known to be too long for
#: strongly correlated parameters (a polytropic tank's n and V from a mid-run
#: recording stop 3.5 standard errors off the optimum; 0.1 % reaches it) while 0.1 %
#: fails to release a base parameter held at its bound (the driven amplifier's line
#: resistance with a control-line tube stays at 0.02): a converged fit is refined from
#: its point with the shorter step (:data:`REFINE_DIFF_STEP`).
#: Folds are crossed by explicit jumps: aligned cycle by cycle (:mod:`.align`) they
#: agree with a stand-alone integration in the dead-volume limit to 0.02 kPa rms; a
#: 1e-4 mL dead volume instead agrees to 0.006 kPa but makes the finite differences
#: rough
FIT_OPTIONS = {"rtol": 1e-6, "atol": 1e-6}
DIFF_STEP = 5e-3
#: a converged fit is refined (:func:`~pneunet.truth.core.lsq.refine`) with these
#: simulator settings and finite-difference step: at rtol 1e-6 the oscillator's cost
#: along a line 0.25 % long wiggles by ±1 % (±9 in χ²), more than the standard errors
#: resolve; at 1e-8 by ±0.1 %, for 1.7× the time of a simulation
REFINE_OPTIONS = {"rtol": 1e-8, "atol": 1e-8}
REFINE_DIFF_STEP = 1e-3
#: simulation output points per sample interval where cycles are compared at shifted
#: times (a shifted cycle interpolated between sample-spaced points misplaces corners)
OUTPUT_PER_SAMPLE = 5


class TraceModel:
    """Simulate ``build(point)`` (+ effects) and sample its signals at given times
    (``typical_s``: a typical simulation's CPU time, for the budget of the first;
    ``budget``: (factor, minimum s) of the budget, default :data:`BUDGET_FACTOR`,
    :data:`BUDGET_MIN_S`)."""

    def __init__(self, build: Callable, fixed: dict | None = None, effects=(), start: str = "ic",
                 options: dict | None = None, typical_s: float | None = None, state=None,
                 budget: tuple | None = None):
        self.build, self.fixed, self.effects, self.start = build, dict(fixed or {}), tuple(effects), start
        self.options = dict(options or {})
        self.state = state  # a StartState (pneunet.truth.circuits.initial_state); None: rest at t = 0
        self.shift = 0.0  # s added to the state's netlist times (a clock fitted with the rest)
        self.calls = 0
        self.failures = 0  # simulations that failed (SolverError, budget included)
        self._times = [] if typical_s is None else [float(typical_s)]
        self.budget = (BUDGET_FACTOR, BUDGET_MIN_S) if budget is None else budget

    def with_state(self, state) -> "TraceModel":
        """The same model started from ``state`` (a new counter)."""
        return self._copy(state=state)

    def with_options(self, options: dict) -> "TraceModel":
        """The same model simulated with ``options`` added to its own (a new counter)."""
        return self._copy(options={**self.options, **options})

    def _copy(self, **changes) -> "TraceModel":
        args = {"build": self.build, "fixed": self.fixed, "effects": self.effects,
                "start": self.start, "options": self.options, "typical_s": self.typical_s,
                "state": self.state, "budget": self.budget, **changes}
        return TraceModel(**args)

    @property
    def typical_s(self) -> float | None:
        """Median CPU time of this process' simulations so far, s (None before one)."""
        return float(np.median(self._times)) if self._times else None

    @property
    def run_state(self):
        """The start state on the netlist's clock moved by :attr:`shift` (None: rest at 0)."""
        if self.state is None or not self.shift:
            return self.state
        return replace(self.state, time_offset=self.state.time_offset + self.shift)

    @property
    def first_time(self) -> float:
        """Netlist time of the record's first sample, s."""
        return 0.0 if self.state is None else self.state.first_time + self.shift

    def base_circuit(self, values: dict):
        """The netlist's circuit at ``values`` (no effects, no start state)."""
        from ...netlist.builder import apply_overrides

        point = dict(self.fixed)
        point.update({k: v for k, v in values.items() if not self._effect_param(k)})
        c = self.build(point)
        apply_overrides(c, point)
        if self.options:
            c.options = c.options.replace(**self.options)
        return c

    def circuit(self, values: dict, settle: bool = True):
        """The circuit at ``values``: the netlist's, started from the start state, with
        the effects in; ``settle`` False leaves the storage the effects add at the
        ambient pressure (for reading its structure and values only, not to simulate)."""
        c = self.base_circuit(values)
        state = self.run_state
        if state is not None:
            state.apply(c, values)
        settled = None
        if settle and self.start == "ic" and (self.effects or c.options.dead_volume > 0):
            settled = settled_pressures(c, state.time_offset if state else 0.0)
        old_nodes = set(c.nodes)
        for eff in self.effects:
            eff.apply(c, {k: values.get(k, eff.params[k][0]) for k in eff.params})
        if settled is not None:
            start_settled(c, settled, old_nodes)
        return c

    def _effect_param(self, name):
        """Whether ``name`` is an effect's or the start state's parameter (not the
        netlist's)."""
        return any(name in e.params for e in self.effects) or (
            self.state is not None and name in self.state.fitted)

    def simulate(self, values: dict, t_end: float, t_step: float | None = None):
        """The transient to ``t_end`` s after the record's first sample (on the netlist's
        clock: from the start state's time offset, through its settling time); a :class:`~pneunet.common.errors.SolverError` when it
        takes more than :data:`BUDGET_FACTOR` × the median simulation so far (at least
        :data:`BUDGET_MIN_S`): a fit's trial point that makes the circuit stiff or
        chattering is a failed point, not minutes lost."""
        self.calls += 1
        circuit = self.circuit(values)
        factor, least = self.budget
        budget = max(least, factor * float(np.median(self._times))) if self._times else None
        start = time.process_time()
        t0 = 0.0 if self.state is None else self.run_state.time_offset
        try:
            with cpu_time_budget(budget):
                sol = circuit.tran(self.first_time + t_end, t_step=t_step, t_start=t0,
                                   start=self.start)
        except SolverError:
            self.failures += 1
            raise
        self._times.append(time.process_time() - start)
        return sol

    def sample(self, values: dict, times, signals, align=None):
        """({signal: samples at ``times``}, solution); output on the sample spacing (a
        fifth of it with ``align``).

        ``times`` count from the record's first sample (netlist time
        :attr:`first_time`).  With ``align`` (:class:`~pneunet.truth.circuits.align.Alignment`)
        each recorded cycle is compared with the simulated cycle of the same number (in
        a settled start: the first after the settling time), started at its own crossing
        (the simulation runs ``align.margin`` past the record, twice that settled)."""
        dt = float(np.median(np.diff(times))) if len(times) > 1 else None
        if dt is not None and align is not None:  # compared at shifted times: finer output
            dt /= OUTPUT_PER_SAMPLE
        settled = self.state is not None and self.state.mode == "settled"
        t_end = float(times[-1]) + (align.margin * (2 if settled else 1)
                                    if align is not None else 0.0)
        sol = self.simulate(values, t_end, dt)
        if align is None:
            at = times + self.first_time
        else:
            anchored = self.state is None or self.state.mode == "rest"
            at = align.model_times(times, sol.t, sol[align.signal], self.first_time, settled,
                                   anchored)
        return {s: sample_at(sol.t, sol[s], at) for s in signals}, sol


def settled_pressures(circuit, t0: float = 0.0) -> dict:
    """({node: pressure}, algebraic nodes) of the circuit's consistent state at ``t0``
    (s; every node, those of pressure sources and the reference included) without dead
    volumes (the algebraic nodes solved for the initial storage pressures), kPa."""
    from ...engine.assembly import CircuitDAE
    from ...engine.simulate import consistent_state

    options = circuit.options
    circuit.options = options.replace(dead_volume=0.0)
    try:
        dae = CircuitDAE(circuit)
        y, _ = consistent_state(dae, t0, dae.initial_state(t0))
    finally:
        circuit.options = options
    names = list(dae.node_names) + list(dae.fixed_names)  # sources' nodes too
    return (dict(zip(names, map(float, dae.full_pressures(t0, y)))),
            {dae.node_names[i] for i in dae.algebraic_idx})


def start_settled(circuit, settled, old_nodes) -> None:
    """Start the storage that effects or ``.options dead_volume`` put on algebraic nodes
    where the circuit had those nodes (``.ic``), and a new node at the pressure of the
    node it joins: a link's line node (a thermal chamber's inlet) at its chamber's, else
    a resistance's (a tube's inner node) at the node across it.  A recording starts from
    a settled state, not from a volume at the ambient pressure; an inlet node started
    at the pressure across its line (a valve's output) started the chamber's valve on
    its other branch."""
    from ...physics import elements

    settled, algebraic = settled
    for node in algebraic:
        circuit.initial.setdefault(node, settled[node])
    joins = [spec.nodes for spec in circuit.elements.values()
             if spec.kind in ("resistor", "pipe") and len(spec.nodes) == 2]
    links = [tuple(spec.nodes[k] for k in elements.family(spec.kind).link_ports)
             for spec in circuit.elements.values() if elements.family(spec.kind).link_ports]
    for a, b in links + joins:  # a link's node is at its volume's pressure, first
        for new, old in ((a, b), (b, a)):
            if new not in old_nodes and old in settled:
                circuit.initial.setdefault(new, settled[old])


#: a simulation may take this many times the median one before it counts as failed
BUDGET_FACTOR = 20.0
BUDGET_MIN_S = 5.0


class _OverBudget(Exception):
    pass


@contextlib.contextmanager
def cpu_time_budget(seconds: float | None):
    """Raise :class:`~pneunet.common.errors.SolverError` when the block uses more than
    ``seconds`` of this process' CPU time (SIGPROF; only in a process' main thread, else
    no limit).  CPU time, not wall time: on a machine busy with other work a simulation
    takes longer by the clock but not in CPU time, and a budget by the clock failed a
    study's right candidate at every screening point."""
    import signal
    import threading

    if seconds is None or threading.current_thread() is not threading.main_thread() \
            or not hasattr(signal, "setitimer"):
        yield
        return

    def alarm(*_):
        raise _OverBudget()

    previous = signal.signal(signal.SIGPROF, alarm)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield
    except _OverBudget:
        raise SolverError(f"simulation stopped after {seconds:.3g} s (its budget)",
                          hint="the trial parameters make the circuit far slower to "
                               "simulate than the others") from None
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)


def sample_at(t, y, times):
    """``y(t)`` interpolated at ``times``; the two states a branch jump stores at one
    time are nudged apart so the abscissae increase."""
    t = np.array(t, dtype=float)
    dup = np.nonzero(np.diff(t) <= 0)[0]
    if dup.size:
        t[dup + 1] = t[dup] + 1e-12 * np.maximum(1.0, np.abs(t[dup]))
        t = np.maximum.accumulate(t)
    return np.interp(times, t, y)


class TraceResidual:
    """Scaled residual (simulated − recorded) on the compared samples, for ln-parameters
    ``x`` (with ``clock_step``, a last entry that moves the netlist's clock by that many s
    per unit); a failed simulation gives a large constant residual.  Picklable."""

    def __init__(self, model: TraceModel, names, times, signals, measured: dict, keep: dict,
                 scales: dict, align=None, clock_step: float = 0.0):
        self.model, self.names, self.times, self.signals = model, list(names), times, signals
        self.measured, self.keep, self.scales, self.align = measured, keep, scales, align
        self.clock_step = clock_step  # s per unit of a last x that shifts the clock (0: none)
        self.failures = 0

    def with_model(self, model: TraceModel) -> "TraceResidual":
        """The same residual simulating ``model`` instead (a refinement's finer one)."""
        return TraceResidual(model, self.names, self.times, self.signals, self.measured,
                             self.keep, self.scales, self.align, self.clock_step)

    def size(self) -> int:
        return int(sum(self.keep[s].sum() for s in self.signals))

    def __call__(self, x):
        if self.clock_step:
            self.model.shift = float(x[-1]) * self.clock_step
            x = x[:-1]
        values = dict(zip(self.names, np.exp(x)))
        try:
            sim, _ = self.model.sample(values, self.times, self.signals, self.align)
        except PneunetError:
            self.failures += 1
            return np.full(self.size(), 1e3)
        return np.concatenate([((sim[s] - self.measured[s]) / self.scales[s])[self.keep[s]]
                               for s in self.signals])


def process_pool(workers: int | None):
    """A fork-based process pool of ``workers`` (None: up to 2, the cores shared here)
    whose workers die with this process (:mod:`pneunet.common.workers`), or None for one."""
    import os

    from ...common.workers import process_pool as guarded_pool

    return guarded_pool(min(2, os.cpu_count() or 1) if workers is None else int(workers))


def synthetic_trace(build: Callable, params: dict, t_end: float, *, dt: float = 0.05,
                    signals=("p_tank", "p_out"), noise: float = 0.5, seed: int = 0,
                    options: dict | None = None):
    """A recording simulated by pneunet with known ``params`` plus white noise (kPa /
    mg/s), columns time_s, p_<node>_kPa, mdot_<element>_mg_s (rtol 1e-7 unless
    ``options``)."""
    import pandas as pd

    from ...netlist.builder import apply_overrides

    c = build(params)
    apply_overrides(c, params)
    c.options = c.options.replace(**({"rtol": 1e-7, "atol": 1e-6} if options is None else options))
    times = np.arange(0.0, t_end + 1e-9, dt)
    sol = c.tran(float(times[-1]), t_step=dt)
    rng = np.random.default_rng(seed)
    data = {"time_s": times}
    for s in signals:
        unit = "kPa" if s.startswith("p_") else "mg_s"
        data[f"{s}_{unit}"] = sample_at(sol.t, sol[s], times) + noise * rng.standard_normal(len(times))
    return pd.DataFrame(data)
