"""From a recorded circuit trace to the missing physics: the truth-finding pipeline.

1. fit the base model on the first cycles (:func:`~pneunet.traces.fit.fit_trace`);
2. the noise floor from the data alone: robust second differences of the residuals
   over the whole record (:mod:`pneunet.truth.noise`), per signal, pooled;
3. locate the residual of the held-out cycles: which signal, which part of the cycle,
   and the time shift that best aligns model and recording there;
4. screen every candidate effect (at its guess, the base parameters re-centred on the
   recorded cycle: about two simulations, candidates in parallel), fit the most
   promising ones fully (warm-started there), rank all by their error on the later,
   held-out cycles;
5. the verdict (:func:`pneunet.truth.verdict.decide`): ``adequate`` (base model at
   the floor), ``explained`` (the best effect, or it plus the next, brings the held-out
   error within ``tolerance`` × floor) or ``unexplained`` (and where it sits).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..truth.locate import best_lag, hot_phases, phase_profile
from ..truth.noise import difference_sigma, segments
from ..truth.verdict import TOLERANCE, Step, decide
from ..truth.waterfall import Waterfall
from .data import read_trace, signal_of_column, split_by_cycles
from .effects import candidates_for
from .fit import TraceFit, fit_trace
from .model import FIT_OPTIONS, TraceModel, TraceResidual
from .data import compared_samples


@dataclass
class TraceDiagnosis:
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
                "ranking": self.ranking, "fit": self.base.as_dict(),
                "final_fit": f.as_dict(), "waterfall": self.waterfall.to_json(),
                "where": list(self.where), "noise": self.noise,
                "train_window": list(self.train_window), "test_window": list(self.test_window),
                "timing": self.timing, "notes": list(self.notes)}

    def report(self) -> str:
        from .report import format_report

        return format_report(self)

    def plots(self, directory) -> list:
        from .plots import plot_diagnosis

        return plot_diagnosis(self, directory)


def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def noise_floor(fit: TraceFit) -> dict:
    """Noise floor of a fit's residuals over the whole record: per signal, σ from
    robust second differences within the runs of compared samples; pooled as the rms
    over signals (in the fit's unit)."""
    out, pooled = {}, []
    for s in fit.signals():
        r = fit.residuals[s].to_numpy() / fit.scales.get(s, 1.0)
        ok = np.isfinite(r)
        sigma = difference_sigma(r, segments(ok))
        out[s] = sigma
        if math.isfinite(sigma):
            pooled.append((sigma ** 2, int(ok.sum())))
    total = sum(w for _, w in pooled)
    floor = math.sqrt(sum(v * w for v, w in pooled) / total) if total else float("nan")
    return {"floor": floor, "per_signal": out,
            "method": "1.4826·MAD of the residuals' second differences / √6, per signal over "
                      "the whole record (jump samples left out), pooled rms"}


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
        lead = ("the recording lags the model" if lag > 0 else "the recording leads the model")
        findings.append(f"{s}: held-out rms {rms:.3g} {fit.unit} ({rms / floor:.1f}× the noise "
                        f"floor), largest at cycle phase {where} (0 = rising through mid-range "
                        f"of p_{node}); {lead} by {abs(lag):.3g} s there")
    return findings


class _ScreenTask:
    """One candidate's screen (picklable, runs in a worker): the effect at its guess,
    the base parameters re-centred on the recorded cycle (two iterations of
    :func:`~pneunet.traces.start.initial_values`), the fit-window residual there."""

    def __init__(self, effect, names, x_base, params, model_args, data):
        self.effect, self.names, self.x_base = effect, names, x_base
        self.params, self.model_args, self.data = params, model_args, data

    def __call__(self):
        from ..errors import PneunetError
        from .start import initial_values

        eff = self.effect
        names = self.names + list(eff.params)
        x = np.concatenate([self.x_base, np.log([v[0] for v in eff.params.values()])])
        lb = np.log([self.params[k][1] for k in self.names] + [v[1] for v in eff.params.values()])
        ub = np.log([self.params[k][2] for k in self.names] + [v[2] for v in eff.params.values()])
        model = TraceModel(*self.model_args[0], effects=(eff,), **self.model_args[1])
        fun = TraceResidual(model, names, *self.data)
        times, sigs, meas = self.data[0], self.data[1], self.data[2]
        node_sig = next((s for s in sigs if s.startswith("p_")), sigs[0])
        try:
            x, info = initial_values(model, names, x, lb, ub, times, meas[node_sig],
                                     node_sig[2:], iterations=2)
        except PneunetError:
            pass
        r = fun(np.clip(x, lb, ub))
        return {"x": dict(zip(names, np.exp(x))), "rss": float(r @ r),
                "failed": bool(fun.failures), "simulations": model.calls}


def _run_task(task):
    return task()


def _screen(cand, names, x_base, params, model_args, data, pool):
    """Screen rows (effect, rss at the re-centred guess, start values), best first."""
    tasks = [_ScreenTask(e, names, x_base, params, model_args, data) for e in cand]
    if pool is None:
        outs = [t() for t in tasks]
    else:
        outs = list(pool.map(_run_task, tasks))
    rows = [dict(o, effect=e) for e, o in zip(cand, outs)]
    rows.sort(key=lambda r: (r["failed"], r["rss"]))
    return rows


def diagnose_trace(build, data, params: dict, *, fixed: dict | None = None, signals=None,
                   node: str = "tank", effects=None, train_fraction: float = 0.5,
                   max_nfev: int = 30, screen: int = 3, tolerance: float = TOLERANCE,
                   workers: int | None = None, options: dict | None = None,
                   progress=None) -> TraceDiagnosis:
    """Diagnose a circuit recording; see the module docstring.

    ``build``/``params``/``fixed``/``signals``/``node`` as in
    :func:`~pneunet.traces.fit.fit_trace`; ``effects``: candidate effects (kinds,
    bound effects or their names; default every registered one at every site);
    ``screen``: how many screened candidates are fitted fully; ``workers``: processes
    for parallel finite differences (None: 2 where there are 2 cores); ``progress``:
    a callable taking a message (e.g. ``print`` to stderr)."""
    from .model import process_pool

    say = progress or (lambda msg: None)
    wall = time.perf_counter()
    where = str(data) if not hasattr(data, "columns") else "trace"
    df = read_trace(data, signals)
    train, test = split_by_cycles(df, node, train_fraction, where=where)
    timing = {}
    pool = process_pool(workers)
    options = FIT_OPTIONS if options is None else options
    try:
        say("base fit")
        t0 = time.perf_counter()
        base = fit_trace(build, df, params, fixed=fixed, node=node, window=train,
                         max_nfev=max_nfev, pool=pool, options=options, where=where)
        timing["base_fit_s"] = time.perf_counter() - t0
        fits = {"none": base}
        noise = noise_floor(base)
        floor = noise["floor"]
        unit = base.unit
        base_err = base.error(test)
        steps = [Step("base model", base_err)]
        ranking = [_row("none", base, test, floor)]
        notes = [f"base fit: {base.extras['intervals']['note']}"]
        circuit = TraceModel(build, fixed, options=options).circuit(base.values)
        cand = candidates_for(circuit, effects)
        verdict, accepted = decide(steps, floor, tolerance)
        if verdict != "adequate" and cand:
            say(f"screening {len(cand)} candidate effects")
            t0 = time.perf_counter()
            names = list(params)
            x_hat = np.log([base.values[k] for k in names])
            data_fit = _fit_data(df, train, base)
            n_res = sum(int(v.sum()) for v in data_fit[3].values())
            rows = _screen(cand, names, x_hat, params, ((build, fixed), {"options": options}),
                           data_fit, pool)
            timing["screen_s"] = time.perf_counter() - t0
            timing["screen_simulations"] = sum(r["simulations"] for r in rows)
            t0 = time.perf_counter()
            for row in rows[:screen]:
                eff = row["effect"]
                say(f"fitting {eff.name}")
                fits[eff.name] = _fit_effects(build, df, params, fixed, node, train, (eff,),
                                              base, [row], max_nfev, pool, options, where)
            timing["candidate_fits_s"] = time.perf_counter() - t0
            fitted = sorted((n for n in fits if n != "none"), key=lambda n: fits[n].error(test))
            ranking += [_row(n, fits[n], test, floor) for n in fitted]
            ranking += [{"effect": r["effect"].name, "held_out_rms": None, "fitted": False,
                         "screen_rms": math.sqrt(r["rss"] / n_res),
                         "note": "screened out: at its guess, with the base parameters "
                                 "re-centred on the cycle, it fits worse than the ones fitted"}
                        for r in rows[screen:]]
            ranking.sort(key=lambda r: (r["held_out_rms"] is None, r["held_out_rms"] or 0))
            if fitted:
                best = fitted[0]
                steps.append(Step(best, fits[best].error(test), effects=(best,)))
                # noise floor from the best model too: less misfit leaks into it
                nb = noise_floor(fits[best])
                if nb["floor"] < floor:
                    noise, floor = nb, nb["floor"]
                    noise["model"] = best
                verdict, accepted = decide(steps, floor, tolerance)
                if verdict == "unexplained" and len(fitted) > 1 \
                        and steps[1].held_out < steps[0].held_out:
                    nxt = fitted[1]
                    say(f"fitting {best} + {nxt}")
                    pair = _fit_effects(build, df, params, fixed, node, train,
                                        (fits[best].effects[0], fits[nxt].effects[0]), base,
                                        None, max_nfev, pool, options, where,
                                        start={**fits[best].values, **fits[nxt].values})
                    key = f"{best} + {nxt}"
                    fits[key] = pair
                    if pair.error(test) < steps[-1].held_out:
                        steps.append(Step(nxt, pair.error(test), effects=(best, nxt)))
                    verdict, accepted = decide(steps, floor, tolerance)
        # the steps' floor ratios may have changed with the floor: decide once more
        verdict, accepted = decide(steps, floor, tolerance)
        final = fits[" + ".join(accepted)] if accepted else base
        where_txt = [] if verdict != "unexplained" else locate(final, test, floor, df, node)
        if verdict == "unexplained" and not where_txt:
            where_txt = ["the held-out error is above the floor on every signal by a similar "
                         "amount (no single place)"]
        for name in accepted:
            f = fits[" + ".join(accepted)]
            at = _at_bound(f, params)
            if at:
                notes.append(f"{name}: {at} at its bound")
    finally:
        if pool is not None:
            pool.shutdown()
    timing["total_s"] = time.perf_counter() - wall
    timing["simulations"] = sum(f.extras.get("simulations", 0) for f in fits.values())
    wf = Waterfall(steps, floor, unit)
    return TraceDiagnosis(verdict, accepted, floor, unit, ranking, fits, wf, where_txt,
                          {k: v for k, v in noise.items()}, train, test, timing, notes)


def _fit_data(df, window, base: TraceFit):
    """(times, signals, measured, keep, scales) of the fit window, as the base fit."""
    times = df["time_s"].to_numpy()
    mask = (times >= window[0]) & (times <= window[1])
    sigs = base.signals()
    cols = {signal_of_column(c): c for c in df.columns if c != "time_s"}
    meas = {s: df[cols[s]].to_numpy() for s in sigs}
    keep = {s: compared_samples(meas[s])[mask] for s in sigs}
    return (times[mask], sigs, {s: meas[s][mask] for s in sigs}, keep, base.scales,
            base.extras.get("alignment"))


def _fit_effects(build, df, params, fixed, node, train, effs, base, rows, max_nfev, pool,
                 options, where, start=None):
    p = {k: (float(np.clip(base.values[k], lo, hi)), lo, hi) for k, (_, lo, hi) in params.items()}
    for e in effs:
        p.update(e.params)
    x_start = dict(start or {})
    if rows:
        x_start.update(rows[0]["x"])
    for k in p:
        x_start.setdefault(k, p[k][0])
    return fit_trace(build, df, p, fixed=fixed, node=node, window=train, effects=effs,
                     max_nfev=max_nfev, pool=pool, options=options, x_start=x_start,
                     where=where)


def _row(name, fit: TraceFit, test, floor) -> dict:
    h = fit.error(test)
    return {"effect": name, "held_out_rms": h, "ratio_to_floor": h / floor if floor else None,
            "fitted": True, "train_rms": fit.error(), "period_error": fit.period_error,
            "values": {k: float(v) for k, v in fit.values.items()},
            "ci": {k: list(v) for k, v in fit.ci.items()}, "nfev": fit.nfev}


def _at_bound(fit: TraceFit, base_params, tol=0.01) -> str:
    for e in fit.effects:
        for k, (_, lo, hi) in e.params.items():
            v = fit.values[k]
            if abs(math.log(v / lo)) < tol or abs(math.log(hi / v)) < tol:
                return f"{k} = {v:.4g}"
    return ""
