"""Confidence intervals of least-squares estimates that are honest about the residuals.

White residuals (the Ljung–Box test of statsmodels finds no autocorrelation) give the
ordinary linearised interval s²(JᵀJ)⁻¹ with Student t.  Autocorrelated residuals
(model error, a sampling rate far above the noise bandwidth) give the Newey–West
sandwich (JᵀJ)⁻¹ S (JᵀJ)⁻¹ with the effective degrees of freedom n(1−ρ₁)/(1+ρ₁), never
narrower than the white one; the result says which and why.
"""
from __future__ import annotations

import math

import numpy as np

#: Ljung–Box p-value below which the residuals count as autocorrelated
WHITE_P = 0.01


def ljung_box_p(r, groups=None, lags: int = 10) -> float:
    """Smallest Ljung–Box p-value (``lags`` lags) over the groups of ``r`` (signals)."""
    from statsmodels.stats.diagnostic import acorr_ljungbox

    r = np.asarray(r, float)
    parts = [r] if groups is None else [r[np.asarray(groups) == g] for g in np.unique(groups)]
    ps = []
    for part in parts:
        if len(part) > 3 * lags:
            ps.append(float(acorr_ljungbox(part - part.mean(), lags=[lags])["lb_pvalue"].iloc[0]))
    return min(ps) if ps else float("nan")


def newey_west(J, r, groups=None, lags: int | None = None):
    """Sandwich covariance of the parameters and its details (see the module doc).

    ``groups`` labels the rows by signal; lags never cross from one signal to the next."""
    n, p = J.shape
    g_ids = np.zeros(n, int) if groups is None else np.unique(groups, return_inverse=True)[1]
    rs = [r[g_ids == k] for k in range(g_ids.max() + 1)]
    Js = [J[g_ids == k] for k in range(g_ids.max() + 1)]
    var = sum(float(np.sum((x - x.mean()) ** 2)) for x in rs)
    m = min(len(x) for x in rs)
    maxlag = max(1, m // 4)

    def acf(lag):
        if var <= 0:
            return 0.0
        return sum(float(np.sum((x[lag:] - x.mean()) * (x[:len(x) - lag] - x.mean())))
                   for x in rs) / var

    rho = np.array([acf(lag) for lag in range(min(maxlag, 60) + 1)])
    rho1 = float(np.clip(rho[1], -0.99, 0.99)) if len(rho) > 1 else 0.0
    if lags is None:
        below = np.nonzero(np.abs(rho) < 0.1)[0]
        first = int(below[0]) if below.size else len(rho) - 1
        lags = int(min(maxlag, max(first, math.floor(4 * (m / 100) ** (2 / 9)))))
    S = np.zeros((p, p))
    for x, Jk in zip(rs, Js):
        g = Jk * x[:, None]
        S += g.T @ g
        for lag in range(1, lags + 1):
            w = 1 - lag / (lags + 1)
            G = g[lag:].T @ g[:-lag]
            S += w * (G + G.T)
    Hinv = np.linalg.pinv(J.T @ J)
    cov = Hinv @ S @ Hinv * n / max(n - p, 1)
    dof = n * (1 - max(rho1, 0.0)) / (1 + max(rho1, 0.0))
    return cov, {"lags": int(lags), "rho1": rho1, "dof_eff": float(dof)}


def intervals(x, J, r, names, *, groups=None, confidence: float = 0.95, log: bool = True):
    """Confidence intervals of the parameters ``x`` (ln values when ``log``).

    Returns (ci {name: (low, high)}, stderr {name: s.e. of x}, info) where info tells
    the method (``white`` or ``newey-west``), the Ljung–Box p-value and a note."""
    from scipy import stats

    n, p = J.shape
    s2 = float(r @ r) / max(n - p, 1)
    JtJ_inv = np.linalg.pinv(J.T @ J)
    se_white = np.sqrt(np.maximum(np.diag(s2 * JtJ_inv), 0))
    p_lb = ljung_box_p(r, groups)
    if not (math.isfinite(p_lb) and p_lb < WHITE_P):
        se, dof = se_white, max(n - p, 1)
        info = {"method": "white", "ljung_box_p": p_lb,
                "note": f"residuals white (Ljung–Box p = {p_lb:.2g}): ordinary linearised "
                        "intervals"}
    else:
        cov, nw = newey_west(J, r, groups)
        se = np.maximum(np.sqrt(np.maximum(np.diag(cov), 0)), se_white)
        dof = max(nw["dof_eff"] - p, 1.0)
        info = {"method": "newey-west", "ljung_box_p": p_lb, **nw,
                "note": f"residuals autocorrelated (Ljung–Box p = {p_lb:.2g}, lag-1 "
                        f"correlation {nw['rho1']:.2f}: model error or coloured noise): "
                        "Newey–West sandwich intervals, widened accordingly"}
    tq = stats.t.ppf(0.5 + confidence / 2, dof)
    conv = np.exp if log else (lambda v: v)
    with np.errstate(over="ignore"):  # an unbounded end is inf (JSON writers say null)
        ci = {k: (float(conv(x[i] - tq * se[i])), float(conv(x[i] + tq * se[i])))
              for i, k in enumerate(names)}
    info["s"] = math.sqrt(s2)
    info["dof"] = float(dof)
    return ci, dict(zip(names, map(float, se))), info
