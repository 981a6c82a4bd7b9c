"""The full fits of a circuit diagnosis' candidate effects, after the screen
(:mod:`pneunet.truth.circuits.screen`): the most promising singles from their screen
points, more where the screen cannot tell them apart, second starts, a second effect
on top of the best single, and parsimony (of singles that fit alike, the one with
fewest parameters; the best single again from a pair's values, the base model again
from the best model's values).  Used by
:func:`~pneunet.truth.circuits.diagnosis.diagnose_trace`."""
from __future__ import annotations

import math

import numpy as np

from ...common.errors import DataError, SolverError
from ..core.lsq import Abandoned
from ..core.verdict import Step, at_floor, indistinguishable, step_tolerance
from .clock import CLOCK_NUDGES, SHIFT, clock_moved, clock_unit
from .data import compared_samples, signal_of_column
from .fit import TraceFit, fit_trace, near_bound
from .screen import SCREEN_KEEP, screen_candidates, step_starts


class CandidateFits:
    """The full fits of candidate effects within one diagnosis (each from given starting
    values: the screen's best point, or a second start, the effect's own guess or its
    range's log-middle); pairs started from each single fit's own values."""

    def __init__(self, build, df, params, fixed, node, train, test, base, pool, options,
                 where, state, floor, tolerance):
        self.build, self.df, self.params, self.fixed, self.node = build, df, params, fixed, node
        self.train, self.test, self.base, self.pool, self.options = train, test, base, pool, options
        self.where, self.state, self.floor, self.tolerance = where, state, floor, tolerance
        self.failed = {}  # effect name -> why it has no fit
        self.starts = {}  # effect name -> [{start values, held-out rms, simulations}]
        #: the screen's (names, Jacobian, model arguments, data), once it has run
        self.screen_setup = None
        self.screen_simulations = 0  # simulations of second starts' and second effects' screens

    def _fit(self, effs, x_start, max_nfev, refined=False, state=None, give_up_rms=None,
             converged_jac=None):
        p = {k: (float(np.clip(self.base.values[k], lo, hi)), lo, hi)
             for k, (_, lo, hi) in self.params.items()}
        for e in effs:
            p.update(e.params)
        x = self.base_start()
        x.update(x_start)
        for k in p:
            x.setdefault(k, p[k][0])
        state = state or self.state
        if x.get(SHIFT):  # a screen point's clock, moved from its fit's
            state = clock_moved(state, x.pop(SHIFT),
                                clock_unit(state, self.df["time_s"].to_numpy(float)))
        return fit_trace(self.build, self.df, p, fixed=self.fixed, node=self.node,
                         window=self.train, effects=effs, max_nfev=max_nfev, pool=self.pool,
                         options=self.options, x_start=x, where=self.where,
                         start_state=state, refined=refined, give_up_rms=give_up_rms,
                         converged_jac=converged_jac)

    def refined(self, fit: TraceFit, max_nfev: int) -> TraceFit:
        """``fit`` refined (:func:`~pneunet.truth.circuits.fit.refine_fit`) from its
        values: from its Jacobian there where it converged, else fitted again first; a
        SolverError when that fails."""
        converged = fit.success and not fit.on_budget
        return self._fit(fit.effects, dict(fit.values), max_nfev, refined=True,
                         state=fit.start_state,
                         converged_jac=fit.extras.get("jacobian") if converged else None)

    def base_start(self, guesses: bool = False) -> dict:
        """Starting values of the base parameters: the base fit's, except where it
        stopped at a bound of its range (a base model bent to mimic missing physics),
        or everywhere with ``guesses``: the user's guesses."""
        out = {}
        for k, (guess, lo, hi) in self.params.items():
            v = self.base.values[k]
            out[k] = guess if guesses or near_bound(v, lo, hi) else v
        return out

    def second_start(self, row) -> dict:
        """Start values of the second fit of a screened candidate (``row``): the base
        parameters at the user's guesses and the effect's grid point that fits best
        from there (its screen again, anchored at the guesses; not zoomed in on as the
        first start is: another kind of start, the inverter chain's control-line tube
        reaches the floor only from its grid point, from the zoomed one it stops at
        10× the floor): a base fit bent to
        mimic the missing effect misranks the effect's points (the inverter chain's
        control-line tube: from the bent fit its smallest point ranks first, from the
        guesses the one nearest the truth).  Without a screen, or where it fails, the
        effect's guess or its range's log-middle (:func:`_second_start`)."""
        eff = row["effect"]
        guesses = self.base_start(guesses=True)
        if self.screen_setup is not None:
            names, jac, model_args, data = self.screen_setup
            x_guess = np.log([guesses[k] for k in names])
            again = screen_candidates([eff], names, x_guess, jac, self.params, model_args,
                                      data, self.pool)[0]
            self.screen_simulations += again["simulations"]
            if math.isfinite(again["rss"]):
                return dict(again["x"])
        return {**guesses, **{k: _second_start(v, row["x"].get(k))
                              for k, v in eff.params.items()}}

    def reached(self, fits) -> bool:
        """Whether a fitted candidate in ``fits`` reaches the noise floor."""
        return any(self.at_floor(f) for n, f in fits.items() if n != "none")

    def step(self, label: str, fit, effects=()) -> Step:
        """The waterfall step of ``fit``: its held-out error and its fitted window's."""
        return Step(label, fit.error(self.test), effects=tuple(effects),
                    train=fit.error(self.train))

    def score(self, fit) -> float:
        """What candidates are ranked and compared by: the larger of ``fit``'s held-out
        and fitted window's errors (:attr:`~pneunet.truth.core.verdict.Step.worst`; a
        held-out window that hardly moves, a relaxation tail, would rank a model that
        misses the fitted window first)."""
        return self.step("", fit).worst

    def at_floor(self, fit) -> bool:
        """Whether ``fit`` is at the noise floor on the held-out window and on its fitted
        one (as :func:`~pneunet.truth.core.verdict.decide` judges it: two effects on a
        record with nothing held out within :data:`~pneunet.truth.core.verdict.NEAR_FLOOR`:
        :func:`~pneunet.truth.core.verdict.step_tolerance`)."""
        return at_floor(self.score(fit), self.floor,
                        step_tolerance(fit.effects, self.tolerance, self.train == self.test))

    def start(self, eff, x_start, max_nfev, kind: str, state=None,
              give_up_rms=None) -> TraceFit | Abandoned | None:
        """The fit of ``eff`` (None: the base model) from ``x_start`` (its parameters;
        the base ones from the base fit's or the screen's) and ``state`` (the start state
        of the fit ``x_start`` comes from, its fitted clock; default the base fit's);
        None (and why in ``failed``) when it fails; the
        :class:`~pneunet.truth.core.lsq.Abandoned` where it cannot reach ``give_up_rms``
        (:func:`~pneunet.truth.circuits.fit.fit_trace`).  Every start is listed in
        ``starts``, with ``kind`` (where it started: 'screen point', 'second start',
        'continued', …)."""
        name = "none" if eff is None else eff.name
        row = {"kind": kind,
               "start": {k: float(x_start[k]) for k in (eff or self).params if k in x_start}}
        try:
            fit = self._fit(() if eff is None else (eff,), x_start, max_nfev, state=state,
                            give_up_rms=give_up_rms)
        except (SolverError, DataError) as err:
            self.failed.setdefault(name, f"fit failed: {err}")
            return None
        except Abandoned as gave_up:
            self.starts.setdefault(name, []).append(
                dict(row, held_out_rms=None, simulations=gave_up.nfev, converged=False,
                     abandoned=True))
            return gave_up
        self.starts.setdefault(name, []).append(
            dict(row, held_out_rms=fit.error(self.test),
                 simulations=fit.extras.get("simulations"), converged=fit.success))
        return fit

    def pair(self, effects, x_start, max_nfev, notes, state=None) -> TraceFit | None:
        """Two effects at once from ``x_start`` (a single fit's own values and the
        second's start, never values a failed fit left at a bound) and ``state`` (that
        fit's start state); None (and why in ``notes``) when it fails."""
        try:
            return self._fit(effects, x_start, max_nfev, state=state)
        except (SolverError, DataError) as err:
            notes.append(f"{' + '.join(e.name for e in effects)}: fit failed: {err}")
            return None


