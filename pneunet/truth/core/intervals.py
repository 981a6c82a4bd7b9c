"""Confidence intervals of least-squares estimates that are honest about the residuals.

White residuals (the Ljung–Box test of statsmodels finds no autocorrelation) give the
ordinary linearised interval s²(JᵀJ)⁻¹ with Student t.  Autocorrelated residuals
(model error, a sampling rate far above the noise bandwidth) give a sandwich
(JᵀJ)⁻¹ S (JᵀJ)⁻¹ whose middle S comes from an autoregression of the residuals
(den Haan and Levin's VARHAC; Andrews and Monahan's prewhitening): AR(k), k by AIC, leaves
white innovations e; the score sum Σ Jₜ rₜ is then exactly Σ Kₛ eₛ with Kₛ the Jacobian
recoloured by the AR filter, so S = Σ Kₛ Kₛᵀ eₛ².  Never narrower than the white interval;
Student t with the effective degrees of freedom n·var(r)/(long-run variance); the result
says which and why.

Why not a kernel (Newey–West, statsmodels' ``cov_hac``): the parameters' scores sum to
zero at the least-squares solution, so a kernel's estimate of S shrinks as its window
grows, while a short window truncates the autocorrelation.  On AR(1) noise (ρ = 0.5, 200
samples, an exponential's two parameters) Bartlett intervals were 0.78–0.86× the
estimator's spread at any window (85 % coverage); these are 0.99–1.00× (93 %).
"""
from __future__ import annotations

import math

import numpy as np

#: Ljung–Box p-value below which the residuals count as autocorrelated
WHITE_P = 0.01
#: a direction of the (ln-)parameter space whose singular value of J is below this
#: fraction of the largest is not determined by the record: an exact invariance of the
#: model (a tube's R and volume feeding a dead end: only R·V sets its time constant)
#: leaves it at round-off, 1e-8 of the largest and below
UNDETERMINED = 1e-6
#: a parameter's share of an undetermined direction above which its interval is
#: unbounded (smaller shares are round-off of the singular vectors)
UNDETERMINED_SHARE = 1e-3
#: a direction v with ‖J·v‖ below this many times ‖(J − J_other side)·v‖ is undetermined:
#: finite-difference noise alone gives 0.3–0.6 (two tanks' R·V, all four fitted: 0.32),
#: a noiseless determined direction 1/(step × relative curvature) (two time constants
#: 5 % apart at a step of 0.005 in ln x: 91; with 1e-5 of noise in each evaluation: 3.1)
NOISE_RATIO = 1.0
#: the share of a direction found by :data:`NOISE_RATIO` below which a parameter is
#: not in it: the differences' noise mixes others in (0.0015 of the logger's clock in
#: the two tanks' R·V)
NOISE_SHARE = 0.02


def inverse_normal_matrix(J, spread=None):
    """(JᵀJ)⁻¹ from the singular values of J (no squaring of its condition number), the
    undetermined directions (unit vectors v with J·v ≈ 0) and the inverse on the
    determined directions alone.  Along an undetermined direction the variance is
    infinite, not dropped as a pseudo-inverse would drop it (which gives the parameters
    on it intervals of zero width).

    A direction is undetermined where its singular value is below :data:`UNDETERMINED`
    of the largest, or, given ``spread`` (J minus the Jacobian from differences on each
    parameter's other side), where J·v is within :data:`NOISE_RATIO` of spread·v: a
    Jacobian of finite differences through a simulator carries the simulation's error
    divided by the step, and along an exact invariance of the model (every resistance
    ×k and every volume ÷k of a circuit whose flows are not recorded) that noise is all
    J·v holds; along a determined direction J·v is the response and spread·v its
    curvature, a step's fraction of it."""
    _, sv, vt = np.linalg.svd(J, full_matrices=False)
    free = sv <= UNDETERMINED * (sv[0] if sv.size else 0.0)
    for k in noise_directions(sv, vt, spread, free):
        free[k] = True
        vt[k] = np.where(np.abs(vt[k]) < NOISE_SHARE, 0.0, vt[k])
        vt[k] /= np.linalg.norm(vt[k])
    inv_sq = np.divide(1.0, sv ** 2, out=np.zeros_like(sv), where=~free)
    determined = (vt.T * inv_sq) @ vt
    cov = determined.copy()
    directions = [v for v in vt[free]]
    for v in directions:
        hit = np.abs(v) > UNDETERMINED_SHARE
        cov[hit, :] = cov[:, hit] = 0.0
        cov[hit, hit] = np.inf
    return cov, directions, determined


def noise_directions(sv, vt, spread, free=None, ratio: float = NOISE_RATIO) -> list[int]:
    """Indices of the right singular vectors ``vt`` of J (singular values ``sv``) along
    which J·v is within ``ratio`` of ``spread``·v, weakest first, stopping at the first
    that is not (``free``: those already undetermined by round-off, skipped); [] without
    a spread."""
    if spread is None:
        return []
    out = []
    for k in range(len(sv) - 1, 0, -1):  # from the smallest: the weakest first
        if free is not None and free[k]:
            continue
        if sv[k] > ratio * float(np.linalg.norm(spread @ vt[k])):
            break
        out.append(k)
    return out


