"""From a recorded circuit trace to the missing physics: the truth-finding pipeline.

0. an oscillating record sampled finer than the fits' difference step resolves is
   fitted on one sample in k (:func:`~pneunet.truth.circuits.align.thinning`);
1. fit the base model on the first cycles (:func:`~pneunet.truth.circuits.fit.fit_trace`);
2. the noise floor from the data alone: robust second differences of the residuals
   over the whole record (:mod:`pneunet.truth.core.noise`), per signal, pooled;
3. locate the residual of the held-out cycles: which signal, which part of the cycle,
   and the time shift that best aligns model and recording there;
4. screen every candidate effect on a grid across its parameter range, the base
   parameters re-centred on the recorded cycle and the residual projected off the base
   fit's Jacobian (two simulations per point, points in parallel); fit the most
   promising ones fully, each started at its best point moved by one Gauss–Newton step
   in the base parameters; rank all by their error on the later, held-out cycles;
5. the verdict (:func:`pneunet.truth.core.verdict.decide`): ``adequate`` (base model at
   the floor, and none of the candidates — screened once the base is above
   :data:`~pneunet.truth.core.verdict.NEAR_FLOOR` × floor — clearly lower),
   ``explained`` (the best effect, or it plus the next, brings the held-out error
   within ``tolerance`` × floor) or ``unexplained`` (and where it sits).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ...common.reprs import Summarized, listed, number
from ..core.locate import best_lag, hot_phases, phase_profile
from ..core.noise import (ROUNDING_SIGMA, WHITE_D2_CORRELATION, difference_correlation,
                          difference_sigma, resolution, segments)
from ..core.verdict import (NEAR_FLOOR, NEAR_GAIN, TOLERANCE, Step, at_floor, decide,
                            needs_candidates, strongly_structured, untested_note)
from ..core.waterfall import Waterfall
from .align import thinned
from .candidate_fits import (CandidateFits, at_bound, base_refit, fit_limits, fit_pairs,
                             fit_screened, ranked, refine_final, second_effects,
                             screen_data, single_refit_from_pair, unfitted_row)
from .data import read_trace, signal_of_column, signal_unit, split_by_cycles
from .effects import candidates_for
from .fit import TraceFit, fit_trace
from .model import DIFF_STEP, FIT_OPTIONS, TraceModel
from .screen import screen_candidates

#: the base fit's cap on simulations, × ``max_nfev``: a fit that stops on its budget
#: has stalled (a storage node's 400 kPa edges within one sample make the cost steep:
#: the inverter chain's base fit needs about 95 simulations from guesses 25 % off); a
#: fit that converges stops before
BASE_BUDGET = 3


@dataclass(repr=False)
class TraceDiagnosis(Summarized):
    """Everything :func:`diagnose_trace` found: ``to_json()``, ``report()``, ``plots()``."""

    verdict: str
    accepted: list
    noise_floor: float
    unit: str
    ranking: list  # of dicts, best first
    fits: dict  # name -> TraceFit (fitted candidates, 'none' = base)
    waterfall: Waterfall
    where: list  # plain-language findings about the remaining residual
    noise: dict
    train_window: tuple
    test_window: tuple
    timing: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    signals: dict = field(default_factory=dict)  # per signal, in its unit: signal_table
    fitted_every: int = 1  # every fit on one sample in this many (align.thinning)

    def _summary(self):
        rows = [("accepted", listed(self.accepted) or "nothing"),
                ("rms residual", number(self.final.error(), self.unit, 3)),
                ("noise floor", number(self.noise_floor, self.unit, 3)),
                ("candidates fitted", str(len(self.fits) - 1))]
        return self.verdict, rows, ".report(), .to_json(), .plots(directory), .final, .fits"

    @property
    def base(self) -> TraceFit:
        return self.fits["none"]

    @property
    def final(self) -> TraceFit:
        return self.fits.get(" + ".join(self.accepted), self.base) if self.accepted else self.base

    def to_json(self) -> dict:
        f = self.final
        return {"verdict": self.verdict, "accepted": list(self.accepted),
                "noise_floor": _num(self.noise_floor), "rms_unit": self.unit,
                "start_state": f.start_state.to_json() if f.start_state else None,
                "ranking": self.ranking, "fit": f.as_dict(),
                "base_fit": self.base.as_dict(), "waterfall": self.waterfall.to_json(),
                "where": list(self.where), "noise": self.noise,
                "train_window": list(self.train_window), "test_window": list(self.test_window),
                "timing": self.timing, "notes": list(self.notes),
                "fitted_every_nth_sample": self.fitted_every,
                "signals": {k: {f: v if f in ("unit", "at_floor") else _num(v)
                                for f, v in row.items()}
                            for k, row in self.signals.items()}}

    def report(self) -> str:
        from .report import format_report

        return format_report(self)

    def plots(self, directory) -> list:
        from .plots import plot_diagnosis

        return plot_diagnosis(self, directory)

    def corrected_netlist(self) -> str:
        """The final model (the accepted effects written as elements, the fitted values
        in) as netlist text (:meth:`TraceFit.corrected_netlist`)."""
        return self.final.corrected_netlist(
            verdict=f"{self.verdict}" + (f", accepted {', '.join(self.accepted)}"
                                         if self.accepted else ", no effect accepted"))


def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def noise_floor(fit: TraceFit, grid: dict | None = None) -> dict:
    """Noise floor of a fit's residuals over the whole record: per signal, σ from
    robust second differences within the runs of compared samples, at least the
    rounding of a signal recorded on a grid (``grid``: {signal: step in its unit},
    :func:`~pneunet.truth.core.noise.resolution`; step/√12); pooled as the rms over
    signals (in the fit's unit)."""
    out, pooled, correlated = {}, [], {}
    grid = grid or {}
    for s in fit.signals():
        scale = fit.scales.get(s, 1.0)
        r = fit.residuals[s].to_numpy() / scale
        ok = np.isfinite(r)
        sigma = difference_sigma(r, segments(ok))
        correlated[s] = difference_correlation(r, segments(ok))
        if math.isfinite(sigma):
            sigma = float(max(sigma, grid.get(s, 0.0) * ROUNDING_SIGMA / scale))
        out[s] = sigma
        if math.isfinite(sigma):
            pooled.append((sigma ** 2, int(ok.sum())))
    total = sum(w for _, w in pooled)
    floor = math.sqrt(sum(v * w for v, w in pooled) / total) if total else float("nan")
    method = ("1.4826·MAD of the residuals' second differences / √6, per signal over "
              "the whole record (jump samples left out), pooled rms")
    grid = {s: q for s, q in grid.items() if q > 0 and s in out}
    if grid:
        method += ("; at least the rounding of a signal logged on a grid, step/√12 ("
                   + ", ".join(f"{s} in steps of {q:.3g} {signal_unit(s)}".rstrip()
                               for s, q in grid.items()) + ")")
    return {"floor": floor, "per_signal": out, "method": method, "resolution": grid,
            "second_difference_correlation": {k: v for k, (v, _) in correlated.items()},
            "correlation_pairs": {k: n for k, (_, n) in correlated.items()}}


#: standard errors (1.05/√n for n pairs) above white noise's −2/3 at which the residuals'
#: second differences count as correlated from sample to sample (white noise: at most
#: 2.1 in 30 records of 800 samples; AR(1) noise of φ 0.7 is 4 standard errors above at
#: 800 samples, 6 at 1,800)
COLOURED_SE = 3.5


def coloured_note(noise: dict) -> str | None:
    """A note where the residuals' second differences are correlated from sample to
    sample (:func:`~pneunet.truth.core.noise.difference_correlation`, more than
    :data:`COLOURED_SE` standard errors above white noise's): the floor, which assumes
    white noise, is then low for a logger that filters; None otherwise."""
    high = {s: c for s, c in noise.get("second_difference_correlation", {}).items()
            if math.isfinite(c) and c > WHITE_D2_CORRELATION
            + COLOURED_SE * 1.05 / math.sqrt(max(noise["correlation_pairs"][s], 1))}
    if not high:
        return None
    which = ", ".join(f"{s} {c:.2f}" for s, c in high.items())
    return (f"the residuals' second differences are correlated from sample to sample "
            f"({which}; white noise gives {WHITE_D2_CORRELATION:.2f}): the noise floor, "
            "which assumes white noise, is low where the logger or its sensor filters "
            "(AR(1) noise of coefficient 0.7 shows about −0.52, and its floor is half "
            "its σ), and a right model then looks wrong. If yours filters, thin the "
            "record to samples a correlation time apart (--max-rows: a fifth of the "
            "rows keeps every fifth) and diagnose again; a model error that varies within "
            "a few samples (a ripple) correlates them too, and stays above the floor "
            "when thinned")


def signal_table(base: TraceFit, final: TraceFit, test, noise: dict,
                 tolerance: float = TOLERANCE) -> dict:
    """Per signal, in its own unit: the noise floor, the held-out rms of the base and
    the final model, the final's ratio to the floor and whether that is within
    ``tolerance`` (the signal's own verdict on the final model)."""
    held_base, held = base.errors_by_signal(test), final.errors_by_signal(test)
    out = {}
    for s in final.signals():
        floor = noise["per_signal"].get(s, math.nan) * final.scales.get(s, 1.0)
        out[s] = {"unit": signal_unit(s), "noise_floor": floor, "base_held_out": held_base[s],
                  "held_out": held[s], "ratio_to_floor": held[s] / floor if floor else math.nan,
                  "at_floor": bool(at_floor(held[s], floor, tolerance))}
    return out


def locate(fit: TraceFit, test_window, floor: float, data_frame, node: str) -> list[str]:
    """Plain-language places where ``fit``'s held-out residual exceeds the floor."""
    r = fit.residuals
    t = r["time_s"].to_numpy()
    sel = (t >= test_window[0]) & (t <= test_window[1])
    findings = []
    rows = []
    for s in fit.signals():
        v = r[s].to_numpy()[sel] / fit.scales.get(s, 1.0)
        ok = np.isfinite(v)
        rms = float(np.sqrt(np.mean(v[ok] ** 2))) if ok.any() else float("nan")
        rows.append((rms, s))
    rows.sort(reverse=True)
    col_of = {signal_of_column(c): c for c in data_frame.columns if c != "time_s"}
    for rms, s in rows:
        if not rms > TOLERANCE * floor:
            continue
        v = r[s].to_numpy() / fit.scales.get(s, 1.0)
        centre, prof = phase_profile(r["phase"].to_numpy()[sel], v[sel])
        hot = hot_phases(centre, prof, floor)
        period = fit.period_measured if math.isfinite(fit.period_measured) else 1.0
        meas = data_frame[col_of[s]].to_numpy()
        model = meas + np.nan_to_num(r[s].to_numpy())
        keep = sel & np.isfinite(r[s].to_numpy())
        lag = best_lag(t, meas, model, 0.1 * period, keep)
        where = ", ".join(f"{a:.2f}–{b:.2f}" for a, b in hot) or "spread over the cycle"
        dt = float(np.median(np.diff(t)))
        if abs(lag) < 0.5 * dt:
            shift = "no time shift brings them together there (a shape error)"
        else:
            shift = (f"the recording {'lags' if lag > 0 else 'leads'} the model by "
                     f"{abs(lag):.3g} s there")
        own = f"{rms * fit.scales.get(s, 1.0):.3g} {signal_unit(s)}".rstrip()
        findings.append(f"{s}: held-out rms {own} ({rms / floor:.1f}× the noise "
                        f"floor), largest at cycle phase {where} (0 = rising through mid-range "
                        f"of p_{node}); {shift}")
    return findings


def diagnose_trace(build, data, params: dict, *, fixed: dict | None = None, signals=None,
                   node: str = "tank", effects=None, train_fraction: float = 0.5,
                   max_nfev: int = 40, screen: int = 3, tolerance: float = TOLERANCE,
                   workers: int | None = None, options: dict | None = None,
                   progress=None, start_state="auto",
                   time_offset: float | None = None) -> TraceDiagnosis:
    """Diagnose a circuit recording; see the module docstring.

    ``build``/``params``/``fixed``/``signals``/``node``/``start_state``/``time_offset``
    as in :func:`~pneunet.truth.circuits.fit.fit_trace` (one start state, chosen for the base
    fit, serves every fit); ``effects``: candidate effects (kinds,
    bound effects or their names; default every registered one at every site);
    ``max_nfev``: cap on a fit's simulations (:data:`BASE_BUDGET` × for the base
    fit); ``screen``: how many of the best screened candidates may be fitted fully (the
    best, the next within :data:`SCREEN_KEEP` of its merit, the second best whatever its
    merit when none of those reaches the floor; 4 × ``max_nfev``: they have more
    parameters and start further away), each from its screen's best point, and when
    none reaches the floor each again from a second start;
    ``workers``: processes
    for parallel finite differences (None: 2 where there are 2 cores); ``progress``:
    a callable taking a message (e.g. ``print`` to stderr)."""
    from ...netlist.builder import require_builder
    from .model import process_pool

    require_builder(build, "diagnose_trace")
    say = progress or (lambda msg: None)
    wall = time.perf_counter()
    df = read_trace(data, signals)
    where = df.attrs["source"]
    options = FIT_OPTIONS if options is None else options
    driven = _sources_vary(build, fixed, params, options, df)
    train, test = split_by_cycles(df, node, train_fraction, where=where, driven=driven)
    thin, thin_notes = 1, []
    if not driven:  # every fit on one sample in thin
        df, thin, note = thinned(df, node, DIFF_STEP)
        thin_notes = [note] if note else []
    timing = {}
    pool = process_pool(workers)
    try:
        say("base fit")
        t0 = time.perf_counter()
        base = fit_trace(build, df, params, fixed=fixed, node=node, window=train,
                         max_nfev=BASE_BUDGET * max_nfev, pool=pool, options=options,
                         where=where, start_state=start_state, time_offset=time_offset,
                         refined=False)
        state = base.start_state
        say(f"start: {state.describe()}")
        params = {**params, **{k: v for k, v in state.fitted.items() if k not in params}}
        timing["base_fit_s"] = time.perf_counter() - t0
        fits = {"none": base}
        grid = {signal_of_column(c): resolution(df[c]) for c in df.columns if c != "time_s"}
        noise = noise_floor(base, grid)
        floor = noise["floor"]
        unit = base.unit
        base_err = base.error(test)
        steps = [Step("base model", base_err, train=base.error(train))]
        ranking = [_row("none", base, test, floor)]
        notes = [f"base fit: {base.extras['intervals']['note']}", *thin_notes]
        in_sample = train == test
        if in_sample:
            notes.append("nothing is held out: a record of a circuit driven by its sources "
                         "with fewer than two cycles at the node is fitted whole, and its "
                         "'held-out' errors are the fitted window's (two effects at once "
                         f"count only within {NEAR_FLOOR:g}× the floor)")
        circuit = TraceModel(build, fixed, options=options, state=state).circuit(base.values)
        cand = candidates_for(circuit, effects)
        # a base within NEAR_FLOOR whose residuals are strongly structured is screened too
        lb_p = base.extras["intervals"].get("ljung_box_p", math.nan)
        structured_base = strongly_structured(lb_p)
        verdict, accepted = decide(steps, floor, tolerance, in_sample, structured_base)
        fitting = CandidateFits(build, df, params, fixed, node, train, test, base, pool,
                                options, where, state, floor, tolerance)
        if cand and needs_candidates(steps[0].worst, floor, tolerance, structured_base):
            if not needs_candidates(steps[0].worst, floor, tolerance):
                notes.append(
                    f"base model within {NEAR_FLOOR:g}× the floor "
                    f"({steps[0].worst / floor:.2f}×) but its residuals strongly structured "
                    f"(Ljung–Box p = {lb_p:.2g}): the candidates were screened, and one is "
                    f"accepted only where it takes the error {NEAR_GAIN:.0%} lower")
            say(f"screening {len(cand)} candidate effects")
            t0 = time.perf_counter()
            names = list(params)
            x_hat = np.log([base.values[k] for k in names])
            data_fit, jac = screen_data(df, train, base)
            n_res = sum(int(v.sum()) for v in data_fit[3].values())
            typical = base.extras["model"].typical_s
            model_args = ((build, fixed), {"options": options, "typical_s": typical,
                                           "state": state})
            rows = screen_candidates(cand, names, x_hat, jac, params, model_args, data_fit,
                                     pool)
            fitting.screen_setup = (names, jac, model_args, data_fit)
            timing["screen_s"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            fit_screened(rows, fits, fitting, screen, 4 * max_nfev, say)
            fit_limits(fits, cand, circuit, fitting, 4 * max_nfev, say)
            timing["candidate_fits_s"] = time.perf_counter() - t0
            fitted, alike = ranked(fits, fitting)
            if alike:
                notes.append(alike)
            ranking += [_row(n, fits[n], test, floor, fitting.starts.get(n))
                        for n in fitted]
            ranking += [unfitted_row(r, fitting.failed, n_res) for r in rows
                        if r["effect"].name not in fits]
            ranking.sort(key=lambda r: (r["held_out_rms"] is None, r["held_out_rms"] or 0))
            # a waterfall step is an effect that lowers the held-out error: a best single
            # fit worse than the base model stays in the ranking only
            if fitted and fitting.score(fits[fitted[0]]) < steps[0].worst:
                best = fitted[0]
                steps.append(fitting.step(best, fits[best], (best,)))
                # noise floor from the best model too: less misfit leaks into it
                nb = noise_floor(fits[best], grid)
                if nb["floor"] < floor:
                    noise, floor = nb, nb["floor"]
                    noise["model"] = best
                    fitting.floor = floor
                verdict, accepted = decide(steps, floor, tolerance, in_sample, structured_base)
                if verdict == "unexplained":
                    t0 = time.perf_counter()
                    seconds = second_effects(fits, best, fitted, cand, params, fitting,
                                              (build, fixed, options, state), df, train, pool,
                                              say)
                    fit_pairs(fits, best, seconds, steps, fitting, 4 * max_nfev, notes, say)
                    if single_refit_from_pair(fits, best, steps, fitting, 4 * max_nfev, say):
                        ranking = [r if r["effect"] != best else
                                   _row(best, fits[best], test, floor, fitting.starts.get(best))
                                   for r in ranking]
                    timing["second_effect_s"] = time.perf_counter() - t0
            if base_refit(fits, steps, fitting, BASE_BUDGET * max_nfev, notes, say):
                base = fits["none"]
                ranking = [r if r["effect"] != "none" else _row("none", base, test, floor)
                           for r in ranking]
        # the steps' floor ratios may have changed with the floor: decide once more
        verdict, accepted = decide(steps, floor, tolerance, in_sample, structured_base)
        name = " + ".join(accepted) or "none"
        unrefined, uncounted = fits[name], 0
        if verdict != "unexplained" and refine_final(fits, name, fitting,
                                                     BASE_BUDGET * max_nfev, notes, say):
            timing["refine_simulations"] = fits[name].extras.get("simulations", 0)
            # the base model and pairs are counted through fits (the refined one now),
            # single effects through their starts
            uncounted = (unrefined if name == "none" or " + " in name
                         else fits[name]).extras.get("simulations", 0)
            step = next(i for i, s in enumerate(steps) if list(s.effects) == accepted)
            steps[step] = replace(steps[step], held_out=fits[name].error(test),
                                  train=fits[name].error(train))
            ranking = [r if r["effect"] != name else
                       _row(name, fits[name], test, floor, fitting.starts.get(name))
                       for r in ranking]
            base = fits["none"]
            verdict, accepted = decide(steps, floor, tolerance, in_sample, structured_base)
        untested = untested_note(steps, floor, tolerance)
        if untested:
            notes.append(untested)
        final = fits[" + ".join(accepted)] if accepted else base
        if not final.success:
            notes.append(f"{' + '.join(accepted) or 'base model'}: {final.unconverged()}")
        if final is not base and "undetermined_note" in final.extras["intervals"]:
            notes.append(f"{' + '.join(accepted)}: {final.extras['intervals']['undetermined_note']}")
        if verdict != "unexplained" and driven:
            notes += repeating_note(circuit, df)
        where_txt = [] if verdict != "unexplained" else locate(final, test, floor, df, node)
        coloured = coloured_note(noise) if verdict == "unexplained" else None
        if coloured:
            notes.append(coloured)
        if verdict == "unexplained" and not where_txt:
            where_txt = ["the held-out error is above the floor on every signal by a similar "
                         "amount (no single place)"]
        for name in accepted:
            f = fits[" + ".join(accepted)]
            at = at_bound(f)
            if at:
                notes.append(f"{name}: {at} at its bound")
    finally:
        if pool is not None:
            pool.shutdown()
    timing["total_s"] = time.perf_counter() - wall
    if "screen_s" in timing:  # the grid's points, their zoom and start steps, later screens
        timing["screen_simulations"] = sum(r["simulations"] for r in rows) \
            + fitting.screen_simulations
    # every fit tried, kept or not (the screen's are in screen_simulations)
    timing["simulations"] = sum(f.extras.get("simulations", 0) for n, f in fits.items()
                                if n == "none" or " + " in n) \
        + sum(st["simulations"] or 0 for tried in fitting.starts.values() for st in tried) \
        + uncounted
    wf = Waterfall(steps, floor, unit)
    return TraceDiagnosis(verdict, accepted, floor, unit, ranking, fits, wf, where_txt,
                          {k: v for k, v in noise.items()}, train, test, timing, notes,
                          signal_table(base, final, test, noise, tolerance), thin)


def repeating_note(circuit, df) -> list[str]:
    """A note (a list of one, or none) for a record of a circuit whose sources only
    repeat (:func:`~pneunet.truth.circuits.clock.repeating_drive`): its held-out periods
    repeat the fitted ones, so passing them says less than on a record through a change."""
    from .clock import repeating_drive

    period = repeating_drive(circuit, float(df.attrs.get("time_origin", 0.0)),
                             float(df["time_s"].iloc[-1]))
    if not period:
        return []
    return [f"the sources repeat every {period:g} s, so the held-out periods repeat the "
            "fitted ones: they test that the model reproduces this cycle, not that its "
            "values are the circuit's (two tanks driven by a sine with a dead end the model "
            "lacks: adequate at 1.1× the floor with both lines' R 20–30 % off); a record "
            "through a change of the drive (a step, another period or amplitude) tests more"]


def _sources_vary(build, fixed, params, options, df) -> bool:
    """Whether the netlist (at the parameter guesses) is driven by its sources for the
    record ``df`` (:func:`~pneunet.truth.circuits.clock.clock_from_record`)."""
    from .clock import clock_from_record

    circuit = TraceModel(build, fixed, options=options).base_circuit(
        {k: v[0] for k, v in params.items()})
    return clock_from_record(circuit, float(df.attrs.get("time_origin", 0.0)),
                             float(df["time_s"].iloc[-1]))


def _row(name, fit: TraceFit, test, floor, starts=None) -> dict:
    h = fit.error(test)
    row = {"effect": name, "held_out_rms": h, "ratio_to_floor": h / floor if floor else None,
           "fitted": True, "status": "fitted", "train_rms": fit.error(),
           "period_error": fit.period_error,
           "values": {k: float(v) for k, v in fit.values.items()},
           "ci": {k: list(v) for k, v in fit.ci.items()}, "nfev": fit.nfev,
           "converged": fit.success, "message": fit.message}
    if starts is not None:
        row["starts"] = starts
    return row