def fit_screened(rows, fits, fitting, screen, max_nfev, say) -> None:
    """Fit the screened candidates ``rows`` (best first) into ``fits``: the best and the
    next ones (``screen``: at most that many) within :data:`SCREEN_KEEP` of its merit,
    each from its screen's best point moved by one Gauss–Newton step; the second best
    whatever its merit when none of them reaches the floor (the screen misranks: a
    control-line tube screened 1.5× worse in rms than a dead volume that missed the
    floor, and only the tube's full fit reached it).  When none
    reaches the floor, the next candidates the screen cannot tell from the best (merit
    within :data:`SCREEN_KEEP`), in its order, until one does: around a base fit bent
    far by the missing effect, the screen's linearisation ranks the right one anywhere
    (heat exchange in one of the inverter chain's volumes: 11th of 13, every merit
    within 7 %).  Then a second start for each of the first round, best first, and for
    each later one whose fit stayed in the base fit's valley (:data:`STAYED`); then the
    best fit, if its budget stopped it, continued (:func:`continue_stopped`)."""
    best_rss = rows[0]["rss"]
    close = rows[:min(1, screen)] + [r for r in rows[1:screen] if r["rss"] <= SCREEN_KEEP * best_rss]
    step_starts(close, fitting.pool)
    for row in close:
        _fit_row(row, fits, fitting, max_nfev, say)
    if len(close) < min(2, screen, len(rows)) and not fitting.reached(fits):  # the second
        close.append(rows[len(close)])
        step_starts(close[-1:], fitting.pool)
        _fit_row(close[-1], fits, fitting, max_nfev, say)
    close = _replace_failed(rows, close, fits, fitting, max_nfev, say)
    more = [r for r in rows[len(close):] if r["rss"] <= SCREEN_KEEP * best_rss]
    for row in more:
        if fitting.reached(fits):
            break
        step_starts([row], fitting.pool)
        _fit_row(row, fits, fitting, max_nfev, say)
    if not fitting.reached(fits):
        _second_starts(rows, close, fits, fitting, max_nfev, say)
    continue_stopped(fits, fitting, max_nfev, say)
    clock_restarts(fits, fitting, max_nfev, say)