def sandwich_of(bread, meat):
    """bread·meat·bread, with an undetermined direction's infinite variance kept infinite
    (inf·0 would give NaN)."""
    with np.errstate(invalid="ignore"):
        cov = bread @ meat @ bread
    cov[np.isnan(cov)] = np.inf
    return cov


#: ln of the largest float: a combination whose interval reaches past it is no more
#: determined than its parameters
_LN_MAX = math.log(np.finfo(float).max)


def combinations(directions, names, x, covs, tq, log=True) -> list[dict]:
    """What the record does determine along each undetermined direction of two
    parameters: a·b^k (k = −v_a/v_b: the product for k = 1, the ratio for −1) with its
    value and interval (``covs``: covariances on the determined directions, the widest
    of them counts, as in :func:`intervals`; ``tq``: the interval's quantile).  Longer
    directions, and a combination whose interval reaches past the floats (a·b^69): only
    who moves."""
    out = []
    for v in directions:
        idx = [int(i) for i in np.argsort(-np.abs(v)) if abs(v[i]) > UNDETERMINED_SHARE]
        who = [names[i] for i in idx]
        if len(idx) != 2:
            out.append({"parameters": who})
            continue
        (i, j), (a, b) = idx, who
        k = -v[i] / v[j]
        w = np.zeros(len(x))
        w[i], w[j] = 1.0, k
        c, se = float(w @ x), math.sqrt(max(max(float(w @ cov @ w) for cov in covs), 0.0))
        if log and not abs(c) + tq * se < _LN_MAX:  # nor is the combination determined
            out.append({"parameters": who})
            continue
        conv = math.exp if log else (lambda u: u)
        power = "" if abs(abs(k) - 1) < 0.005 else f"^{abs(k):.2g}"
        expr = f"{a}{'·' if k > 0 else '/'}{b}{power}"
        out.append({"parameters": who, "combination": expr, "value": conv(c),
                    "ci": (conv(c - tq * se), conv(c + tq * se))})
    return out


def undetermined_note(combos) -> str:
    """Plain words for each undetermined direction (:func:`combinations`): which
    parameters the record cannot tell apart, and what it does determine."""
    out = []
    for c in combos:
        if "combination" in c:
            a, b = c["parameters"]
            lo, hi = c["ci"]
            out.append(f"{a} and {b} are not separately determined by the record (their "
                       f"intervals are unbounded), only {c['combination']} = "
                       f"{c['value']:.4g} [{lo:.4g}, {hi:.4g}] is")
        else:
            out.append(", ".join(c["parameters"]) + " move together without changing the "
                       "fit (not separately determined): their intervals are unbounded; "
                       "fix one of them (--set NAME=VALUE) to determine the others")
    return "; ".join(out)


def ljung_box_p(r, groups=None, lags: int = 10) -> float:
    """Smallest Ljung–Box p-value (``lags`` lags) over the groups of ``r`` (signals).

    statsmodels' ``acorr_ljungbox`` with its autocorrelations through the FFT (its own
    direct sum costs 18 s on 60,000 samples)."""
    from scipy import stats
    from statsmodels.tsa.stattools import acf

    r = np.asarray(r, float)
    parts = [r] if groups is None else [r[np.asarray(groups) == g] for g in np.unique(groups)]
    ps = []
    for part in parts:
        n = len(part)
        if n > 3 * lags:
            rho = acf(part - part.mean(), nlags=lags, fft=True)[1:]
            q = n * (n + 2) * float(np.sum(rho ** 2 / (n - np.arange(1, lags + 1))))
            ps.append(float(stats.chi2.sf(q, lags)))
    return min(ps) if ps else float("nan")


