"""Where does the model fail?  Learned residual model, binned maps, plain-language regions."""
from __future__ import annotations

import numpy as np
import pandas as pd

from .features import FEATURE_LABELS, MODEL_FEATURES
from .fitting import rmse_diff_ci


def residual_structure(features: pd.DataFrame, resid: np.ndarray, folds, boot, *, seed=0):
    """Gradient boosting on the residuals under grouped CV (groups = sweeps).

    Returns a dict: ``r2_cv`` (out-of-fold explained variance), ``gain`` and
    ``gain_se`` (RMSE removed by the residual model out of sample, with a
    bootstrap-over-sweeps standard error), ``oof`` predictions and ``importance``
    [(feature, share)] from out-of-fold permutation importance, most important first.
    """
    from sklearn.ensemble import HistGradientBoostingRegressor
    from threadpoolctl import threadpool_limits

    cols = [c for c in MODEL_FEATURES if c in features and features[c].nunique() > 1]
    X = features[cols].to_numpy(float)
    r = np.asarray(resid, float)
    oof = np.zeros_like(r)
    rng = np.random.default_rng(seed)
    incr = np.zeros(len(cols))
    for train, test in folds:
        hgb = HistGradientBoostingRegressor(max_iter=80, learning_rate=0.1, max_leaf_nodes=15,
                                            min_samples_leaf=30, l2_regularization=1.0,
                                            early_stopping=False, random_state=seed)
        with threadpool_limits(1):  # OpenMP threads on shared cores cost 50x here
            hgb.fit(X[train], r[train])
            Xt = X[test]
            oof[test] = hgb.predict(Xt)
            base = np.mean((r[test] - oof[test]) ** 2)
            for j in range(len(cols)):
                Xp = Xt.copy()
                Xp[:, j] = Xp[rng.permutation(len(test)), j]
                incr[j] += (np.mean((r[test] - hgb.predict(Xp)) ** 2) - base) * len(test)
    incr = np.maximum(incr / len(r), 0.0)
    share = incr / incr.sum() if incr.sum() > 0 else np.full(len(cols), 1.0 / max(len(cols), 1))
    order = np.argsort(-share)
    gain, gain_se = rmse_diff_ci(r ** 2, (r - oof) ** 2, boot)
    ss = float(np.sum((r - r.mean()) ** 2))
    return {"r2_cv": 1.0 - float(np.sum((r - oof) ** 2)) / ss if ss > 0 else 0.0,
            "gain": gain, "gain_se": gain_se, "oof": oof,
            "importance": [(cols[i], float(share[i])) for i in order]}


def binned_map(x, y, r, nx=8, ny=8, min_count=5):
    """Mean residual and its standard error in an nx × ny grid of equal-width bins
    (a feature with two values, like the sweep direction, gets two bins).

    Returns (x_edges, y_edges, mean, se, count); bins with fewer than
    ``min_count`` points are NaN.
    """
    def edges(v, n):
        u = np.unique(v)
        if len(u) <= 3:
            mids = (u[1:] + u[:-1]) / 2 if len(u) > 1 else np.array([])
            return np.concatenate([[u[0] - 0.5], mids, [u[-1] + 0.5]])
        return np.linspace(v.min(), v.max() + 1e-9 * (abs(v.max()) + 1), n + 1)

    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    ex, ey = edges(x, nx), edges(y, ny)
    ix = np.clip(np.searchsorted(ex, x, side="right") - 1, 0, len(ex) - 2)
    iy = np.clip(np.searchsorted(ey, y, side="right") - 1, 0, len(ey) - 2)
    shape = (len(ex) - 1, len(ey) - 1)
    flat = ix * shape[1] + iy
    n = np.bincount(flat, minlength=shape[0] * shape[1]).astype(float)
    s = np.bincount(flat, r, minlength=n.size)
    s2 = np.bincount(flat, r * r, minlength=n.size)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = s / n
        var = (s2 - n * mean ** 2) / np.maximum(n - 1, 1)
        se = np.sqrt(np.maximum(var, 0) / n)
    bad = n < min_count
    mean[bad] = np.nan
    se[bad] = np.nan
    return ex, ey, mean.reshape(shape), se.reshape(shape), n.reshape(shape)


