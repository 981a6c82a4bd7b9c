"""Where a residual sits: which signal, which part of the cycle, and whether the
recording leads or lags the model there."""
from __future__ import annotations

import numpy as np


def phase_profile(phase, resid, bins: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """(bin centres, rms of ``resid`` per phase bin); NaN where a bin is empty."""
    edges = np.linspace(0, 1, bins + 1)
    idx = np.digitize(phase, edges) - 1
    ok = np.isfinite(resid) & (idx >= 0) & (idx < bins)
    rms = np.full(bins, np.nan)
    for i in range(bins):
        sel = ok & (idx == i)
        if sel.any():
            rms[i] = float(np.sqrt(np.mean(resid[sel] ** 2)))
    return 0.5 * (edges[1:] + edges[:-1]), rms


def best_lag(t, measured, model, max_lag: float, mask=None) -> float:
    """Time shift (s) that best aligns ``model`` with ``measured`` (positive: the
    recording lags the model), least squares over shifts up to ± ``max_lag``."""
    t = np.asarray(t, float)
    dt = float(np.median(np.diff(t)))
    ok = np.ones(len(t), bool) if mask is None else np.asarray(mask, bool)
    shifts = np.linspace(-max_lag, max_lag, 2 * int(round(max_lag / (dt / 4))) + 1)
    cost = [np.nanmean((np.interp(t[ok] - s, t, model) - measured[ok]) ** 2) for s in shifts]
    return float(shifts[int(np.nanargmin(cost))])


def hot_phases(centres, rms, floor: float, share: float = 0.5) -> list[tuple[float, float]]:
    """Phase intervals (from, to) of the bins that together carry ``share`` of the excess
    squared error above ``floor``, merged where adjacent."""
    excess = np.nan_to_num(np.maximum(rms ** 2 - floor ** 2, 0.0))
    if excess.sum() <= 0:
        return []
    order = np.argsort(-excess)
    keep = order[:int(np.searchsorted(np.cumsum(excess[order]) / excess.sum(), share) + 1)]
    width = centres[1] - centres[0] if len(centres) > 1 else 1.0
    out = []
    for i in sorted(keep):
        lo, hi = centres[i] - width / 2, centres[i] + width / 2
        if out and abs(out[-1][1] - lo) < 1e-9:
            out[-1] = (out[-1][0], hi)
        else:
            out.append((lo, hi))
    return out