def _autoregression(rs, p: int):
    """AR coefficients of the residual groups ``rs`` (pooled least squares, order by AIC up
    to Schwert's 12·(m/100)^¼ lags), the order chosen and the lag-1 autocorrelation.

    An AR(1) is corrected for its least-squares bias, −(p·(1+ρ) + 2ρ·G)/n for ``p`` fitted
    parameters and G groups (Kendall's −(1+3ρ)/n when the fit is a mean); roots are kept
    inside |z| ≤ 0.99."""
    n, m = sum(len(x) for x in rs), min(len(x) for x in rs)
    kmax = max(1, min(m // 4, int(12 * (m / 100) ** 0.25), 30))
    y = np.concatenate([x[kmax:] for x in rs])
    X = np.vstack([np.column_stack([x[kmax - j:len(x) - j] for j in range(1, kmax + 1)])
                   for x in rs])
    Q, R = np.linalg.qr(X)
    b = Q.T @ y
    rss = float(y @ y) - np.concatenate([[0.0], np.cumsum(b ** 2)])
    aic = len(y) * np.log(np.maximum(rss, 1e-300) / len(y)) + 2 * np.arange(kmax + 1)
    k = int(np.argmin(aic))
    a = np.linalg.lstsq(R[:k, :k], b[:k], rcond=None)[0] if k else np.zeros(0)
    if k == 1 and a[0] > 0:
        a = a + (p * (1 + a) + 2 * a * len(rs)) / n
    if k:
        root = float(np.max(np.abs(np.roots(np.r_[1.0, -a]))))
        if root > 0.99:  # z ↦ c·z: coefficient j scaled by c^j
            a = a * (0.99 / root) ** np.arange(1, k + 1)
    cs = [x - x.mean() for x in rs]
    rho1 = float(sum(float(c[1:] @ c[:-1]) for c in cs)
                 / max(sum(float(c @ c) for c in cs), 1e-300))
    return a, k, rho1


def sandwich(J, r, groups=None, determined=None):
    """AR-prewhitened sandwich covariance of the parameters and its details (see the
    module doc).  ``groups`` labels the rows by signal; no lag crosses from one signal to
    the next.  ``determined``: a (JᵀJ)⁻¹ of the determined directions to use instead
    (:func:`inverse_normal_matrix`)."""
    from scipy.signal import lfilter

    n, p = J.shape
    g_ids = np.zeros(n, int) if groups is None else np.unique(groups, return_inverse=True)[1]
    rs = [r[g_ids == k] for k in range(g_ids.max() + 1)]
    Js = [J[g_ids == k] for k in range(g_ids.max() + 1)]
    a, k, rho1 = _autoregression(rs, p)
    poly = np.r_[1.0, -a]
    S = np.zeros((p, p))
    e2 = 0.0
    for x, Jk in zip(rs, Js):
        e = lfilter(poly, [1.0], x)  # innovations: r = lfilter(1, poly, e) exactly
        K = lfilter([1.0], poly, Jk[::-1], axis=0)[::-1]  # Σₜ Jₜ rₜ = Σₛ Kₛ eₛ
        g = K * e[:, None]
        S += g.T @ g
        e2 += float(e @ e)
    bread = inverse_normal_matrix(J)[0] if determined is None else determined
    cov = sandwich_of(bread, S) * (n / max(n - p, 1))
    var = sum(float(np.sum((x - x.mean()) ** 2)) for x in rs)
    long_run = e2 / (1.0 - float(a.sum())) ** 2
    dof = n * min(var / long_run, 1.0) if long_run > 0 else float(n)
    return cov, {"ar_order": k, "ar_sum": float(a.sum()), "rho1": rho1, "dof_eff": dof}


def intervals(x, J, r, names, *, groups=None, confidence: float = 0.95, log: bool = True,
              spread=None):
    """Confidence intervals of the parameters ``x`` (ln values when ``log``); ``spread``
    as in :func:`inverse_normal_matrix`.

    Returns (ci {name: (low, high)}, stderr {name: s.e. of x}, info) where info tells
    the method (``white`` or ``hac``), the Ljung–Box p-value and a note."""
    from scipy import stats

    n, p = J.shape
    s2 = float(r @ r) / max(n - p, 1)
    JtJ_inv, undetermined, determined = inverse_normal_matrix(J, spread)
    se_white = np.sqrt(np.maximum(np.diag(s2 * JtJ_inv), 0))
    p_lb = ljung_box_p(r, groups)
    covs = [s2 * determined]  # on the determined directions (their combinations' intervals)
    if not (math.isfinite(p_lb) and p_lb < WHITE_P):
        se, dof = se_white, max(n - p, 1)
        info = {"method": "white", "ljung_box_p": p_lb,
                "note": f"residuals white (Ljung–Box p = {p_lb:.2g}): ordinary linearised "
                        "intervals"}
    else:
        cov, hac = sandwich(J, r, groups, determined)
        covs.append(cov)
        # an undetermined direction's infinite variance comes in through se_white
        se = np.maximum(np.sqrt(np.maximum(np.diag(cov), 0)), se_white)
        dof = max(hac["dof_eff"] - p, 1.0)
        info = {"method": "hac", "ljung_box_p": p_lb, **hac,
                "note": f"residuals autocorrelated (Ljung–Box p = {p_lb:.2g}, lag-1 "
                        f"correlation {hac['rho1']:.2f}: model error or coloured noise): "
                        f"sandwich intervals through an AR({hac['ar_order']}) of the "
                        "residuals, widened accordingly"}
    tq = stats.t.ppf(0.5 + confidence / 2, dof)
    if undetermined:
        info["undetermined"] = combinations(undetermined, names, x, covs, tq, log)
        info["undetermined_note"] = undetermined_note(info["undetermined"])
        info["note"] += "; " + info["undetermined_note"]
    conv = np.exp if log else (lambda v: v)
    with np.errstate(over="ignore"):  # an unbounded end is inf (JSON writers say null)
        ci = {k: (float(conv(x[i] - tq * se[i])), float(conv(x[i] + tq * se[i])))
              for i, k in enumerate(names)}
    info["s"] = math.sqrt(s2)
    info["dof"] = float(dof)
    return ci, dict(zip(names, map(float, se))), info
