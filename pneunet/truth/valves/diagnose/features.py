"""Data preparation for the diagnosis: sweeps (CV groups), sweep direction, features."""
from __future__ import annotations

import numpy as np
import pandas as pd

from ....common.errors import DataError

#: feature name -> plain-language label (used in maps, ``where`` and regions)
FEATURE_LABELS = {
    "p_in": "p_in [kPa]",
    "p_out": "p_out [kPa]",
    "p_ctrl": "p_ctrl [kPa]",
    "dp": "Δp − p_close [kPa]",
    "ratio": "p_out/p_in",
    "mdot": "model flow ṁ [mg/s]",
    "time": "time (row order) [s]",
    "sweep": "sweep direction (−1 falling, +1 rising p_ctrl)",
}
#: features of the learned residual model (Δp and Δp − p_close carry the same
#: information, so only the latter is used; time stands for row order)
MODEL_FEATURES = ("p_in", "p_out", "p_ctrl", "dp", "ratio", "mdot", "time", "sweep")


def prepare(frame: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """Copy of ``frame`` with ``group`` (sweep id) and ``sweep`` (direction) columns.

    Sweeps: a ``group`` column is used as is.  Otherwise a new sweep starts where
    the ``sweep`` column changes, or where p_ctrl jumps against the sweep direction
    (more than half the typical step).  Without a ``sweep`` column the direction
    is derived from row order (sign of the p_ctrl step) and a new sweep starts
    where it reverses or p_ctrl jumps by more than three typical steps.
    Returns the frame and notes for the report.
    """
    need = ("p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s")
    missing = [c for c in need if c not in frame]
    if missing:
        raise DataError(f"data lacks column(s) {', '.join(missing)}",
                        hint="the bench CSV layout is in docs/identify.md, section 1")
    df = frame.reset_index(drop=True).copy()
    notes = []
    if "time_s" not in df:
        df["time_s"] = np.arange(len(df), dtype=float)
        notes.append("no time_s column: row order used as time")
    if df[list(need)].isna().any().any():
        raise DataError("data contains NaN values", hint="load it with pneunet.truth.valves.identify."
                        "load_measurements(..., on_invalid='exclude')")
    pc = df["p_ctrl_kPa"].to_numpy(float)
    step = np.diff(pc)
    typical = float(np.median(np.abs(step[np.abs(step) > 1e-9]))) if len(step) else 1.0
    if "group" in df:
        groups = pd.factorize(df["group"])[0]
        if "sweep" not in df:
            df["sweep"] = _direction(pc, groups)
            notes.append("sweep direction derived from row order")
    elif "sweep" in df:
        s = np.sign(df["sweep"].to_numpy(float))
        brk = np.zeros(len(df), dtype=bool)
        brk[1:] = (s[1:] != s[:-1]) | (step * s[1:] < -0.5 * typical)
        groups = np.cumsum(brk)
    else:
        brk = np.zeros(len(df), dtype=bool)
        brk[1:] = np.abs(step) > 3 * typical
        groups = np.cumsum(brk)
        d = _direction(pc, groups)
        rev = np.zeros(len(df), dtype=bool)
        rev[1:] = (d[1:] != d[:-1]) & (groups[1:] == groups[:-1])
        groups = np.cumsum(brk | rev)
        df["sweep"] = d
        notes.append("no sweep column: sweep direction derived from row order")
    df["group"] = groups
    n_groups = len(np.unique(groups))
    if n_groups < 5:
        raise DataError(f"only {n_groups} sweep(s) found; the diagnosis needs at least 5 "
                        "for grouped cross-validation",
                        hint="add a 'group' column naming the sweep of each row")
    return df, notes


def _direction(pc, groups):
    d = np.zeros(len(pc))
    back = np.zeros(len(pc))
    back[1:] = np.sign(pc[1:] - pc[:-1])
    same_prev = np.zeros(len(pc), dtype=bool)
    same_prev[1:] = groups[1:] == groups[:-1]
    fwd = np.zeros(len(pc))
    fwd[:-1] = np.sign(pc[1:] - pc[:-1])
    same_next = np.zeros(len(pc), dtype=bool)
    same_next[:-1] = groups[:-1] == groups[1:]
    d = np.where(same_prev & (back != 0), back, np.where(same_next, fwd, -1.0))
    d[d == 0] = -1.0
    return d


def feature_table(df: pd.DataFrame, model, pred: np.ndarray) -> pd.DataFrame:
    """The diagnosis features for each point, under the (fitted) model ``model``."""
    P = model.params
    p_in = df["p_in_kPa"].to_numpy(float)
    p_out = df["p_out_kPa"].to_numpy(float)
    p_ctrl = df["p_ctrl_kPa"].to_numpy(float)
    hi, lo = np.maximum(p_in, p_out), np.minimum(p_in, p_out)
    dp = P.ain * hi + P.aout * lo - p_ctrl
    return pd.DataFrame({
        "p_in": p_in, "p_out": p_out, "p_ctrl": p_ctrl, "dp": dp - P.pclose,
        "ratio": lo / hi, "mdot": pred, "time": df["time_s"].to_numpy(float),
        "sweep": df["sweep"].to_numpy(float)})


def noise_floor(df: pd.DataFrame, resid: np.ndarray, pred: np.ndarray, n_bins=8) -> dict:
    """Measurement noise estimated from the data alone (no model truth needed).

    Second differences of the residuals along each sweep, r[i−1] − 2r[i] + r[i+1],
    cancel any misfit that is smooth along the sweep and keep the point-to-point
    noise (flow-sensor noise and pressure noise propagated through the law) with
    variance 6σ².  Robust (median-based) per bin of predicted flow, so the
    estimate follows flow-dependent noise and ignores the few points where the
    misfit is sharp (the opening flank).  Returns ``{"rmse": σ_floor, "bins":
    [(flow_lo, flow_hi, σ, n)]}`` with σ_floor the RMS over all points.  Every σ is at
    least the rounding of a flow logged on a grid (a meter's display in whole units:
    step/√12, :func:`~pneunet.truth.core.noise.rounding_sigma`), which differences do not
    see where the flow is flat (a closed valve).
    """
    from ...core.noise import robust_sigma, rounding_sigma, second_differences

    d2, idx = second_differences(resid, df["group"].to_numpy(), centres=True)
    if len(idx) < 30:
        return {"rmse": float("nan"), "bins": []}
    rounding = rounding_sigma(df["mdot_mg_s"]) if "mdot_mg_s" in df else 0.0
    m = np.abs(pred[idx])
    mp = np.abs(pred)
    closed_cut = 1.0
    op = m > closed_cut
    edges = [0.0, closed_cut]
    if op.sum() >= 20:
        q = np.quantile(m[op], np.linspace(0, 1, n_bins + 1))[1:]
        edges += list(q)
    edges = np.unique(np.array(edges + [max(mp.max(), m.max()) + 1.0]))
    which = np.clip(np.searchsorted(edges, m, side="right") - 1, 0, len(edges) - 2)
    sig_bin, bins = {}, []
    for b in range(len(edges) - 1):
        sel = which == b
        if sel.sum() < 10:
            continue
        s = max(robust_sigma(d2[sel]), rounding)
        sig_bin[b] = s
        bins.append((float(edges[b]), float(edges[b + 1]), float(s), int(sel.sum())))
    if not sig_bin:
        return {"rmse": float("nan"), "bins": []}
    wall = np.clip(np.searchsorted(edges, mp, side="right") - 1, 0, len(edges) - 2)
    known = np.array(sorted(sig_bin))
    nearest = known[np.abs(known[None, :] - wall[:, None]).argmin(axis=1)]
    sig = np.array([sig_bin[k] for k in nearest])
    return {"rmse": float(np.sqrt(np.mean(sig ** 2))), "bins": bins}