def _replace_failed(rows, close, fits, fitting, max_nfev, say) -> list:
    """``close`` (the first rows of ``rows``, fitted) extended, for each of them whose
    fit failed, by the next row in the screen's order, fitted, until as many fits stand
    as ``close`` has rows: a candidate that cannot be fitted takes no place from one
    that can (a 400 mL oscillator with 16 s cycles recorded for 40 s: the screen ranked
    two tubes and heat exchange first, whose added states settle only after the fit
    window, and screened out the hidden dead volume, which a full fit brings to the
    floor)."""
    wanted = len(close)
    close = list(close)
    for row in rows[len(close):]:
        if sum(r["effect"].name in fits for r in close) >= wanted:
            break
        step_starts([row], fitting.pool)
        _fit_row(row, fits, fitting, max_nfev, say)
        close.append(row)
    return close


def _second_starts(rows, close, fits, fitting, max_nfev, say) -> None:
    """A second start (:meth:`CandidateFits.second_start`: every base parameter at the
    user's guess) for each of the first round ``close``, and for each later fitted row
    whose fit stayed in the base fit's valley (:data:`STAYED`), in the screen's order,
    until one reaches the floor."""
    base = fitting.score(fitting.base)
    stayed = [r for r in rows[len(close):] if r["effect"].name in fits
              and fitting.score(fits[r["effect"].name]) >= STAYED * base]
    for row in close + stayed:
        eff = row["effect"]
        if eff.name not in fits and eff.name not in fitting.failed:
            continue
        say(f"fitting {eff.name} from a second start")
        fit = fitting.start(eff, fitting.second_start(row), max_nfev, "second start")
        if fit is not None and (eff.name not in fits or fitting.score(fit)
                                < fitting.score(fits[eff.name])):
            fits[eff.name] = fit
            fitting.failed.pop(eff.name, None)
        if fitting.reached(fits):
            break


