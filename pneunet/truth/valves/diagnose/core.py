"""Model vs measurement: localise the misfit, name the missing effect, add it.

:func:`diagnose` runs the loop of issue 5:

1. fit the plain six-parameter model (least squares on ṁ, started from the
   issue-4 identification) and estimate the noise floor from the data;
2. localise the residuals (learned residual model under grouped CV, binned
   maps, plain-language regions, misclassified points);
3. screen every candidate effect (one full-data refit each), cross-validate the
   promising ones with groups = sweeps, and rank them by out-of-sample RMSE;
4. accept the best one if its gain is clearly larger than its uncertainty
   (``z`` bootstrap standard errors) *and* than a practical floor
   (``min_gain`` × current CV RMSE); repeat until nothing passes;
5. report honestly: ``adequate`` when nothing was needed and no learnable
   structure is left, ``unexplained`` when structure remains that no accepted
   effect explains — with where it lives.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ....physics.valve_effects import ValveModel, as_effect, available_effects
from ....common.errors import DataError, ParameterError
from ....common.reprs import Summarized, listed
from .features import FEATURE_LABELS, feature_table, noise_floor, prepare
from .fitting import (ModelFit, cross_validate, fit_model, group_bootstrap_weights, group_folds,
                      initial_params, model_inputs, predict, rmse_ci, rmse_diff_ci)
from .residuals import regions, residual_structure


@dataclass
class Candidate:
    """One candidate effect in one round of the search."""

    effect: str
    fit: ModelFit
    insample_gain: float
    screened: bool = True  # passed the screen and was cross-validated
    cv_rmse: float | None = None
    gain: float | None = None
    gain_se: float | None = None
    accepted: bool = False
    equivalent: list = field(default_factory=list)
    oof_sq: np.ndarray | None = None
    reason: str = ""

    def to_json(self):
        return {"effect": self.effect, "cv_rmse": _num(self.cv_rmse), "gain": _num(self.gain),
                "gain_se": _num(self.gain_se), "accepted": self.accepted,
                "screened": self.screened, "insample_gain": _num(self.insample_gain),
                "equivalent_to": list(self.equivalent), "params": self.fit.effect_params()
                .get(self.effect, {}), "note": self.reason}


@dataclass
class Stage:
    """The model after 0, 1, 2 ... accepted effects (one bar of the waterfall)."""

    label: str
    fit: ModelFit
    cv_rmse: float
    cv_se: float
    oof_sq: np.ndarray
    pred: np.ndarray
    resid: np.ndarray
    structure: dict | None = None
    regions: list | None = None
    misclassified: dict | None = None

    def summary(self):
        return {"rmse": self.fit.rmse, "rmse_open": self.fit.rmse_open,
                "cv_rmse": self.cv_rmse, "cv_rmse_se": self.cv_se}


@dataclass(repr=False)
class Diagnosis(Summarized):
    """Everything :func:`diagnose` found; ``to_json()``, ``report()``, ``plots(dir)``."""

    data: object
    stages: list
    rounds: list  # list of lists of Candidate
    noise: dict
    structure_left: bool  # the learned residual model still finds structure
    notes: list
    settings: dict
    identification: object = None

    def _summary(self):
        rows = [("accepted", listed(self.accepted) or "nothing"),
                ("stages", str(len(self.stages))), ("structure left", str(self.structure_left))]
        return self.verdict, rows, ".report(), .to_json(), .plots(directory), .model, .stages"

    @property
    def baseline(self) -> Stage:
        return self.stages[0]

    @property
    def final(self) -> Stage:
        return self.stages[-1]

    @property
    def added(self) -> list[str]:
        """Effects that passed the acceptance rule, in waterfall order."""
        return [s.label for s in self.stages[1:]]

    @property
    def accepted(self) -> list[str]:
        """The effects claimed as the explanation: :attr:`added` unless the verdict is
        ``unexplained`` (then they only partly help, :attr:`partial`)."""
        return [] if self.verdict == "unexplained" else self.added

    @property
    def partial(self) -> list[str]:
        """Added effects that lower the error but leave structure: claimed as nothing."""
        return self.added if self.verdict == "unexplained" else []

    @property
    def model(self) -> ValveModel:
        return self.final.fit.model

    @property
    def ranking(self) -> list:
        return self.rounds[0] if self.rounds else []

    @property
    def verdict(self) -> str:
        """``adequate``, ``explained`` or ``unexplained`` (:func:`pneunet.truth.core.verdict`:
        held-out errors against the noise floor, and structure a flexible residual
        model still learns)."""
        from ... import verdict

        return verdict(self.baseline.cv_rmse, self.final.cv_rmse, self.noise["rmse"],
                       self.added, structure_left=self.structure_left)

    @property
    def waterfall(self):
        """The error waterfall (:class:`pneunet.truth.Waterfall`, CV RMSE in mg/s)."""
        from ... import Step, Waterfall

        steps = [Step(s.label, s.cv_rmse, s.cv_se,
                      effects=tuple(x.label for x in self.stages[1:i + 1]))
                 for i, s in enumerate(self.stages)]
        return Waterfall(steps, self.noise["rmse"], "mg/s", base_label="six-parameter model")

    @property
    def where(self) -> list:
        stage = self.final if self.added else self.baseline
        return [{"feature": f, "importance": round(v, 4), "label": FEATURE_LABELS.get(f, f)}
                for f, v in stage.structure["importance"]]

    def model_card(self, name="VDIAG") -> str:
        return self.model.model_card(name)

    def to_json(self) -> dict:
        b, f = self.baseline, self.final
        verdict = self.verdict
        return {
            "verdict": verdict,
            "adequate": verdict == "adequate",
            "unexplained": verdict == "unexplained",
            "final_adequate": verdict != "unexplained",
            "accepted": self.accepted,
            "partial": self.partial,
            "rms_unit": "mg/s",
            "ranking": [c.to_json() for c in self.ranking],
            "rounds": [[c.to_json() for c in r] for r in self.rounds],
            "baseline": {**b.summary(), "params": b.fit.model.params.as_dict()},
            "final": {**f.summary(), "params": f.fit.model.card_params(),
                      "effects": f.fit.effect_params()},
            "waterfall": [dict(w, cv_rmse=s.cv_rmse, cv_rmse_se=s.cv_se)
                          for w, s in zip(self.waterfall.to_json(), self.stages)],
            "where": self.where,
            "structure": {
                "baseline": _structure_json(b.structure),
                "final": _structure_json(f.structure)},
            "regions": {"baseline": [r["text"] for r in b.regions or []],
                        "final": [r["text"] for r in f.regions or []]},
            "misclassified": {"baseline": b.misclassified, "final": f.misclassified},
            "noise_floor": _num(self.noise["rmse"]),
            "noise_floor_bins": [{"flow_lo": lo, "flow_hi": hi, "sigma": s, "n": n}
                                 for lo, hi, s, n in self.noise["bins"]],
            "n": int(len(self.data)),
            "n_sweeps": int(self.data["group"].nunique()),
            "model_card": self.model_card(),
            "notes": list(self.notes),
            "settings": self.settings,
        }

    def report(self) -> str:
        return format_report(self)

    def plots(self, directory) -> list:
        from .plots import plot_all

        return plot_all(self, directory)


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _structure_json(s):
    if s is None:
        return None
    return {"r2_cv": s["r2_cv"], "gain": s["gain"], "gain_se": s["gain_se"],
            "learnable": s["learnable"],
            "importance": [{"feature": f, "importance": v} for f, v in s["importance"]]}


def diagnose(data, *, effects=None, n_splits=5, z=3.0, min_gain=0.02, max_effects=3,
             mdot_min=1.0, screen_gain=0.005, coverage=0.6, progress=True, seed=0,
             start=None, load_options=None) -> Diagnosis:
    """Diagnose a valve model against measured data.

    Parameters
    ----------
    data : path, DataFrame or :class:`pneunet.truth.valves.identify.Measurements`
        Static characterisation data (docs/identify.md); ``sweep`` optional.
    effects : list of ids / Effect classes or instances, optional
        Candidate effects (default: every registered effect, user ones included).
    n_splits : int
        Folds of the grouped cross-validation (groups = sweeps).
    z, min_gain : float
        Acceptance rule: CV gain > ``z`` × its bootstrap standard error and
        gain > ``min_gain`` × the current CV RMSE.  The same rule decides whether
        the learned residual model has found structure (``unexplained``).
    max_effects : int
        At most this many effects are accepted.
    mdot_min : float
        Flow (mg/s) above which a point counts as open (rmse_open, misclassified).
    coverage : float
        When the learned residual model finds structure, an effect must remove at
        least this fraction of the RMSE the residual model removes (otherwise it
        is a partial look-alike of an effect the library does not know).  An
        effect whose fit ends at a parameter bound is never accepted.
    screen_gain : float
        A candidate is cross-validated only if its full-data refit lowers the
        RMSE by more than this fraction (a CV gain can hardly exceed it otherwise).
    progress : bool
        Show a tqdm progress bar on stderr.
    start : ValveParams or ValveModel, optional
        Starting model instead of the issue-4 identification.
    """
    import scipy.linalg  # noqa: F401 — load the BLAS/LAPACK libraries before limiting them
    import scipy.optimize  # noqa: F401
    import sklearn.ensemble  # noqa: F401
    from threadpoolctl import threadpool_limits

    # BLAS/OpenMP threads make the many small SVDs and tree fits here 10-50x
    # slower on a shared machine; everything below is single-threaded.
    with threadpool_limits(1):
        return _diagnose(data, effects=effects, n_splits=n_splits, z=z, min_gain=min_gain,
                         max_effects=max_effects, mdot_min=mdot_min, screen_gain=screen_gain,
                         coverage=coverage, progress=progress, seed=seed, start=start,
                         load_options=load_options)


def _diagnose(data, *, effects, n_splits, z, min_gain, max_effects, mdot_min, screen_gain,
              coverage, progress, seed, start, load_options):
    from ....common.progress import progress_bar

    frame = _as_frame(data, load_options or {})
    df, notes = prepare(frame)
    cands = _candidate_specs(effects)
    inputs = model_inputs(df)
    y = df["mdot_mg_s"].to_numpy(float)
    folds = group_folds(df["group"].to_numpy(), n_splits)
    boot = group_bootstrap_weights(df["group"].to_numpy(), seed=seed)
    settings = {"n_splits": len(folds), "z": z, "min_gain": min_gain, "max_effects": max_effects,
                "mdot_min": mdot_min, "screen_gain": screen_gain, "coverage": coverage,
                "candidates": [c.id for c in cands]}
    n_dir = len(np.unique(df["sweep"]))
    bar = progress_bar(progress, total=3 + len(cands) * (1 + max_effects), desc="diagnose",
                       unit="step", leave=False)
    try:
        bar.set_postfix_str("baseline fit")
        if start is None:
            start_model = ValveModel(initial_params(df, None))
        else:
            start_model = start if isinstance(start, ValveModel) else ValveModel(start)
        base_fit = fit_model(df, start_model, inputs=inputs, mdot_min=mdot_min)
        base_cv = cross_validate(df, base_fit.model, folds, inputs=inputs)
        stage = _make_stage("baseline", base_fit, base_cv, df, inputs, y, boot, mdot_min)
        bar.update(1)
        noise = noise_floor(df, stage.resid, stage.pred)
        bar.set_postfix_str("residual structure")
        _localise(stage, df, folds, boot, z, min_gain, mdot_min, seed)
        bar.update(1)
        stages, rounds = [stage], []
        remaining = list(cands)
        while remaining and len(stages) <= max_effects:
            current = stages[-1]
            rnd = []
            for eff in remaining:
                bar.set_postfix_str(f"screen {eff.id}")
                rnd.append(_screen(eff, current, df, inputs, n_dir, screen_gain, mdot_min))
                bar.update(1)
            for c in rnd:
                if c.screened:
                    bar.set_postfix_str(f"cross-validate {c.effect}")
                    cv = cross_validate(df, c.fit.model, folds, inputs=inputs)
                    c.cv_rmse = cv.rmse
                    c.oof_sq = cv.sq
                    c.gain, c.gain_se = rmse_diff_ci(current.oof_sq, cv.sq, boot)
                    c._cv = cv
            _rank(rnd)
            best = rnd[0] if rnd and rnd[0].screened else None
            if best is not None:
                _equivalents(best, rnd, boot)
            rounds.append(rnd)
            chosen, partial = None, []
            for c in rnd:
                if not c.screened:
                    continue
                if not _passes(c.gain, c.gain_se, current.cv_rmse, z, min_gain):
                    c.reason = (f"gain {c.gain:.3g} ± {c.gain_se:.2g} mg/s does not pass "
                                f"(needs > {z:g} s.e. and > {100 * min_gain:g} % of "
                                f"{current.cv_rmse:.3g})")
                    continue
                at = _at_bound(c)
                if at:
                    c.reason = (f"fits only with {at} at its bound: the data want more than "
                                "this effect can give (probably a different effect)")
                    continue
                st = current.structure
                if st["learnable"] and c.gain < coverage * st["gain"]:
                    c.reason = (f"explains only {100 * c.gain / st['gain']:.0f} % of the "
                                f"structure a flexible model learns ({st['gain']:.3g} mg/s); "
                                f"needs {100 * coverage:.0f} % alone or with a second effect")
                    partial.append(c)
                    continue
                chosen = c
                break
            if chosen is None and len(partial) >= 2 and len(stages) < max_effects:
                chosen = _try_pairs(partial[:3], current, df, inputs, folds, boot, z,
                                    min_gain, coverage, bar)
            if chosen is None:
                break
            best = chosen
            best.accepted = True
            best.reason = "accepted" + (f"; {best.reason}" if best.reason.startswith("with")
                                        else "")
            bar.set_postfix_str(f"accepted {best.effect}")
            new = _make_stage(best.effect, best.fit, best._cv, df, inputs, y, boot, mdot_min)
            _localise(new, df, folds, boot, z, min_gain, mdot_min, seed)
            stages.append(new)
            remaining = [e for e in remaining if e.id != best.effect]
        bar.update(bar.total - bar.n)
    finally:
        bar.close()
    if n_dir < 2 and any("sweep" in e.needs for e in cands):
        notes.append("only one sweep direction in the data: hysteresis cannot be told from a "
                     "shift of p_close (measure rising and falling p_ctrl sweeps)")
    # re-estimate the noise floor under the final model (less misfit to cancel)
    noise = noise_floor(df, stages[-1].resid, stages[-1].pred)
    ident = None
    return Diagnosis(data=df, stages=stages, rounds=rounds, noise=noise,
                     structure_left=bool(stages[-1].structure["learnable"]), notes=notes, settings=settings,
                     identification=ident)


def _as_frame(data, load_options):
    import pandas as pd

    from ..identify import load_measurements

    if isinstance(data, pd.DataFrame):
        return data
    if hasattr(data, "frame"):
        return data.frame
    if not isinstance(data, (str, os.PathLike)):
        raise DataError(f"diagnose takes bench data: a CSV file, a DataFrame or "
                        f"Measurements, got {type(data).__name__}",
                        hint="the format: docs/data-format.md")
    return load_measurements(data, **load_options).frame


def _candidate_specs(effects):
    specs = [as_effect(e) for e in (effects if effects is not None else available_effects())]
    ids = [e.id for e in specs]
    if len(set(ids)) != len(ids):
        raise ParameterError(f"candidate effect listed twice: {ids}")
    # start each candidate at its init value (inside its bounds)
    return [type(e)(**{k: p.start for k, p in e.params.items()}) if e.is_null() else e
            for e in specs]


def _make_stage(label, fit, cv, df, inputs, y, boot, mdot_min):
    pred = predict(fit.model, inputs)
    rm, se = rmse_ci(cv.sq, boot)
    measured_open = y > mdot_min
    model_open = np.abs(pred) > mdot_min
    wrong = measured_open != model_open
    mis = {"count": int(wrong.sum()), "fraction": float(wrong.mean()),
           "open_but_predicted_closed": int((measured_open & ~model_open).sum()),
           "closed_but_predicted_open": int((~measured_open & model_open).sum())}
    return Stage(label=label, fit=fit, cv_rmse=rm, cv_se=se, oof_sq=cv.sq, pred=pred,
                 resid=y - pred, misclassified=mis)


def _localise(stage, df, folds, boot, z, min_gain, mdot_min, seed):
    feats = feature_table(df, stage.fit.model, stage.pred)
    s = residual_structure(feats, stage.resid, folds, boot, seed=seed)
    s["learnable"] = _passes(s["gain"], s["gain_se"], float(np.sqrt(np.mean(stage.resid ** 2))),
                             z, min_gain)
    stage.structure = s
    top = [f for f, _ in s["importance"]]
    stage.features = feats
    if not s["learnable"]:
        stage.regions = []
        return
    stage.regions = regions(feats, stage.resid, stage.pred, df["group"].to_numpy(), top,
                            mdot_min=mdot_min)
    stage.features = feats


def _try_pairs(partial, current, df, inputs, folds, boot, z, min_gain, coverage, bar):
    """Two partial look-alikes may be two real effects: accept the better one if the
    pair together passes the coverage rule (the other is then found next round)."""
    best_pair = None
    for i in range(len(partial)):
        for j in range(i + 1, len(partial)):
            a, b = partial[i], partial[j]
            bar.set_postfix_str(f"pair {a.effect}+{b.effect}")
            start = a.fit.model.with_effect(b.fit.model.effect(b.effect))
            fit = fit_model(df, start, inputs=inputs)
            cv = cross_validate(df, fit.model, folds, inputs=inputs)
            gain, se = rmse_diff_ci(current.oof_sq, cv.sq, boot)
            if (_passes(gain, se, current.cv_rmse, z, min_gain)
                    and gain >= coverage * current.structure["gain"]
                    and (best_pair is None or gain > best_pair[0])):
                best_pair = (gain, se, a, b)
    if best_pair is None:
        return None
    gain, se, a, b = best_pair
    a.reason = (f"with {b.effect} explains {100 * gain / current.structure['gain']:.0f} % of "
                f"the learnable structure (pair gain {gain:.3g} ± {se:.2g} mg/s)")
    return a


def _at_bound(c, tol=0.005):
    eff = c.fit.model.effect(c.effect)
    for k, p in eff.params.items():
        v = eff.values[k]
        for bound in (p.lo, p.hi):
            if bound != p.null and abs(v - bound) <= tol * (p.hi - p.lo):
                return f"{c.effect}.{k} = {v:.4g} {p.unit}"
    return ""


def _passes(gain, se, ref, z, min_gain):
    return gain is not None and gain > z * se and gain > min_gain * ref


def _screen(eff, current, df, inputs, n_dir, screen_gain, mdot_min):
    model = current.fit.model.with_effect(eff)
    if "sweep" in eff.needs and n_dir < 2:
        fit = current.fit  # placeholder: unidentifiable without both directions
        return Candidate(effect=eff.id, fit=fit_model(df, model, inputs=inputs, max_nfev=1),
                         insample_gain=0.0, screened=False,
                         reason="needs rising and falling sweeps; the data has one direction")
    fit = fit_model(df, model, inputs=inputs, mdot_min=mdot_min)
    g = current.fit.rmse - fit.rmse
    ok = g > screen_gain * current.fit.rmse
    return Candidate(effect=eff.id, fit=fit, insample_gain=g, screened=bool(ok),
                     reason="" if ok else f"screened out: full-data refit gains only {g:.3g} mg/s")


def _rank(rnd):
    rnd.sort(key=lambda c: (not c.screened, c.cv_rmse if c.cv_rmse is not None
                            else -c.insample_gain))


def _equivalents(best, rnd, boot):
    for c in rnd[1:]:
        if not c.screened or c.gain is None or c.gain <= 0:
            continue
        d, se = rmse_diff_ci(c.oof_sq, best.oof_sq, boot)
        if d < 2 * se:
            best.equivalent.append(c.effect)
            c.equivalent.append(best.effect)


def format_report(diag: Diagnosis) -> str:
    from ....physics.valve_effects import get_effect

    j = diag.to_json()
    b, f = diag.baseline, diag.final
    L = []
    L.append("[[Diagnosis: valve model vs measurement]]")
    L.append(f"    data points       = {j['n']} in {j['n_sweeps']} sweeps "
             f"({diag.settings['n_splits']}-fold CV grouped by sweep)")
    L.append("    noise floor       = " + (
        f"{j['noise_floor']:.3g} mg/s (estimated from the data)" if j["noise_floor"] is not None
        else "not estimated (fewer than 30 points inside sweeps of 3 or more)"))
    verdict = {"adequate": "ADEQUATE: nothing missing that the data can show",
               "explained": "EXPLAINED: the accepted effects bring the held-out error to the "
                            "noise floor",
               "unexplained": "UNEXPLAINED structure remains"}[diag.verdict]
    L.append(f"    verdict           = {verdict}")
    L.append(f"    accepted effects  = {', '.join(diag.accepted) or '(none)'}")
    if diag.partial:
        L.append(f"    partly helping    = {', '.join(diag.partial)} (not claimed: structure "
                 "remains)")
    L.append("[[Error waterfall]] (RMSE of held-out sweeps, mg/s)")
    L.append(diag.waterfall.table())
    L.append(f"    in-sample: baseline rmse {b.fit.rmse:.3g} (open {b.fit.rmse_open:.3g}), "
             f"final rmse {f.fit.rmse:.3g} (open {f.fit.rmse_open:.3g})")
    for k, rnd in enumerate(diag.rounds):
        L.append(f"[[Candidates, round {k + 1}]] (ranked by CV RMSE)")
        L.append(f"    {'effect':<18}{'cv_rmse':>9}{'gain':>9}{'± s.e.':>8}  parameters / note")
        for c in rnd:
            par = ", ".join(f"{n}={v['value']:.4g}±{v['stderr']:.2g} {v['unit']}"
                            for n, v in c.fit.effect_params().get(c.effect, {}).items())
            cv = f"{c.cv_rmse:9.3f}" if c.cv_rmse is not None else f"{'-':>9}"
            gn = f"{c.gain:9.3f}{c.gain_se:8.2g}" if c.gain is not None else f"{'-':>9}{'':>8}"
            mark = " *" if c.accepted else "  "
            L.append(f"  {mark}{c.effect:<16}{cv}{gn}  {par}")
            if c.reason and not c.accepted:
                L.append(f"{'':24}{c.reason}")
        best = rnd[0] if rnd else None
        if best is not None and best.equivalent:
            names = [best.effect] + best.equivalent
            hints = "; ".join(f"{n}: {get_effect(n).tell_apart}" for n in names
                              if get_effect(n).tell_apart)
            L.append(f"    {' and '.join(names)} explain these data equally well; "
                     f"to tell them apart measure — {hints}")
    for lab, s in (("before", b), ("after", f)) if diag.added else (("", b),):
        st = s.structure
        L.append(f"[[Remaining structure {lab}]]".replace(" ]]", "]]"))
        L.append(f"    learned residual model: CV explained variance {st['r2_cv']:.2f}, removes "
                 f"{st['gain']:.3g} ± {st['gain_se']:.2g} mg/s -> "
                 f"{'learnable structure' if st['learnable'] else 'no learnable structure'}")
        L.append("    carried by: " + ", ".join(f"{FEATURE_LABELS.get(n, n).split(' [')[0]} "
                                                f"{v:.0%}" for n, v in st["importance"][:4]))
        m = s.misclassified
        L.append(f"    misclassified open/closed: {m['count']} ({m['open_but_predicted_closed']} "
                 f"open predicted closed, {m['closed_but_predicted_open']} closed predicted open)")
        for r in s.regions or []:
            L.append(f"    - {r['text']}")
    if diag.added:
        L.append("[[Fitted effects]]")
        for eid, pars in f.fit.effect_params().items():
            for n, v in pars.items():
                L.append(f"    {eid}.{n} = {v['value']:.5g} ± {v['stderr']:.2g} {v['unit']} "
                         f"(95 % CI {v['ci95'][0]:.4g} … {v['ci95'][1]:.4g})")
    L.append("[[Model card]]")
    L.append("    " + diag.model_card())
    for n in diag.notes:
        L.append(f"note: {n}")
    return "\n".join(L)
