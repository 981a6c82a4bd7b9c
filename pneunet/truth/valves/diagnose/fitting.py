"""Fits of a :class:`~pneunet.physics.valve_effects.ValveModel` to measured flow, and grouped CV.

All models — the plain six-parameter valve and every extension — are fitted the
same way, so that a gain in error is the effect's and not the method's: nonlinear
least squares of ṁ over all points (scipy ``least_squares``, bounded), started
from the two-stage identification of issue 4 (:func:`pneunet.truth.valves.identify.fit_valve`,
or a thin fallback of the same two stages when it is not available).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ....physics.valve_effects import ValveModel
from ....common.errors import DataError
from ....physics.valve_params import ValveParams


@dataclass
class ModelFit:
    """A fitted model with its parameter uncertainties and figures of merit."""

    model: ValveModel
    names: list[str]
    values: np.ndarray
    stderr: np.ndarray
    rmse: float
    rmse_open: float
    n: int
    nfev: int = 0
    extra: dict = field(default_factory=dict)

    def ci95(self, name):
        i = self.names.index(name)
        return (self.values[i] - 1.96 * self.stderr[i], self.values[i] + 1.96 * self.stderr[i])

    def effect_params(self) -> dict:
        """{effect id: {param: {value, stderr, ci95, unit}}}."""
        out = {}
        for eff in self.model.effects:
            out[eff.id] = {}
            for k, p in eff.params.items():
                i = self.names.index(f"{eff.id}.{k}")
                out[eff.id][k] = {"value": float(self.values[i]),
                                  "stderr": float(self.stderr[i]),
                                  "ci95": [float(v) for v in self.ci95(f"{eff.id}.{k}")],
                                  "unit": p.unit}
        return out


def model_inputs(frame: pd.DataFrame):
    cols = frame
    return (cols["p_in_kPa"].to_numpy(float), cols["p_out_kPa"].to_numpy(float),
            cols["p_ctrl_kPa"].to_numpy(float),
            cols["time_s"].to_numpy(float) if "time_s" in cols else None,
            cols["sweep"].to_numpy(float) if "sweep" in cols else None)


def predict(model: ValveModel, inputs) -> np.ndarray:
    p_in, p_out, p_ctrl, t, s = inputs
    return model.flow(p_in, p_out, p_ctrl, time=t, sweep=s)


def open_mask(mdot, mdot_min=1.0):
    return np.asarray(mdot) > mdot_min


def initial_params(frame: pd.DataFrame, mdot_min=None) -> ValveParams:
    """Starting six parameters: the issue-4 two-stage fit when available."""
    try:
        from ..identify import fit_valve
    except ImportError:  # identification not part of this build
        fit_valve = None
    if fit_valve is not None:
        try:
            kw = {"mdot_min": "auto" if mdot_min is None else mdot_min}
            try:
                fit = fit_valve(frame, n_boot=0, **kw)  # no bootstrap: only a start
            except TypeError:
                fit = fit_valve(frame, **kw)
            return fit.params
        except Exception:  # noqa: BLE001 — fall back to the thin adapter below
            pass
    return _two_stage_fallback(frame, mdot_min)


def _two_stage_fallback(frame, mdot_min=None) -> ValveParams:
    """Minimal version of eqs. 20–24 (used only when pneunet.truth.valves.identify cannot fit)."""
    from scipy.optimize import least_squares
    from sklearn.svm import LinearSVC

    p_in, p_out, p_ctrl, _, _ = model_inputs(frame)
    mdot = frame["mdot_mg_s"].to_numpy(float)
    if mdot_min is None:
        closed_guess = mdot[mdot < np.quantile(mdot, 0.3)]
        mdot_min = max(1.0, 5.0 * 1.4826 * np.median(np.abs(closed_guess - np.median(closed_guess))))
    y = np.where(mdot > mdot_min, 1, -1)
    if len(set(y)) < 2:
        raise DataError("all points are open or all closed; cannot identify the valve",
                        hint="the protocol must sweep p_ctrl across the closing threshold")
    X = np.column_stack([p_in, p_out, p_ctrl])
    scale = 100.0
    svm = LinearSVC(C=10.0, max_iter=20000, dual=False).fit(X / scale, y)
    w = svm.coef_[0] / scale
    b = svm.intercept_[0]
    ain, aout = -w[0] / w[2], -w[1] / w[2]
    pclose = b / w[2]
    ain, aout = float(np.clip(ain, 0.01, 2.9)), float(np.clip(aout, 0.01, 2.9))
    dp = ain * p_in + aout * p_out - p_ctrl
    d = p_in ** 2 - p_out ** 2
    ok = (y > 0) & (dp > pclose) & (d > 0)
    inv_r = mdot[ok] / np.sqrt(d[ok])
    x = dp[ok] - pclose

    def res(v):
        rf, w_, e = v
        return 1.0 / (rf * np.sqrt(1.0 + (x / w_) ** (-2 * e))) - inv_r

    v0 = [1.0 / max(np.quantile(inv_r, 0.98), 1e-3), max(np.median(x), 5.0), 2.0]
    sol = least_squares(res, v0, bounds=([1e-3, 1e-2, 0.2], [1e3, 3e3, 9.5]))
    rf, w_, e = sol.x
    return ValveParams(Rf=float(rf), pclose=float(pclose), ptrans=float(pclose + w_), e=float(e),
                       ain=ain, aout=aout)


def fit_model(frame: pd.DataFrame, start: ValveModel, *, inputs=None, mdot_min=1.0,
              max_nfev=300) -> ModelFit:
    """Least-squares fit of all parameters of ``start`` (six + effects) to ṁ."""
    from scipy.optimize import least_squares

    inputs = model_inputs(frame) if inputs is None else inputs
    y = frame["mdot_mg_s"].to_numpy(float)
    spec = start.vector_spec()
    lo = np.array([s[1] for s in spec])
    hi = np.array([s[2] for s in spec])
    x0 = np.clip(start.to_vector(), lo, hi)
    # keep the start strictly inside the box (trf needs it)
    span = hi - lo
    x0 = np.clip(x0, lo + 1e-9 * span, hi - 1e-9 * span)

    def resid(v):
        try:
            return predict(start.from_vector(v), inputs) - y
        except Exception:  # noqa: BLE001 — invalid parameter combination
            return np.full_like(y, 1e6)

    sol = least_squares(resid, x0, bounds=(lo, hi), method="trf", x_scale="jac",
                        max_nfev=max_nfev, ftol=1e-10, xtol=1e-10, gtol=1e-10)
    model = start.from_vector(sol.x)
    r = sol.fun
    n, k = len(y), len(sol.x)
    stderr = _stderr(sol.jac, r, n, k)
    om = open_mask(y, mdot_min)
    return ModelFit(model=model, names=[s[0] for s in spec], values=sol.x, stderr=stderr,
                    rmse=float(np.sqrt(np.mean(r * r))),
                    rmse_open=float(np.sqrt(np.mean(r[om] ** 2))) if om.any() else float("nan"),
                    n=n, nfev=int(sol.nfev))


def _stderr(jac, r, n, k):
    """s·√diag((JᵀJ)⁻¹); a direction the Jacobian cannot see gives its parameters an
    infinite standard error (dropping it, as a truncated pseudo-inverse does, gives them
    a made-up small one)."""
    from ...core.intervals import inverse_normal_matrix

    s2 = float(r @ r) / max(n - k, 1)
    try:
        cov = inverse_normal_matrix(np.asarray(jac))[0] * s2
    except np.linalg.LinAlgError:
        return np.full(k, np.inf)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    se[~np.isfinite(se)] = np.inf
    return se


@dataclass
class CVResult:
    """Out-of-fold predictions of a model family under grouped k-fold CV."""

    oof: np.ndarray  # out-of-fold prediction per point
    sq: np.ndarray  # squared out-of-fold error per point
    fold_models: list

    @property
    def rmse(self) -> float:
        return float(np.sqrt(np.mean(self.sq)))


def group_folds(groups, n_splits=5):
    """GroupKFold splits (groups = sweeps): neighbouring points stay together."""
    from sklearn.model_selection import GroupKFold

    groups = np.asarray(groups)
    n_splits = int(min(n_splits, len(np.unique(groups))))
    if n_splits < 2:
        raise DataError("grouped cross-validation needs at least two sweeps")
    idx = np.arange(len(groups))
    return list(GroupKFold(n_splits=n_splits).split(idx, groups=groups))


def cross_validate(frame, start: ValveModel, folds, *, inputs=None, max_nfev=150) -> CVResult:
    """Refit ``start`` on each training fold, predict the held-out sweeps."""
    inputs = model_inputs(frame) if inputs is None else inputs
    y = frame["mdot_mg_s"].to_numpy(float)
    oof = np.empty_like(y)
    models = []
    for train, test in folds:
        sub = frame.iloc[train]
        sub_inputs = tuple(None if a is None else a[train] for a in inputs)
        fit = fit_model(sub, start, inputs=sub_inputs, max_nfev=max_nfev)
        oof[test] = predict(fit.model, tuple(None if a is None else a[test] for a in inputs))
        models.append(fit.model)
    return CVResult(oof=oof, sq=(oof - y) ** 2, fold_models=models)


def group_bootstrap_weights(groups, n_boot=400, seed=0):
    """(n_boot × n_groups) multinomial weights and the group index of each point."""
    uniq, gidx = np.unique(np.asarray(groups), return_inverse=True)
    rng = np.random.default_rng(seed)
    w = rng.multinomial(len(uniq), np.full(len(uniq), 1.0 / len(uniq)), size=n_boot)
    return w, gidx, len(uniq)


def rmse_diff_ci(sq_a, sq_b, boot):
    """rmse(a) − rmse(b) with a bootstrap-over-sweeps standard error."""
    w, gidx, ng = boot
    sa = np.bincount(gidx, sq_a, minlength=ng)
    sb = np.bincount(gidx, sq_b, minlength=ng)
    cnt = np.bincount(gidx, minlength=ng).astype(float)
    n = w @ cnt
    diff = np.sqrt((w @ sa) / n) - np.sqrt((w @ sb) / n)
    point = float(np.sqrt(np.mean(sq_a)) - np.sqrt(np.mean(sq_b)))
    return point, float(np.std(diff, ddof=1))


def rmse_ci(sq, boot):
    """rmse with its bootstrap-over-sweeps standard error."""
    w, gidx, ng = boot
    s = np.bincount(gidx, sq, minlength=ng)
    cnt = np.bincount(gidx, minlength=ng).astype(float)
    r = np.sqrt((w @ s) / (w @ cnt))
    return float(np.sqrt(np.mean(sq))), float(np.std(r, ddof=1))