#: a candidate whose fit from its screen point ends with a held-out error at least this
#: fraction of the base fit's stayed in the base fit's valley (it tested nothing): it is
#: fitted again from a second start, whatever its screen rank
STAYED = 0.9
#: how many times the best candidate's fit, stopped on its budget, is continued
CONTINUATIONS = 2


def continue_stopped(fits, fitting, max_nfev, say) -> None:
    """The best fitted candidate, if its fit stopped on its budget while improving on the
    base model, continued from where it stopped (at most :data:`CONTINUATIONS` times,
    while that lowers its cost on the fit window): neither the verdict nor the intervals
    are decided where a budget stopped a fit.  A tube whose R and V trade along R·V needs
    about 300 simulations from its second start, twice its budget."""
    for _ in range(CONTINUATIONS):
        name = min((n for n in fits if n != "none"), key=lambda n: fitting.score(fits[n]),
                   default=None)
        if name is None or not fits[name].stopped_on_budget() \
                or fitting.score(fits[name]) >= fitting.score(fitting.base):
            return
        last = fits[name]
        say(f"fitting {name} on from where its budget stopped it")
        again = fitting.start(last.effects[0], dict(last.values), max_nfev, "continued",
                              last.start_state)
        if again is None or again.error() >= last.error():
            return
        fits[name] = again


def clock_restarts(fits, fitting, max_nfev, say) -> None:
    """The best fitted candidate, when it fitted the logger's clock with the parameters
    and stopped above the floor while improving on the base model, fitted again from its
    values with the clock moved by each of
    :data:`~pneunet.truth.circuits.clock.CLOCK_NUDGES` sample spacings; the lowest cost
    on the fit window is kept.  An edge sharper than a sample puts a kink in
    the misfit each time a sample crosses it, and LM stops a fraction of a sample from
    the clock's minimum (the inverter chain's control-line tube, recorded from 4.08 s on
    the logger's clock: 1.74× the floor; from its clock half a sample earlier, 1.03×,
    half a sample later 25×)."""
    name = min((n for n in fits if n != "none"), key=lambda n: fitting.score(fits[n]),
               default=None)
    if name is None or fitting.reached(fits) \
            or fitting.score(fits[name]) >= fitting.score(fitting.base):
        return
    first = fits[name]
    state = first.start_state
    if not state.clock_ci:
        return
    step = clock_unit(state, fitting.df["time_s"].to_numpy(float))
    for k in CLOCK_NUDGES:
        say(f"fitting {name} again with its clock moved {k:+g} sample spacings")
        again = fitting.start(first.effects[0], dict(first.values), max_nfev,
                              f"clock moved {k:+g} samples", clock_moved(state, k, step))
        if again is not None and again.error() < fits[name].error():
            fits[name] = again


def refine_final(fits, name, fitting, max_nfev, notes, say) -> bool:
    """The reported fit ``fits[name]`` (the accepted effects joined, or 'none') fitted
    again from its values and refined (:func:`~pneunet.truth.circuits.fit.refine_fit`:
    finer simulations, stopped within a fraction of its standard errors); True when it
    replaced the fit.  The other fits, which only rank the candidates, are not refined."""
    final = fits[name]
    say(f"refining {name}")
    try:
        again = fitting.refined(final, max_nfev)
    except SolverError as err:
        notes.append(f"{name}: not refined: {err}")
        return False
    fits[name] = again
    return True


def _fit_row(row, fits, fitting, max_nfev, say) -> None:
    """The full fit of one screened candidate from its screen's best point."""
    eff = row["effect"]
    if not math.isfinite(row["rss"]):
        fitting.failed[eff.name] = ("not fitted: the circuit could not be simulated at any "
                                    "point of its parameter range")
        return
    say(f"fitting {eff.name}")
    fit = fitting.start(eff, row["x"], max_nfev, "screen point")
    if fit is not None:
        fits[eff.name] = fit