_FMT = {"ratio": "{:.2f}", "sweep": "{:+.0f}"}


def regions(features: pd.DataFrame, resid: np.ndarray, pred: np.ndarray, groups, top,
            *, mdot_min=1.0, max_regions=3, z=3.0):
    """Plain-language regions where the mean residual is clearly non-zero.

    A shallow regression tree on the most important features (plus "valve
    open") splits the input space; each leaf whose mean residual differs from
    zero by more than ``z`` standard errors (clustered by sweep) becomes a
    sentence such as "p_out/p_in < 0.42 and valve open: flow under-predicted by
    9 ± 2 % (31 ± 7 mg/s, 412 points)".  Returns a list of dicts with ``text``.
    """
    from sklearn.tree import DecisionTreeRegressor

    feats = [f for f in top if f in features][:3]
    X = features[feats].copy()
    X["open"] = (np.abs(pred) > mdot_min).astype(float)
    cols = list(X.columns)
    n = len(resid)
    tree = DecisionTreeRegressor(max_leaf_nodes=6, min_samples_leaf=max(40, n // 50),
                                 random_state=0).fit(X.to_numpy(float), resid)
    leaf = tree.apply(X.to_numpy(float))
    t = tree.tree_
    paths = {}

    def walk(node, conds):
        if t.children_left[node] == -1:
            paths[node] = conds
            return
        f, thr = t.feature[node], t.threshold[node]
        walk(t.children_left[node], conds + [(cols[f], "<", thr)])
        walk(t.children_right[node], conds + [(cols[f], ">=", thr)])

    walk(0, [])
    groups = np.asarray(groups)
    out = []
    for node, conds in paths.items():
        sel = leaf == node
        r = resid[sel]
        if len(r) < 10:
            continue
        # standard error clustered by sweep: mean of per-sweep means
        gm = pd.Series(r).groupby(groups[sel]).mean().to_numpy()
        se = float(np.std(gm, ddof=1) / np.sqrt(len(gm))) if len(gm) > 1 else float("inf")
        mean = float(r.mean())
        if not abs(mean) > z * se:
            continue
        text_cond = _conditions_text(conds)
        flow = float(np.mean(np.abs(pred[sel])))
        verb = "under-predicted" if mean > 0 else "over-predicted"
        if flow > 10 * mdot_min:
            pct, pct_se = 100 * abs(mean) / flow, 100 * se / flow
            amount = (f"{pct:.1f} ± {pct_se:.1f} % ({abs(mean):.1f} ± {se:.1f} mg/s, "
                      f"{len(r)} points)")
        else:
            amount = f"{abs(mean):.2f} ± {se:.2f} mg/s ({len(r)} points)"
        out.append({"text": f"{text_cond}: flow {verb} by {amount}", "mean": mean, "se": se,
                    "n": int(len(r)), "weight": abs(mean) * len(r)})
    out.sort(key=lambda d: -d["weight"])
    return out[:max_regions]


def _conditions_text(conds):
    bounds: dict[str, list] = {}
    for f, op, thr in conds:
        lo, hi = bounds.get(f, [None, None])
        if op == "<":
            hi = thr if hi is None else min(hi, thr)
        else:
            lo = thr if lo is None else max(lo, thr)
        bounds[f] = [lo, hi]
    parts = []
    for f, (lo, hi) in bounds.items():
        if f == "open":
            parts.append("valve open" if lo is not None else "valve closed")
            continue
        if f == "sweep":
            parts.append("rising p_ctrl sweeps" if lo is not None else "falling p_ctrl sweeps")
            continue
        name = FEATURE_LABELS.get(f, f).split(" [")[0]
        fmt = _FMT.get(f, "{:.0f}")
        if lo is not None and hi is not None:
            parts.append(f"{fmt.format(lo)} ≤ {name} < {fmt.format(hi)}")
        elif lo is not None:
            parts.append(f"{name} ≥ {fmt.format(lo)}")
        else:
            parts.append(f"{name} < {fmt.format(hi)}")
    return " and ".join(parts) if parts else "everywhere"
