"""The circuit's state at a recording's first sample.

A logger is started wherever the user started it: at switch-on, mid-cycle, minutes
later, with its own clock.  A fit that starts the simulation at the netlist's rest
state compares a start-up transient with a settled recording.  Three start states:

* ``rest``: the netlist's initial state (``.ic``, volumes' p0, ambient) at the first
  sample — a recording made from switch-on; for a driven circuit recorded from netlist
  time t0 > 0, the rest state at switch-on (or a record's length before t0, whichever is
  later) driven by its sources up to t0, so that states the record does not hold (a
  control line's pressure, a gas temperature) carry their history;
* ``record``: the state read from the recording — every storage node's initial
  pressure fitted with the parameters (``p0@NODE``), a recorded one from the pressure
  its first samples extrapolate to at t = 0 (a parabola through them), an unrecorded
  one from what the recorded algebraic nodes imply; a recorded algebraic node's value
  picks its branch (a valve open or closed), an unrecorded one's branch is the one
  whose first samples match the record;
  the elements' own states (a muscle's contraction and velocity, a balloon's volume)
  at rest for those pressures (:func:`element_states`), then moved to match their
  recorded signals (a muscle's encoder);
* ``settled``: a circuit that oscillates on its own (constant sources) simulated from
  rest through several cycles, its settled cycle aligned in phase with the record.

``auto`` (the default) takes ``rest`` when the recorded storage nodes' first values
agree with the rest state within their noise and every recorded algebraic node lies on
the rest state's branch, else ``record``.  ``settled`` is chosen by the user: it puts
every state on the cycle (an effect's gas temperature included) but hangs the whole fit
on the simulated limit cycle, which a base model that lacks an effect can move far
(the mid-run dead-volume recording of the tests: base fit 172× the floor settled, 8×
from the record's state).  A driven circuit (sources that vary during the
record) is simulated on the record's own clock: the netlist time of the first sample is
``time_offset`` (by default the first time stamp of the file).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ...common.errors import DataError, ParameterError
from .data import signal_unit

START_MODES = ("auto", "rest", "record", "settled")
#: most samples of the parabola whose value at t = 0 is a node's initial pressure
FIRST_SAMPLES = 12
#: rest is taken when every recorded node's first value lies within this many standard
#: errors of its rest pressure (and within REST_TOLERANCE_KPA at least)
REST_SIGMAS = 5.0
REST_TOLERANCE_KPA = 1.0
#: unrecorded storage that the recorded algebraic nodes put this far from rest (kPa, and
#: this fraction of the circuit's pressure range) is off rest: the algebraic values also
#: depend on the guessed parameters
IMPLIED_TOLERANCE_KPA = 5.0
IMPLIED_TOLERANCE = 0.05
#: full recorded cycles simulated before the record in the ``settled`` start
SETTLE_CYCLES = 4
#: prefix of a storage node's fitted initial pressure
P0_PREFIX = "p0@"


@dataclass(frozen=True)
class StartState:
    """The start used by a trace fit.

    ``mode`` rest/record/settled; ``pressures`` {node: kPa} imposed at the first sample;
    ``guesses`` {algebraic node: kPa} that pick its branch; ``fitted`` {``p0@NODE``:
    (guess, low, high)} initial pressures fitted with the parameters; ``time_offset``
    netlist time where the simulation starts (s); ``settle`` s simulated from there before
    the first sample (the settled cycle; a driven circuit's history from rest);
    ``driven``: the sources vary during the record (no cycle alignment); ``signals``
    {element signal: first recorded value} that set the elements' own states."""

    mode: str
    pressures: dict = field(default_factory=dict)
    guesses: dict = field(default_factory=dict)
    fitted: dict = field(default_factory=dict)
    time_offset: float = 0.0
    settle: float = 0.0
    driven: bool = False
    reason: str = ""
    signals: dict = field(default_factory=dict)
    clock: str = ""  # how the netlist time of the first sample was found, when not the file's
    #: s, when ``clock`` is set: the sources' common period (sources that change once:
    #: twice the starts scanned); the clock's fit moves within half of it
    clock_period: float = 0.0
    clock_ci: tuple = ()  # s, the interval of the first sample's netlist time once fitted

    @property
    def first_time(self) -> float:
        """Netlist time of the record's first sample, s."""
        return self.time_offset + self.settle

    def apply(self, circuit, values: dict) -> None:
        """Set the start in ``circuit.initial`` (``values``: the fitted ``p0@NODE``)."""
        if self.mode != "record":
            return
        for node, p in {**self.guesses, **self.pressures}.items():
            circuit.initial[node] = float(p)
        for name, (guess, _, _) in self.fitted.items():
            circuit.initial[name[len(P0_PREFIX):]] = float(values.get(name, guess))
        circuit.initial.update(element_states(circuit, self.time_offset, self.signals))

    def describe(self) -> str:
        """One line for the report."""
        clock = f", netlist time {self.first_time:g} s at the first sample" \
            if self.first_time and self.mode != "settled" else ""
        kind = "driven by its sources" if self.driven else "autonomous"
        if self.mode == "record":
            given = ", ".join(f"{n} {p:.4g} kPa" for n, p in self.pressures.items())
            parts = [f"from the record ({given or 'no recorded storage node'})"]
            if self.guesses:
                parts.append("branch of " + ", ".join(f"{n} near {p:.4g} kPa"
                                                      for n, p in self.guesses.items()))
            if self.fitted:
                parts.append("fitted: " + ", ".join(self.fitted))
            if self.signals:
                parts.append("element states from " + ", ".join(
                    f"{n} {v:.4g} {signal_unit(n)}" for n, v in self.signals.items()))
            text = "; ".join(parts)
        elif self.mode == "settled":
            text = f"settled cycle ({self.settle:.3g} s simulated from rest, aligned in phase)"
        elif self.settle:
            text = (f"rest state of the netlist at netlist time {self.time_offset:g} s, "
                    f"driven by its sources for {self.settle:.4g} s to the first sample")
        else:
            text = "rest state of the netlist at the first sample"
        fitted = (f"; fitted with the parameters: {self.first_time:.4f} s, 95 % interval "
                  f"{(self.clock_ci[0] - self.first_time) * 1e3:+.2g} … "
                  f"{(self.clock_ci[1] - self.first_time) * 1e3:+.2g} ms") if self.clock_ci else ""
        return f"{text}; circuit {kind}{clock}" + (f" ({self.reason})" if self.reason else "") \
            + (f"; {self.clock}" if self.clock else "") + fitted

    def to_json(self) -> dict:
        return {"mode": self.mode, "pressures": dict(self.pressures),
                "branch_guesses": dict(self.guesses), "fitted": list(self.fitted),
                "time_offset_s": self.time_offset, "settle_s": self.settle,
                "driven": self.driven, "reason": self.reason, "clock": self.clock or None,
                "first_time_s": self.first_time,
                "first_time_ci_s": list(self.clock_ci) if self.clock_ci else None,
                "element_signals": dict(self.signals)}


def first_value(t, y, n: int = FIRST_SAMPLES) -> tuple[float, float]:
    """(value at t[0], its standard error) of a parabola through the first samples
    before the first jump (:func:`~pneunet.truth.circuits.data.jump_samples`): the most of
    them, at most ``n``, that a parabola fits within their noise (the noise from the
    whole column's second differences, at least its rounding to a logger's grid), so a
    corner (a valve switching) soon after the first sample does not bend the
    estimate."""
    from ..core.noise import difference_sigma, rounding_sigma
    from .data import jump_samples

    t, y = np.asarray(t, float), np.asarray(y, float)
    jumps = jump_samples(y)
    m = min(n, len(y), int(jumps[0]) + 1 if len(jumps) else len(y))
    sigma = max(difference_sigma(y), rounding_sigma(y))
    if m < 4 or not sigma > 0:
        return float(y[0]), float(sigma) if sigma > 0 else float("nan")
    for k in range(m, 3, -1):
        A = np.column_stack([np.ones(k), t[:k] - t[0], (t[:k] - t[0]) ** 2])
        coef, *_ = np.linalg.lstsq(A, y[:k], rcond=None)
        resid = y[:k] - A @ coef
        dof = k - 3
        if float(resid @ resid) / sigma ** 2 <= dof + 3.0 * math.sqrt(2.0 * dof) + 1.0:
            break
    cov = sigma ** 2 * np.linalg.pinv(A.T @ A)
    return float(coef[0]), float(math.sqrt(cov[0, 0]))


def element_states(circuit, t0: float, recorded: dict | None = None) -> dict:
    """{state node: value} of the elements' own states (``state_ports``: a muscle's
    contraction and velocity, a balloon's volume) at netlist time ``t0`` (s) for the
    pressures of ``circuit.initial``: at rest for them (every rate zero: a muscle where
    its force balances its load, a balloon at its pressure's volume), then, for an
    element with a signal in ``recorded`` ({``contraction_M1``: mm, …} at ``t0``), its
    states moved by least squares until its signals match (the states a signal does not
    see, a muscle's velocity, keep their rest values).  Empty without such elements."""
    from scipy import optimize

    from ...engine.assembly import CircuitDAE
    from ...engine.single_rate import pseudo_capacitance, residual_and_jacobian
    from ...engine.solvers.newton import newton

    if not any(_family(spec.kind).state_ports for spec in circuit.elements.values()):
        return {}
    dae = CircuitDAE(circuit)
    states = [dae.node_names.index(n) for n in sorted(dae.state_nodes)]
    y = dae.initial_state(t0)
    active = np.union1d(states, dae.algebraic_idx)
    result = newton(residual_and_jacobian(dae, t0), y, active,
                    capacitance=pseudo_capacitance(dae, t0, y))
    if result.converged:
        y = result.y
    seen = _signals_at(dae, t0, y, recorded or {})
    if seen:
        owners = {name.partition("_")[2] for name in seen}  # contraction_M1 → M1
        free = [dae.node_names.index(spec.nodes[p]) for spec in circuit.elements.values()
                if spec.name in owners
                for p in _family(spec.kind).state_ports]
        target = np.array([recorded[n] for n in seen])

        def miss(z):
            trial = y.copy()
            trial[free] = z
            return np.array(list(_signals_at(dae, t0, trial, recorded).values())) - target

        fit = optimize.least_squares(miss, y[free], bounds=(1e-6, np.inf), x_scale=1.0)
        y[free] = fit.x
    return {dae.node_names[i]: float(y[i]) for i in states}


def _family(kind):
    from ...physics import elements

    return elements.family(kind)


def _signals_at(dae, t0, y, wanted) -> dict:
    """{signal: value} of the ``wanted`` element signals at state ``y`` (time ``t0``)."""
    if not wanted:
        return {}
    t, states = np.array([float(t0)]), y[None, :]
    full = dae.full_pressures(t, states)
    out = {}
    for names, _, compute in dae.element_signal_groups(t, states, lambda: full):
        if any(n in wanted for n in names):
            out.update({n: float(v[0]) for n, v in compute().items() if n in wanted})
    return {n: out[n] for n in wanted if n in out}


def _recorded_states(circuit, data) -> dict:
    """{element signal: value at the first sample} of the recorded columns of elements
    that carry their own states (a muscle's contraction, force or volume)."""
    from .data import element_column, signal_of_column

    stateful = {spec.name for spec in circuit.elements.values()
                if _family(spec.kind).state_ports}
    times = data["time_s"].to_numpy()
    out = {}
    for col in data.columns:
        ref = element_column(col)
        if ref is not None and ref.stem.partition("_")[2] in stateful:
            out[signal_of_column(col)] = first_value(times, data[col].to_numpy())[0]
    return out


def sources_vary(circuit, t0: float, t1: float) -> bool:
    """Whether a source of ``circuit`` changes its value within [t0, t1] (s)."""
    from .clock import varying_waveforms

    return bool(varying_waveforms(circuit, t0, t1))


def choose_start(model, values: dict, data, mode: str = "auto",
                 time_offset: float | None = None, where: str = "trace") -> StartState:
    """The :class:`StartState` of ``model`` (a :class:`~pneunet.truth.circuits.model.TraceModel`)
    for the recording ``data`` (from :func:`~pneunet.truth.circuits.data.read_trace`) at the
    parameter guesses ``values``; see the module docstring for ``mode``.  Without
    ``time_offset``, a circuit driven by periodic sources (or by sources that change
    once) whose switching the file's clock misplaces starts where the record shows it
    (:mod:`.clock`)."""
    if mode not in START_MODES:
        raise ParameterError(f"start {mode!r} is not one of {', '.join(START_MODES)}")
    state = _placed_start(model, values, data, mode, time_offset, where)
    if time_offset is None and mode != "settled" and not state.clock:
        state = _unplaced_note(state, model, values, data)
    return state


def _placed_start(model, values: dict, data, mode: str, time_offset: float | None,
                  where: str) -> StartState:
    """:func:`choose_start` before the note on sources a record cannot place."""
    clock = ""
    if time_offset is None and mode != "settled":
        origin = float(data.attrs.get("time_origin", 0.0))
        times = data["time_s"].to_numpy()
        circuit = model.base_circuit(values)
        from .clock import clock_from_record, source_clock

        # sources that change once are scanned wherever the file's clock puts the record
        # (a wall-clock time after the last change, a logger started before the first)
        if clock_from_record(circuit, origin, float(times[-1])):
            time_offset, clock, period = source_clock(circuit, data, origin)
            if not clock and origin == 0 and mode == "auto":
                state = _start_at(model, values, data, mode, time_offset, where)
                if state.mode == "rest":
                    return state
                # a file clock from 0 whose first samples are off the rest state is no
                # record from switch-on: a logger's own clock, kept only where it fits best
                time_offset, clock, period = source_clock(circuit, data, origin, slack=1.0)
                if not clock:
                    return state
                clock = ("the file's clock starts at 0 but the first samples are off the "
                         "rest state (no record from switch-on); " + clock)
    state = _start_at(model, values, data, mode, time_offset, where)
    return replace(state, clock=clock, clock_period=period) if clock else state


def _unplaced_note(state: StartState, model, values: dict, data) -> StartState:
    """``state`` with a note in its reason where the file's clock was taken for sources a
    record cannot place (:func:`~pneunet.truth.circuits.clock.unplaced_sources`)."""
    from .clock import unplaced_sources

    times = data["time_s"].to_numpy()
    unplaced = unplaced_sources(model.base_circuit(values),
                                float(data.attrs.get("time_origin", 0.0)), float(times[-1]))
    if not unplaced:
        return state
    return replace(state, reason="; ".join(filter(None, [state.reason, (
        f"the file's clock is taken as the netlist's: {', '.join(unplaced)} (a Python "
        "function, a damped SIN or a sampled waveform) cannot be placed from the record; "
        "if the logger was not started at the file's time 0 on the netlist's clock, give "
        "the first sample's netlist time (--time-offset)")])))


def _start_at(model, values: dict, data, mode: str, time_offset: float | None,
              where: str) -> StartState:
    """:func:`choose_start` once the netlist time of the first sample is settled."""
    times = data["time_s"].to_numpy()
    origin = float(data.attrs.get("time_origin", 0.0))
    circuit = model.base_circuit(values)
    span = float(times[-1])
    if time_offset is None:
        varies = sources_vary(circuit, origin, origin + span)
        offset = origin if varies else 0.0
    else:
        offset = float(time_offset)
    driven = sources_vary(circuit, offset, offset + span)
    if mode == "settled":
        if driven:
            raise ParameterError("start 'settled' needs a circuit that oscillates on its own",
                                 hint="its sources vary during the record: use --start record")
        return _settled(data, where)
    rest, storage, algebraic = _rest_state(circuit, offset)
    recorded = {c[2:-4]: first_value(times, data[c].to_numpy())
                for c in data.columns if c.startswith("p_") and c[2:-4] in rest}
    off_rest = {n: v for n, (v, se) in recorded.items() if n in storage
                and abs(v - rest[n]) > max(REST_TOLERANCE_KPA,
                                           REST_SIGMAS * (se if math.isfinite(se) else 0.0))}
    measured_algebraic = {n: v for n, (v, _) in recorded.items() if n in algebraic}
    unrecorded_storage = [n for n in storage if n not in recorded]
    lo, hi = _pressure_range(circuit, rest)
    implied = _implied_storage(circuit, offset, rest, {n: v for n, (v, _) in recorded.items()
                                                       if n in storage},
                               measured_algebraic, unrecorded_storage, lo, hi)
    if not off_rest:  # unrecorded storage the recorded algebraic nodes put off rest
        off_rest = {n: v for n, v in implied.items()
                    if abs(v - rest[n]) > max(IMPLIED_TOLERANCE_KPA,
                                              IMPLIED_TOLERANCE * (hi - lo))}
    if not off_rest:  # storage at rest: is every recorded algebraic node on its branch?
        off_rest = _other_branches(circuit, offset, rest, measured_algebraic)
    if mode == "rest" or (mode == "auto" and not off_rest):
        reason = "the first samples match the rest state" if mode == "auto" else "forced"
        # a driven circuit's unrecorded states (a control line's pressure, a gas
        # temperature) carry its sources' recent history: run them from rest before the
        # first sample, from switch-on (netlist time 0) or a record's length earlier, a
        # whole number of sample spacings (the simulation's output falls on the samples)
        history = max(0.0, min(offset, span)) if driven else 0.0
        if history > 0 and len(times) > 1:
            dt = float(np.median(np.diff(times)))
            history = math.floor(history / dt + 1e-9) * dt
            history = offset if offset - history < 1e-9 * dt else history
        return StartState("rest", time_offset=offset - history, settle=history,
                          driven=driven, reason=reason)
    pressures = {n: v for n, (v, _) in recorded.items() if n in storage}
    guesses = {n: v for n, (v, _) in recorded.items() if n in algebraic}
    # every storage node's initial pressure is fitted: an unrecorded one from the
    # pressure the recorded algebraic nodes imply, a recorded one from its first samples
    # (fixed there, their noise and a transient's curvature would bias the parameters)
    fitted = {f"{P0_PREFIX}{n}": (float(np.clip(pressures.get(n, implied.get(n, rest[n])),
                                                lo, hi)), lo, hi) for n in storage}
    if mode == "auto":
        first = ", ".join(f"{n} {v:.4g} kPa against {rest[n]:.4g}"
                          for n, v in list(off_rest.items())[:3])
        reason = f"the first samples are off the rest state: {first}"
    else:
        reason = "forced"
    state = StartState("record", pressures, guesses, fitted, offset, 0.0, driven, reason,
                       _recorded_states(circuit, data))
    unrecorded = [n for n in algebraic if n not in guesses]
    if unrecorded:
        state = _pick_branches(model, values, data, state, unrecorded, rest)
    return state


def _rest_state(circuit, t0):
    """({node: rest pressure}, storage nodes, algebraic nodes) at netlist time ``t0``."""
    from ...engine.assembly import CircuitDAE
    from ...engine.single_rate import consistent_state

    dae = CircuitDAE(circuit)
    y, _ = consistent_state(dae, t0, dae.initial_state(t0))
    names = list(dae.node_names) + list(dae.fixed_names)
    rest = dict(zip(names, map(float, dae.full_pressures(t0, y))))
    algebraic = [dae.node_names[i] for i in dae.algebraic_idx]
    storage = dae.stored_pressure_nodes
    return rest, storage, algebraic


def _implied_storage(circuit, t0, rest, storage_values, algebraic_values, unknown, lo, hi):
    """{unrecorded storage node: kPa}: the pressures that put the recorded algebraic
    nodes (a valve junction) at their recorded first values in the consistent state,
    by least squares from the rest state (the recorded storage at its values); empty
    when nothing is recorded that depends on them."""
    from scipy import optimize

    from ...engine.assembly import CircuitDAE
    from ...engine.single_rate import consistent_state
    from ...common.errors import PneunetError

    if not unknown or not algebraic_values:
        return {}
    dae = CircuitDAE(circuit)
    names = list(dae.node_names)
    base = dae.initial_state(t0)
    for n, v in {**storage_values, **algebraic_values}.items():
        base[names.index(n)] = v
    guess = base.copy()

    def miss(z):
        y0 = guess.copy()
        y0[[names.index(n) for n in unknown]] = z
        try:
            y, _ = consistent_state(dae, t0, y0)
        except PneunetError:
            return np.full(len(algebraic_values), 1e3)
        guess[dae.algebraic_idx] = y[dae.algebraic_idx]  # the next solve starts here
        return np.array([y[names.index(n)] - v for n, v in algebraic_values.items()])

    z0 = np.clip([rest[n] for n in unknown], lo, hi)
    r = optimize.least_squares(miss, z0, bounds=(lo, hi), diff_step=1e-4, max_nfev=50)
    return dict(zip(unknown, map(float, r.x)))


def _other_branches(circuit, t0, rest, recorded) -> dict:
    """{algebraic node: recorded first value} of the nodes whose recorded value leads
    to another root than the rest state's (a valve on its other branch)."""
    from ...engine.assembly import CircuitDAE
    from ...engine.single_rate import consistent_state
    from ...common.errors import PneunetError

    if not recorded:
        return {}
    dae = CircuitDAE(circuit)
    y0 = dae.initial_state(t0)
    for node, value in recorded.items():
        y0[dae.node_names.index(node)] = value
    try:
        y, _ = consistent_state(dae, t0, y0)
    except PneunetError:
        return dict(recorded)
    full = dict(zip(list(dae.node_names) + list(dae.fixed_names), dae.full_pressures(t0, y)))
    return {n: v for n, v in recorded.items() if abs(full[n] - rest[n]) > REST_TOLERANCE_KPA}


def _pressure_range(circuit, rest) -> tuple[float, float]:
    """(lowest, highest) pressure the circuit's sources and ambient set, kPa: the range
    of a fitted initial pressure."""
    values = [circuit.options.ambient] + [rest[n] for n in rest]
    lo, hi = min(values), max(values)
    return 0.9 * lo, 1.1 * hi


def _pick_branches(model, values, data, state, nodes, rest) -> StartState:
    """Guesses for the unrecorded algebraic ``nodes`` (a valve's output between its
    branches): each pressure the circuit holds at the start (rest state, recorded first
    values) tried as the guess of all of them; of the distinct consistent states they
    lead to, the one whose simulation matches the first recorded samples best."""
    from ...engine.assembly import CircuitDAE
    from ...engine.single_rate import consistent_state
    from ...common.errors import PneunetError
    from .model import sample_at

    times = data["time_s"].to_numpy()
    k = min(len(times), max(FIRST_SAMPLES * 2, 10))
    cols = [c for c in data.columns if c.startswith("p_")]
    levels = sorted({round(v, 6) for v in list(rest.values()) + list(state.pressures.values())
                     + list(state.guesses.values())})
    roots, states = [], []
    for level in levels:
        trial = replace(state, guesses={**state.guesses, **{n: level for n in nodes}})
        try:
            circuit = model.with_state(trial).circuit(values)
            dae = CircuitDAE(circuit)
            y, _ = consistent_state(dae, trial.time_offset, dae.initial_state(trial.time_offset))
        except PneunetError:
            continue
        root = np.array([y[dae.node_names.index(n)] for n in nodes])
        if any(np.allclose(root, r, atol=REST_TOLERANCE_KPA) for r in roots):
            continue
        roots.append(root)
        trial = replace(state, guesses={**state.guesses,
                                        **{n: float(v) for n, v in zip(nodes, root)}})
        try:
            sol = model.with_state(trial).simulate(values, float(times[k - 1]))
        except PneunetError:
            continue
        err = sum(float(np.sum((sample_at(sol.t, sol[c[:-4]], times[:k] + trial.first_time)
                                - data[c].to_numpy()[:k]) ** 2)) for c in cols)
        states.append((err, trial))
    if not states:
        raise DataError("the circuit cannot start from the recorded first samples",
                        where="start state", hint="try --start rest or --start settled")
    return min(states, key=lambda s: s[0])[1]


def _settled(data, where) -> StartState:
    """The settled start: SETTLE_CYCLES recorded periods and the time to the record's
    first cycle start simulated from rest before the first sample."""
    from .align import Alignment

    cols = [c for c in data.columns if c.startswith("p_")]
    times = data["time_s"].to_numpy()
    for c in cols:
        a = Alignment.of(times, data[c].to_numpy(), c[:-4])
        if a is not None:
            period = float(np.median(np.diff(a.starts)))
            return StartState("settled", settle=SETTLE_CYCLES * period + float(a.starts[0]),
                              reason=f"{c} oscillates with period {period:.3g} s")
    raise DataError("start 'settled' needs a record that oscillates (two full cycles or more)",
                    where=where, hint="use --start record")