def fit_limits(fits, cand, circuit, fitting, max_nfev, say) -> None:
    """Parsimony: each fitted single effect's simpler limits
    (:meth:`~pneunet.truth.circuits.effects.CircuitEffect.limits`, a tube's dead volume at
    its node) that are candidates not fitted yet, fitted from its values, for the ranking
    to take where the two fit alike (the limit has fewer parameters)."""
    by_name = {e.name: e for e in cand}
    for fit in [f for n, f in fits.items() if n != "none" and len(f.effects) == 1]:
        eff = fit.effects[0]
        for name, values in eff.limits(circuit, fit.values):
            if name not in by_name or name in fits:
                continue
            say(f"fitting {name} from {eff.name}'s values")
            start = {k: v for k, v in fit.values.items() if k in fitting.params}
            again = fitting.start(by_name[name], {**start, **values}, max_nfev,
                                  f"{eff.name}'s values", fit.start_state)
            if again is not None:
                fits[name] = again


def second_effects(fits, best, fitted, cand, params, fitting, model_setup, df, train, pool,
                    say):
    """Second effects to fit with ``best`` (a single effect that improved on the base
    model but did not reach the floor), each with its start values: the best of every
    other candidate screened again on top of ``best``'s fit (an effect the wrong base
    model hid: its screen ran around a base fit bent to mimic two effects), then the next
    single fit that did not stop at a bound, started from ``best``'s values."""
    first = fits[best]
    build, fixed, options, _ = model_setup
    names = list(first.values)
    p2 = {**params, **first.effects[0].params}
    others = [e for e in cand if e.name != best]
    out = []
    if others:
        say(f"screening {len(others)} candidate effects on top of {best}")
        typical = first.extras["model"].typical_s
        data, jac = screen_data(df, train, first)
        rows = screen_candidates(
            others, names, np.log([first.values[k] for k in names]), jac, p2,
            ((build, fixed), {"options": options, "typical_s": typical,
                              "state": first.start_state}),
            data, pool, on_top=first.effects)
        step_starts(rows[:1], pool)
        fitting.screen_simulations += sum(r["simulations"] for r in rows)
        if math.isfinite(rows[0]["rss"]):
            out.append((rows[0]["effect"], rows[0]["x"]))
    usable = [n for n in fitted[1:] if not at_bound(fits[n])]
    if usable and all(e.name != usable[0] for e, _ in out):
        e2 = fits[usable[0]].effects[0]
        out.append((e2, {**first.values, **{k: fits[usable[0]].values[k] for k in e2.params}}))
    return out


def fit_pairs(fits, best, seconds, steps, fitting, max_nfev, notes, say):
    """Fit ``best`` with each second effect of ``seconds`` in turn until a pair reaches
    the floor; the best pair so far is the waterfall's last step."""
    for nxt, x_start in seconds:
        say(f"fitting {best} + {nxt.name}")
        pair = fitting.pair((fits[best].effects[0], nxt), x_start, max_nfev, notes,
                            fits[best].start_state)
        name = f"{best} + {nxt.name}"
        if pair is not None and fitting.score(pair) < steps[-1].worst:
            pair = _continued_pair(pair, name, fitting, max_nfev, notes, say)
        if pair is None or (name in fits and fitting.score(fits[name]) <= fitting.score(pair)):
            continue
        fits[name] = pair
        if fitting.score(pair) < steps[-1].worst:
            if len(steps) > 2:
                steps.pop()
            steps.append(fitting.step(nxt.name, pair, (best, nxt.name)))
        if fitting.at_floor(pair):
            break


