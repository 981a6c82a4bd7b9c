"""Fit a circuit to a recorded transient: least squares through the simulator.

The unknown parameters (e.g. R_out, R_vent and V of the oscillator, and the parameters
of circuit effects) are varied in log space within bounds until the simulated signals
match the recorded ones at the recorded times, on a fit window (the first cycles).
Every recorded column is compared; around the jumps of an algebraic node (p_out at a
fold) a few samples are left out (:func:`compared_masks`); a storage node's samples are
all compared, its fast edges included (they tell a resistance from a volume).
Intervals come from :func:`pneunet.truth.core.intervals.intervals` (white residuals, or a
sandwich through an AR model of autocorrelated ones, and why).  The solution over the
whole record gives the held-out error.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ...common.errors import DataError, ParameterError, PneunetError
from ...common.reprs import Summarized, listed, number
from ..core.intervals import intervals
from ..core.lsq import (LsqResult, jacobian_spread, least_squares_log, refine,
                        secant_checked, secant_note)
from ..core.noise import record_sigma, segments
from .align import Alignment, thinned
from .clock import CLOCK, clock_fitted, clock_unit, fit_clock
from .data import compared_samples, read_trace, signal_of_column, signal_unit, swings
from .driven_start import better_start, clock_at_fit
from .initial_state import P0_PREFIX, StartState, choose_start
from .model import (DIFF_STEP, FIT_OPTIONS, REFINE_DIFF_STEP, REFINE_OPTIONS, TraceModel,
                    TraceResidual, sample_at)


@dataclass(repr=False)
class TraceFit(Summarized):
    """Result of :func:`fit_trace`.

    ``values``, ``ci`` ({name: (low, high)}), ``stderr_log`` (standard error of ln
    value), ``rmse`` per signal in the fit window (its own unit, compared samples),
    ``residuals`` (DataFrame: time_s, phase, fitted, one column per signal, NaN where
    not compared), ``phase_rms`` (phase bin centre, rms per signal),
    ``period_measured``/``period_simulated``/``period_error`` (s, at ``node``),
    ``unit`` ('kPa', or :data:`NOISE_UNIT` for signals of several units) and ``scales``
    (signal → divisor giving that unit), ``solution`` (the simulation with the
    estimates over the whole record).
    """

    values: dict
    ci: dict
    stderr_log: dict
    rmse: dict
    residuals: object
    phase_rms: object
    period_measured: float
    period_simulated: float
    period_error: float
    sigma: float
    nfev: int
    success: bool
    message: str
    effects: tuple = ()
    solution: object = None
    wall_time_s: float = 0.0
    unit: str = "kPa"
    scales: dict = field(default_factory=dict)
    extras: dict = field(default_factory=dict)
    on_budget: bool = False  # stopped on its simulation budget before converging

    def _summary(self):
        estimates = (f"{k} {v:.4g} [{self.ci[k][0]:.3g}, {self.ci[k][1]:.3g}]"
                     for k, v in self.values.items())
        rows = [("estimates (95 % CI)", listed(estimates, 4)),
                ("rms residual", number(self.error(), self.unit, 3)),
                ("period error", number(self.period_error, "s", 3)),
                ("converged", str(self.success)), ("evaluations", str(self.nfev)),
                ("wall time", number(self.wall_time_s, "s", 3))]
        title = " + ".join(e.name for e in self.effects) or "base model"
        return title, rows, ".values, .ci, .residuals, .solution, .report()"

    def signals(self) -> list[str]:
        return [c for c in self.residuals.columns if c not in ("time_s", "phase", "fitted")]

    def _in(self, window):
        """Mask of the residual rows in ``window`` (default: the fit window)."""
        r = self.residuals
        if window is None:
            return r["fitted"].to_numpy()
        t = r["time_s"].to_numpy()
        return (t >= window[0]) & (t <= window[1])

    def error(self, window=None) -> float:
        """Pooled rms of the scaled residuals (in ``unit``) on the compared samples in
        ``window`` (default: the fit window)."""
        return _rms(self.scaled_residuals(window))

    def scaled_residuals(self, window=None) -> np.ndarray:
        """The residuals of :meth:`error`, signal after signal (NaN where not compared)."""
        sel = self._in(window)
        return np.concatenate([self.residuals[s].to_numpy()[sel] / self.scales.get(s, 1.0)
                               for s in self.signals()])

    def errors_by_signal(self, window=None) -> dict:
        """{signal: rms residual in the signal's own unit} on the compared samples in
        ``window`` (default: the fit window)."""
        sel = self._in(window)
        return {s: _rms(self.residuals[s].to_numpy()[sel]) for s in self.signals()}

    def as_dict(self) -> dict:
        return {"values": self.values, "ci": {k: list(v) for k, v in self.ci.items()},
                "rmse": self.rmse, "period_measured": self.period_measured,
                "period_simulated": self.period_simulated, "period_error": self.period_error,
                "sigma": self.sigma, "nfev": self.nfev, "success": self.success,
                "stopped_on_budget": self.stopped_on_budget(), "message": self.message,
                "effects": [e.name for e in self.effects],
                "wall_time_s": self.wall_time_s, "unit": self.unit,
                "start_state": self.start_state.to_json() if self.start_state else None,
                **{k: v for k, v in self.extras.items()
                   if k not in ("stage1", "alignment", "jacobian", "start_state", "model")}}

    @property
    def start_state(self):
        """The :class:`~pneunet.truth.circuits.initial_state.StartState` the fit used."""
        return self.extras.get("start_state")

    def corrected_netlist(self, verdict: str | None = None) -> str:
        """The fitted circuit as netlist text: the user's netlist with the fitted values
        and the effects written in (:mod:`pneunet.truth.circuits.netlist_out`)."""
        from .netlist_out import corrected_netlist

        return corrected_netlist(self.extras["model"], self.values, ci=self.ci,
                                 recording=self.extras.get("recording", ""),
                                 times=self.residuals["time_s"].to_numpy(), verdict=verdict,
                                 caveat="; ".join(
                                     self.extras.get("intervals", {}).get(k, "") for k in
                                     ("undetermined_note", "at_bound_note")).strip("; "))

    def report(self) -> str:
        lines = ["parameter        estimate      95 % CI"]
        every = self.extras.get("fitted_every_nth_sample", 1)
        if every > 1:
            lines.insert(0, f"fitted on one sample in {every} (see the intervals' note)")
        for k, v in self.values.items():
            lo, hi = self.ci[k]
            lines.append(f"  {k:<14} {v:>10.5g}   [{lo:.5g}, {hi:.5g}]")
        lines.append("rms residual: " + ", ".join(f"{k} {v:.3g} {signal_unit(k)}".rstrip()
                                                  for k, v in self.rmse.items()))
        if math.isfinite(self.period_error):
            lines.append(f"period: measured {self.period_measured:.4g} s, simulated "
                         f"{self.period_simulated:.4g} s, error {self.period_error:+.3g} s")
        note = self.extras.get("intervals", {}).get("note")
        if note:
            lines.append(f"intervals: {note}")
        if self.start_state is not None:
            lines.append(f"start: {self.start_state.describe()}")
        if not self.success:
            lines.append(f"warning: {self.unconverged()}")
        return "\n".join(lines)

    def stopped_on_budget(self) -> bool:
        """Whether the fit stopped on its simulation budget before converging."""
        return not self.success and self.on_budget

    def unconverged(self) -> str:
        """Why the estimates are not at an optimum ('' when the fit converged): a fit
        stopped on its simulation budget reports where it stopped, and its intervals
        are not confidence intervals of the best fit."""
        if self.success:
            return ""
        why = "on its budget" if self.stopped_on_budget() else f"({self.message})"
        remedy = ("fix one of the parameters the record does not determine (above): along "
                  "them the fit wanders without converging"
                  if self.extras.get("intervals", {}).get("undetermined")
                  else "raise --max-nfev (max_nfev) or start nearer")
        return (f"the fit stopped {why} after {self.nfev} simulations, before converging: "
                f"the estimates and intervals are where it stopped, not at the best fit; "
                f"{remedy}")


def _rms(v) -> float:
    """rms of the finite values of ``v``; NaN when there are none."""
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v ** 2))) if v.size else float("nan")


def phase_of(t, y, level=None):
    """Oscillation phase in [0, 1) of each time from the rising crossings of ``y``."""
    from ...engine.oscillation import rising_crossings
    from .data import crossing_band

    if level is None:
        level = 0.5 * (np.min(y) + np.max(y))
    rises = rising_crossings(t, y, level, crossing_band(y))
    phase = np.full(len(t), np.nan)
    for a, b in zip(rises[:-1], rises[1:]):
        inside = (t >= a) & (t < b)
        phase[inside] = (t[inside] - a) / (b - a)
    return phase


def fit_trace(build: Callable, data, params: dict, *, fixed: dict | None = None, signals=None,
              node: str | None = None, window=None, effects=(), max_nfev: int = 40,
              confidence: float = 0.95, phase_bins: int = 20, start: str = "ic",
              features: bool = True, diff_step: float = DIFF_STEP, options: dict | None = None,
              pool=None, x_start: dict | None = None, where: str | None = None,
              align: bool = True, start_state="auto",
              time_offset: float | None = None, refined: bool = True,
              clock_starts: bool | None = None, thin: bool = False,
              give_up_rms: float | None = None,
              converged_jac: np.ndarray | None = None) -> TraceFit:
    """Estimate ``params`` ({name: (guess, low, high)}) so the circuit reproduces ``data``.

    ``build(point) -> Circuit`` (or a :class:`~pneunet.netlist.builder.NetlistBuilder`)
    with ``fixed`` values for the other parameters; ``signals``: recorded columns to fit
    (default: all); ``node``: the node whose period is compared (default: the first
    pressure signal); ``window`` = (t0, t1) the fitted samples; ``effects``: circuit
    effects added (their parameters may appear in ``params``); ``options``: simulator
    options (default :data:`~pneunet.truth.circuits.model.FIT_OPTIONS`); ``max_nfev``: cap on
    the simulations of the least-squares stage (Jacobian included), raised in proportion
    for the start state's fitted initial pressures; ``pool``: an
    executor for the Jacobian's columns; ``x_start``: starting values (skips the
    cycle stage); ``align``: compare an oscillating record cycle by cycle, each
    simulated cycle started at its own crossing (:mod:`pneunet.truth.circuits.align`), for a
    circuit that oscillates on its own (a driven one is compared on the record's time
    axis); ``start_state``: the circuit's state at the first sample, 'auto', 'rest',
    'record', 'settled' or a :class:`~pneunet.truth.circuits.initial_state.StartState`
    (:mod:`pneunet.truth.circuits.initial_state`; fitted initial pressures ``p0@NODE`` join the
    estimates); ``time_offset``: netlist time of the first sample (s; default: the
    file's first time stamp for a driven circuit, else 0; where the record shows the
    file's clock misplaces periodic sources, the phase it shows, then fitted with the
    parameters: :func:`~pneunet.truth.circuits.clock.fit_clock`, from several starts
    unless ``clock_starts`` is False (default: unless ``start_state`` is a StartState));
    ``thin``: for a circuit that oscillates on its own, fit one sample in as many as
    :func:`~pneunet.truth.circuits.align.thinning` says, as a diagnosis does, with a note
    in the intervals' note (default: every sample; thinned, the Fig. 12 rig with a slow
    muscle at 40 Hz, on one sample in 3, ended 0.74 % off its tank volume at rms 0.322
    kPa for 0.3 of noise, on every sample 0.41 % at 0.307); ``give_up_rms``: an rms
    (in the fit's unit) the fit is of use only below: an
    :class:`~pneunet.truth.core.lsq.Abandoned` is raised where, at its pace, its budget
    would not bring it there (:func:`~pneunet.truth.core.lsq.least_squares_log`);
    ``converged_jac``: with ``refined``, ``x_start`` and ``start_state``, the Jacobian
    (``extras['jacobian']``) of a fit that converged there: it is refined from that
    point without being fitted again (:func:`_converged_at`).
    A driven record whose first samples are off rest, after its sources began to
    change, is fitted from them and from the netlist's rest state driven by its sources
    up to the first sample (:func:`~pneunet.truth.circuits.driven_start.better_start`;
    the latter again where the record shows another netlist time at its fitted values:
    :func:`~pneunet.truth.circuits.driven_start.clock_at_fit`).

    Two stages: with ``features`` and an oscillating record at ``node``, starting
    values from the cycle (:mod:`pneunet.truth.circuits.start`); then Levenberg–Marquardt on
    the samples in ln-parameters.  Signals are compared in kPa when all are pressures,
    else each in units of its own noise (:func:`residual_scales`).
    """
    arguments = dict(locals())  # this call's own, for the fit from a second start
    from ...netlist.builder import require_builder
    from .start import _feature_fit, initial_values

    require_builder(build, "fit_trace")
    wall = time.perf_counter()
    df = read_trace(data, signals)
    where = where or df.attrs["source"]
    cols = [c for c in df.columns if c != "time_s"]
    sigs = [signal_of_column(c) for c in cols]
    times, meas, mask = _samples(df, sigs, cols, window, where)
    for k in params:
        g, lo, hi = params[k]
        if not 0 < lo <= g <= hi:
            raise ParameterError(f"fit parameter {k}: need 0 < low ≤ guess ≤ high, got {params[k]}")
    model = TraceModel(build, fixed, effects, start, FIT_OPTIONS if options is None else options)
    guess = {k: v[0] for k, v in params.items()}
    if isinstance(start_state, StartState):  # its fitted p0@NODE are not netlist parameters
        model = model.with_state(start_state)
    check_signals(model, guess, cols, where)
    state = start_state if isinstance(start_state, StartState) else choose_start(
        model, guess, df, start_state, time_offset, where)
    if start_state == "auto" and state.mode == "record" and state.driven \
            and state.time_offset > 0:  # the sources' history before the first sample
        again = {k: v for k, v in arguments.items()
                 if k not in ("build", "data", "params", "start_state")}
        again.update(where=where, clock_starts=True)
        try:  # a rest start that cannot be found or fitted leaves the record's alone
            rest = choose_start(model, guess, df, "rest", time_offset, where)
            if rest.settle > 0:
                rest = fit_trace(build, df, params, start_state=replace(rest, reason=(
                    "the netlist's rest state driven by its sources to the first sample")),
                    **again)
                if time_offset is None:
                    rest = clock_at_fit(rest, model, df, where, lambda st, x: fit_trace(
                        build, df, params, start_state=st, **{**again, "x_start": x}))
        except PneunetError:
            rest = None
        if isinstance(rest, TraceFit):
            return better_start(rest, fit_trace(build, df, params, start_state=state,
                                                **again))
    node = node or next((s[2:] for s in sigs if s.startswith("p_")), None)
    thin_note = None
    every = 1
    if thin and not state.driven and node:
        df, every, thin_note = thinned(df, node, diff_step)
        times, meas, mask = _samples(df, sigs, cols, window, where)
    settle_until = settling_time(state, times, meas.get(f"p_{node}"),
                                 2 if not state.driven and unset_storage(model, guess, meas)
                                 else 1)
    if settle_until > 0:  # a recorded node's first value is not compared: not fitted
        state = replace(state, fitted={k: v for k, v in state.fitted.items()
                                       if f"p_{k[len(P0_PREFIX):]}" not in meas})
    model = model.with_state(state)
    params = {**params, **{k: v for k, v in state.fitted.items() if k not in params}}
    names = list(params)
    x0 = np.log([params[k][0] for k in names])
    lb = np.log([params[k][1] for k in names])
    ub = np.log([params[k][2] for k in names])
    keep_all = compared_masks(model, guess, meas, autonomous=not state.driven)
    unit, scales = residual_scales(meas, keep_all)
    t_fit = times[mask]
    aligned = None
    if align and not state.driven and node and f"p_{node}" in meas:
        aligned = Alignment.of(times, meas[f"p_{node}"], f"p_{node}")
    if settle_until > 0:  # states the record cannot give settle before they are compared
        keep_all = {s: k & (times >= settle_until) for s, k in keep_all.items()}
    clock_step = clock_unit(state, times)
    fun = TraceResidual(model, names, t_fit, sigs, {s: meas[s][mask] for s in sigs},
                        {s: keep_all[s][mask] for s in sigs}, scales, aligned, clock_step)
    if fun.size() <= len(names) + bool(clock_step):
        raise DataError(
            f"{fun.size()} samples compared in the fit window for "
            f"{len(names) + bool(clock_step)} parameters"
            + (f" (the states the record cannot give settle until {settle_until:.4g} s)"
               if settle_until > 0 else ""), where=where,
            hint="fit a longer window (--train-fraction) or record longer")
    stage1 = None
    if x_start is not None:
        x0 = np.clip(np.log([x_start.get(k, params[k][0]) for k in names]), lb, ub)
        stage1 = {"method": "given"}
    elif features and node and f"p_{node}" in meas and swings(meas[f"p_{node}"][mask]):
        try:
            x0, stage1 = initial_values(model, names, x0, lb, ub, t_fit, meas[f"p_{node}"][mask],
                                        node)
        except PneunetError as err:
            stage1 = {"method": "none", "error": str(err)}
        if stage1 is None or stage1.get("method") == "none":
            x0, stage1 = _feature_fit(model, names, x0, lb, ub, t_fit, meas[f"p_{node}"][mask],
                                      node, max_nfev)
    if clock_step:  # the clock's shift, in sample spacings, within half a period
        half = 0.5 * state.clock_period / clock_step
        x0, lb, ub = np.append(x0, 0.0), np.append(lb, -half), np.append(ub, half)
    calls0 = model.calls
    # each initial pressure fitted costs a Jacobian column per step: it adds its share
    own = len(names) - sum(k in state.fitted for k in names)
    max_nfev = math.ceil(max_nfev * len(names) / max(own, 1))
    res = _converged_at(fun, x0, converged_jac) if refined and x_start is not None else None
    if res is None:
        res = least_squares_log(fun, x0, lb, ub, max_nfev=max_nfev, diff_step=diff_step,
                                pool=pool, give_up=None if give_up_rms is None
                                else give_up_rms ** 2 * fun.size())
        if clock_step:
            res = fit_clock(res, fun, x0, lb, ub, model, df, state,
                            not isinstance(start_state, StartState) if clock_starts is None
                            else clock_starts, max_nfev=max_nfev,
                            diff_step=diff_step, pool=pool)
    if refined and res.success:
        res, fun, model = refine_fit(res, fun, lb, ub, max_nfev, pool)
        diff_step = REFINE_DIFF_STEP if model.options == REFINE_OPTIONS else diff_step
    jac, spread, checked, cliffs = jacobian_spread(res, fun, lb, ub, diff_step, pool)
    jac, spread, secants, measured = secant_checked(fun, res, jac, spread, lb, ub, pool)
    res = replace(res, nfev=res.nfev + checked + secants, jac=jac)
    est = dict(zip(names, np.exp(res.x[:len(names)])))
    groups = np.concatenate([np.full(int(fun.keep[s].sum()), i) for i, s in enumerate(sigs)])
    ci, se, info = intervals(res.x, res.jac, res.fun, names + [CLOCK] * bool(clock_step),
                             groups=groups, confidence=confidence, spread=spread)
    named = names + [CLOCK] * bool(clock_step)
    if thin_note:
        info["thinned_note"] = thin_note
        info["note"] += "; " + thin_note
    if measured:
        info["secant_note"] = secant_note(measured, named, diff_step)
        info["note"] += "; " + info["secant_note"]
    if cliffs:
        info["cliff_note"] = (
            f"{', '.join(named[i] for i in cliffs)}: a difference step ({diff_step:.2g} in "
            "ln value) to one side changes the fit abruptly (the circuit behaves otherwise "
            "there: an oscillation stops, a valve switches on another cycle): its "
            "derivative is the other side's, and its interval does not hold across that edge")
        info["note"] += "; " + info["cliff_note"]
    if clock_step:
        state = clock_fitted(state, res.x[-1], ci.pop(CLOCK), clock_step)
        se.pop(CLOCK)
        model = model.with_state(state)
    n = len(names)
    bounded = at_bounds(names, res.x[:n], lb[:n], ub[:n])
    if bounded:
        info["at_bound"] = bounded
        info["at_bound_note"] = "; ".join(
            f"{k} stopped at its {side} bound {v:.4g} (the recording wants it beyond "
            "the range given, or the model lacks something): its interval is not a "
            "confidence interval" for k, side, v in bounded)
        info["note"] += "; " + info["at_bound_note"]
    import pandas as pd

    sim, sol = model.sample(est, times, sigs, aligned)
    ref = meas[f"p_{node}"] if node and f"p_{node}" in meas else meas[sigs[0]]
    phase = phase_of(times, ref)
    resid = {s: np.where(keep_all[s], sim[s] - meas[s], np.nan) for s in sigs}
    frame = pd.DataFrame({"time_s": times, "phase": phase, "fitted": mask, **resid})
    rmse = {s: float(np.sqrt(np.nanmean(resid[s][mask] ** 2))) for s in sigs}
    from ..core.locate import phase_profile

    rows = {"phase": None}
    for s in sigs:
        centre, rms = phase_profile(phase[mask], resid[s][mask], phase_bins)
        rows["phase"], rows[s] = centre, rms
    phase_rms = pd.DataFrame(rows)
    pm, ps, perr = period_error(times, ref, sol, node, mask, model.first_time)
    nfev = calls0 + res.nfev
    return TraceFit(est, ci, se, rmse, frame, phase_rms, pm, ps, perr, float(info["s"]),
                    int(nfev), res.success,
                    res.message + (f"; {fun.failures} failed simulations" if fun.failures else ""),
                    tuple(effects), sol, time.perf_counter() - wall, unit, scales,
                    {"stage1": stage1, "simulations": nfev, "intervals": info,
                     "alignment": aligned, "start_state": state,
                     # a fitted clock's column last (its shift, per sample spacing)
                     "jacobian": res.jac, "clock_step": clock_step,
                     "model": model, "recording": where,
                     "compared": {s: int(keep_all[s].sum()) for s in sigs},
                     "keep": keep_all,
                     "compared_from_s": settle_until, "fitted_every_nth_sample": every},
                    on_budget=res.on_budget)


def _samples(df, sigs, cols, window, where):
    """(times, {signal: values}, mask of the fit ``window``) of a recording ``df``; a
    DataError with fewer than 5 samples in the window."""
    times = df["time_s"].to_numpy()
    meas = {s: df[c].to_numpy() for s, c in zip(sigs, cols)}
    mask = np.ones(len(times), bool)
    if window is not None:
        mask = (times >= window[0]) & (times <= window[1])
    if mask.sum() < 5:
        raise DataError("fewer than 5 samples in the fit window", where=where)
    return times, meas, mask


#: the message of a fit taken as converged from an earlier fit (:func:`_converged_at`)
CONVERGED_BEFORE = "converged in the fit it refines"


def _converged_at(fun: TraceResidual, x, jac) -> LsqResult | None:
    """The least-squares result of a fit that converged at ``x`` with Jacobian ``jac``
    (its columns ``fun``'s parameters, a clock's shift last): ``fun`` evaluated there
    once, where LM from ``x`` would spend a Jacobian and a step to stay (the oscillator's
    polytropic fit: 11 simulations, 1 s of a diagnosis).  None without ``jac``, when its
    shape does not match or the simulation fails."""
    if jac is None or jac.shape != (fun.size(), len(x)):
        return None
    failures = fun.failures
    r = fun(x)
    if fun.failures > failures or not np.all(np.isfinite(r)):
        return None
    return LsqResult(np.array(x, float), r, np.array(jac, float), 1, True, CONVERGED_BEFORE)


def refine_fit(res, fun: TraceResidual, lb, ub, max_nfev: int, pool):
    """(result, residual, model) of a converged fit ``res`` of ``fun`` refined
    (:func:`~pneunet.truth.core.lsq.refine`: simulated with :data:`~pneunet.truth.circuits.
    model.REFINE_OPTIONS`, differences of :data:`~pneunet.truth.circuits.model.
    REFINE_DIFF_STEP`, until its step is a fraction of its smallest standard error), or
    the fit as it is when its stopping radius was already that fine.  The simulations
    of both count."""
    model = fun.model.with_options(REFINE_OPTIONS)
    finer = fun.with_model(model)
    again = refine(finer, res, lb, ub, max_nfev=max_nfev, diff_step=REFINE_DIFF_STEP,
                   pool=pool)
    if again is None:
        return res, fun, fun.model
    return replace(again, nfev=res.nfev + again.nfev), finer, model


def compared_masks(model: TraceModel, values: dict, measured: dict,
                   autonomous: bool = True) -> dict:
    """{signal: samples compared}: every sample of a pressure at a node the netlist gives
    a volume (its edges, however fast, are the model's to follow: they tell a resistance
    from a volume); elsewhere all but those around a recorded jump
    (:func:`~pneunet.truth.circuits.data.compared_samples`: an algebraic node jumps at a
    valve's fold, where a few ms of timing would decide the error).  In an
    ``autonomous`` circuit the model's own state decides when a valve switches, and a
    jump is left out whole however many samples a fast logger spreads it over
    (``whole_edges``); in one driven by its sources they decide it, and only a jump
    within a sample is left out: an edge spread over samples is compared (a dead volume
    between the amplifier's valves shows there: 6 mL spreads the junction's 50 kPa jump
    over two samples at 100 Hz).  Decided on the netlist without effects, so that every
    candidate is compared on the same samples."""
    from ...engine.assembly import CircuitDAE

    circuit = model.base_circuit(values)
    circuit.options = circuit.options.replace(dead_volume=0.0)
    stored = set(CircuitDAE(circuit).stored_pressure_nodes)
    return {s: np.ones(len(y), bool) if s.startswith("p_") and s[2:] in stored
            else compared_samples(y, whole_edges=autonomous) for s, y in measured.items()}


#: a fitted value this close to a bound of its range (in ln value: 1 %) stopped there
BOUND_TOL = 0.01


def near_bound(v: float, lo: float, hi: float) -> str:
    """'lower' or 'upper' when ``v`` lies within :data:`BOUND_TOL` of that bound of
    (``lo``, ``hi``), else ''."""
    if abs(math.log(v / lo)) < BOUND_TOL:
        return "lower"
    return "upper" if abs(math.log(hi / v)) < BOUND_TOL else ""


def at_bounds(names, x, lb, ub) -> list[tuple]:
    """(name, 'lower'/'upper', bound) of each parameter that stopped at a bound of its
    range (:func:`near_bound`); ``x``, ``lb``, ``ub`` are ln values, the bound is not."""
    out = []
    for k, v, lo, hi in zip(names, np.exp(x), np.exp(lb), np.exp(ub)):
        side = near_bound(v, lo, hi)
        if side:
            out.append((k, side, float(lo if side == "lower" else hi)))
    return out


def settling_time(state, times, y, cycles: int = 1) -> float:
    """Time of the record (s) from which a fit started from the record's state compares
    it: the ``cycles``-th rising mid-level crossing of the cycle node ``y`` (an
    oscillating record; the last one where it shows fewer), when the unrecorded states
    that the start had to guess have settled; 0 for another start, or a record that does
    not oscillate."""
    from .data import oscillates, rising_crossings

    if state.mode != "record" or y is None or not oscillates(times, y):
        return 0.0
    starts = rising_crossings(times, y)
    return float(starts[min(cycles, len(starts)) - 1])


def unset_storage(model, values: dict, measured: dict) -> list:
    """Storage nodes that ``model``'s effects add and the record does not show (a gas
    temperature, a tube's inner pressure): a start from the record guesses them (the
    wall's temperature, a neighbour's pressure), so the fit of a circuit that
    oscillates on its own compares the record from the second cycle start, one whole
    cycle later.  From the first, a mid-run record of the oscillator's heat exchange
    ended 1.18× the noise floor with R_out's interval missing the truth; from the
    second, 0.94×, every interval covering.  A driven circuit's cycle is its sources'
    period, often a large part of the record (the inverter chain's: 4 s of a 10 s fit
    window, without which its control-line tube was not found: 26.5× the floor against
    1.04×)."""
    from ...engine.assembly import CircuitDAE

    if not model.effects:
        return []
    circuit = model.circuit(values)
    old = set(model.base_circuit(values).nodes)
    return [n for n in CircuitDAE(circuit).stored_pressure_nodes
            if n not in old and f"p_{n}" not in measured]


#: the pooled unit of signals in different units: each signal's residual divided by its
#: own noise (robust fourth differences of the recorded column)
NOISE_UNIT = "× noise"


def residual_scales(measured: dict, keep: dict) -> tuple[str, dict]:
    """(unit, {signal: divisor}) of the compared residuals: kPa when every signal is a
    pressure, else each signal in units of its own noise (σ of its recorded column's
    fourth differences over the compared runs, :func:`~pneunet.truth.core.noise.record_sigma`;
    where a column shows none, 1e-6 of its range), so that a contraction in mm and a
    pressure in kPa weigh as their noise says."""
    if all(s.startswith("p_") for s in measured):
        return "kPa", dict.fromkeys(measured, 1.0)
    scales = {}
    for s, y in measured.items():
        sigma = record_sigma(y, segments(keep[s]))
        floor = 1e-6 * max(float(np.ptp(y)), 1e-12)
        scales[s] = sigma if math.isfinite(sigma) and sigma > floor else floor
    return NOISE_UNIT, scales


def check_signals(model: TraceModel, values: dict, columns, where: str) -> None:
    """DataError when a recorded column names a node or element the circuit lacks, or a
    signal its element does not have (listing the columns ``pneunet run`` would write)."""
    from ...engine.solution import column_name

    c = model.circuit(values)
    nodes, elements = set(c.nodes), set(c.elements)
    others = []
    for col in columns:
        sig = signal_of_column(col)
        if sig.startswith("p_") and sig[2:] not in nodes:
            raise DataError(f"column {col}: the circuit has no node {sig[2:]!r}", where=where,
                            hint="nodes: " + ", ".join(sorted(nodes)) + "; rename the column "
                                 "or leave it out with --signal")
        if sig.startswith("mdot_") and sig[5:] not in elements:
            raise DataError(f"column {col}: the circuit has no element {sig[5:]!r}",
                            where=where, hint="elements: " + ", ".join(sorted(elements)))
        if not sig.startswith(("p_", "mdot_")):
            others.append(col)
    if not others:
        return
    import warnings

    with warnings.catch_warnings():  # a probe of a few steps: nothing worth a warning
        warnings.simplefilter("ignore")
        sol = c.tran(SIGNAL_PROBE_S)  # which signals the circuit's elements write
    has = {column_name(k, u) for k, u in sol.units.items()}
    for col in others:
        if col not in has:
            quantity, _, element = signal_of_column(col).partition("_")
            what = (f"element {element} has no {quantity} signal" if element in elements
                    else f"the circuit has no element {element!r}")
            raise DataError(f"column {col}: {what}", where=where,
                            hint="signals of this circuit besides pressures and flows: "
                                 + (", ".join(sorted(h for h in has if not h.startswith(
                                     ("p_", "mdot_")))) or "none"))


#: simulated time (s) of the probe that lists a circuit's signals
SIGNAL_PROBE_S = 1e-3


def period_error(times, ref, sol, node, mask, first_time: float = 0.0):
    """(measured, simulated, simulated − measured) period at ``node`` in ``mask``, s
    (``first_time``: the netlist time of the first sample)."""
    from ...engine.oscillation import analyze_oscillation
    from .data import crossing_band
    from .start import cycle_features

    w = mask
    try:
        m = analyze_oscillation(times[w], ref[w], band=crossing_band(ref[w]))
        sim_t = sol.t - first_time
        inside = (sim_t >= times[w][0]) & (sim_t <= times[w][-1])
        s = analyze_oscillation(sim_t[inside], sol.pressure(node)[inside]) if node else m
        if m.oscillating and s.oscillating:
            return m.period_s, s.period_s, s.period_s - m.period_s
        fm = cycle_features(times[w], ref[w])
        fs = cycle_features(sim_t[inside], sol.pressure(node)[inside],
                            fm["levels"] if fm else None) if node else None
        if fm and fs:
            return fm["period"], fs["period"], fs["period"] - fm["period"]
        return m.period_s, s.period_s, float("nan")
    except PneunetError:
        return float("nan"), float("nan"), float("nan")


__all__ = ["TraceFit", "fit_trace", "phase_of", "period_error", "check_signals", "sample_at"]