def _continued_pair(pair, name, fitting, max_nfev, notes, say):
    """``pair``, if its budget stopped it, fitted on from where it stopped (at most
    :data:`CONTINUATIONS` times, while that lowers its cost on the fit window), as the
    best single fit is (:func:`continue_stopped`)."""
    for _ in range(CONTINUATIONS):
        if not pair.stopped_on_budget():
            break
        say(f"fitting {name} on from where its budget stopped it")
        again = fitting.pair(pair.effects, dict(pair.values), max_nfev, notes,
                             pair.start_state)
        if again is None or again.error() >= pair.error():
            break
        pair = again
    return pair


def single_refit_from_pair(fits, best, steps, fitting, max_nfev, say) -> bool:
    """Parsimony: when a pair reached the floor, ``best`` alone again from the pair's
    values (a single fit that stopped in a wrong valley, a second effect making up for
    it); True when that single fit is better than ``best``'s first (it replaces it)."""
    floor, tolerance = fitting.floor, fitting.tolerance
    if len(steps) < 3 or not at_floor(steps[-1].worst, floor, tolerance):
        return False
    pair = fits[" + ".join(steps[-1].effects)]
    drop = pair.effects[1].params
    say(f"fitting {best} again from the pair's values")
    again = fitting.start(pair.effects[0], {k: v for k, v in pair.values.items()
                                            if k not in drop}, max_nfev, "the pair's values",
                          pair.start_state)
    if again is None or fitting.score(again) >= fitting.score(fits[best]):
        return False
    fits[best] = again
    steps[1] = fitting.step(best, again, (best,))
    if fitting.at_floor(again):
        steps.pop()  # the second effect is not needed
    return True


def base_refit(fits, steps, fitting, max_nfev, notes, say) -> bool:
    """Parsimony: the base model again from the best model's values of its parameters
    (a base fit that stopped in a wrong valley, an effect merely escaping it); True when
    that fit is better than the base fit (it replaces it, and the verdict is decided on
    it: an effect is accepted only where the base model cannot reach the floor).  The
    fit is abandoned where, at the pace of its last steps, its budget would not bring its
    fit window's error below the base model's score (the larger of its two windows'
    errors), which it has to beat (:func:`~pneunet.truth.core.lsq.least_squares_log`)."""
    if len(steps) < 2 or steps[-1].worst >= steps[0].worst:
        return False
    name = " + ".join(steps[-1].effects)
    best = fits[name]
    say(f"fitting the base model again from {name}'s values")
    again = fitting.start(None, {k: best.values[k] for k in fitting.params}, max_nfev,
                          f"{name}'s values", best.start_state, give_up_rms=steps[0].worst)
    if isinstance(again, Abandoned):  # its fit window's error would not beat the base's
        notes.append(f"base model fitted again from {name}'s values: abandoned after "
                     f"{again.nfev} simulations, at its pace it could not reach the base "
                     f"fit's {steps[0].worst:.4g} {best.unit}")
        return False
    if again is None or fitting.score(again) >= steps[0].worst:
        return False
    notes.append(f"base model fitted again from {name}'s values: held-out error "
                 f"{steps[0].held_out:.4g} → {again.error(fitting.test):.4g} {again.unit}")
    fits["none"] = again
    steps[0] = fitting.step(steps[0].label, again)
    return True


def _second_start(spec, first):
    """A second starting value of an effect parameter ``spec`` = (guess, low, high):
    its guess, or when the first start was near it, the log-middle of its range."""
    guess, lo, hi = spec
    mid = math.sqrt(lo * hi)
    if first is None or abs(math.log(first / guess)) > 0.5:
        return guess
    return mid


def unfitted_row(row, failed, n_res) -> dict:
    name = row["effect"].name
    return {"effect": name, "held_out_rms": None, "fitted": False,
            "status": "failed" if name in failed else "screened out",
            "screen_rms": math.sqrt(row["rss"] / n_res) if math.isfinite(row["rss"]) else None,
            "screen_values": {k: float(v) for k, v in row["x"].items()},
            "note": failed.get(name, "not fitted: across its parameter range it fits the first "
                                     "cycles worse than the ones fitted fully")}


def screen_data(df, window, fit: TraceFit):
    """The screen's data on the fit window, (times, signals, measured, keep, scales,
    alignment, and for a fit of the logger's clock its s per unit of shift), and
    ``fit``'s Jacobian on those samples (the clock's column last): the fit's compared samples less
    those around a recorded jump, a storage node's too (a grid point misses a 400 kPa
    edge's timing by a fraction of a sample; that misfit, alike for every candidate,
    would hide the differences the screen looks for)."""
    times = df["time_s"].to_numpy()
    mask = (times >= window[0]) & (times <= window[1])
    sigs = fit.signals()
    cols = {signal_of_column(c): c for c in df.columns if c != "time_s"}
    meas = {s: df[cols[s]].to_numpy() for s in sigs}
    fitted = {s: fit.extras["keep"][s][mask] for s in sigs}  # as the fit compared
    keep = {s: fitted[s] & compared_samples(meas[s])[mask] for s in sigs}
    rows = np.concatenate([keep[s][fitted[s]] for s in sigs])
    data = (times[mask], sigs, {s: meas[s][mask] for s in sigs}, keep, fit.scales,
            fit.extras.get("alignment"))
    clock_step = fit.extras.get("clock_step", 0.0)
    return data + (clock_step,) * bool(clock_step), fit.extras["jacobian"][rows]


def at_bound(fit: TraceFit) -> str:
    """'k = value' of the first of the fit's effect parameters that stopped at a bound of
    its range, or ''."""
    for e in fit.effects:
        for k, (_, lo, hi) in e.params.items():
            if near_bound(fit.values[k], lo, hi):
                return f"{k} = {fit.values[k]:.4g}"
    return ""


def ranked(fits: dict, fitting: CandidateFits) -> tuple[list, str]:
    """(the fitted candidates' names, best first by :meth:`CandidateFits.score` with the
    parsimonious one of those alike moved first; :func:`parsimonious_first`'s note)."""
    fitted = sorted((n for n in fits if n != "none"), key=lambda n: fitting.score(fits[n]))
    return parsimonious_first(fitted, fits, fitting.test, fitting.floor, fitting.tolerance,
                              fitting.score, fitting.train)


def parsimonious_first(fitted: list, fits: dict, test, floor: float, tolerance: float,
                       score=None, train=None) -> tuple[list, str]:
    """``fitted`` (candidate names by held-out error, best first) with the candidate of
    fewest parameters among those whose held-out residuals the best's cannot be told
    from (:func:`~pneunet.truth.core.verdict.indistinguishable`) and that are on the
    best's side of the verdict's threshold (``tolerance`` × ``floor``) moved first, and a
    note naming the others ('' when the best stays first alone): a tube of small
    resistance at a valve's output and a dead volume at that node fit a recording alike,
    and the recording cannot choose between them.  ``score(fit)``: the error the
    threshold applies to (default: held out); with the fitted window ``train`` the
    residuals there must be alike too."""
    if len(fitted) < 2:
        return fitted, ""
    score = score or (lambda fit: fit.error(test))
    windows = [test] + ([train] if train is not None else [])
    best = [fits[fitted[0]].scaled_residuals(w) for w in windows]
    side = at_floor(score(fits[fitted[0]]), floor, tolerance)
    alike = [fitted[0]] + [n for n in fitted[1:]
                           if at_floor(score(fits[n]), floor, tolerance) == side
                           and all(indistinguishable(fits[n].scaled_residuals(w), b)
                                   for w, b in zip(windows, best))]
    if len(alike) < 2:
        return fitted, ""
    size = {n: sum(len(e.params) for e in fits[n].effects) for n in alike}
    first = min(alike, key=lambda n: (size[n], alike.index(n)))
    others = [n for n in alike if n != first]
    record = "record" if train is not None else "held-out record"
    note = (f"{first} and {', '.join(others)} fit the {record} alike (held out "
            + ", ".join(f"{fits[n].error(test):.4g}" for n in [first] + others)
            + f"): the recording cannot tell them apart; {first} is taken, with the fewest "
            "parameters")
    return [first] + [n for n in fitted if n != first], note
