"""The truth core's autocorrelation gate and sandwich covariance (pneunet.truth.core.intervals)
against their formulas: Ljung–Box as statsmodels computes it, the AR order and
coefficients as statsmodels' ar_select_order/AutoReg give them, the covariance written out
(issue 39; the coverage of the resulting intervals: test_interval_coverage.py)."""
import numpy as np
import pytest


def test_ljung_box_p_is_statsmodels_acorr_ljungbox():
    """The gate between white and sandwich intervals: the smallest p-value over the
    signals equals statsmodels' acorr_ljungbox (10 lags, each signal's mean removed)."""
    from statsmodels.stats.diagnostic import acorr_ljungbox

    from pneunet.truth.core.intervals import ljung_box_p

    rng = np.random.default_rng(7)
    parts = []
    for rho in (0.0, 0.15, 0.3):
        x = np.zeros(300)
        w = rng.standard_normal(300)
        for i in range(1, 300):
            x[i] = rho * x[i - 1] + w[i]
        parts.append(x + 5.0)
    want = [float(acorr_ljungbox(x - x.mean(), lags=[10])["lb_pvalue"].iloc[0]) for x in parts]
    assert ljung_box_p(parts[1]) == pytest.approx(want[1], rel=1e-9)
    groups = np.repeat([2, 0, 1], 300)
    assert ljung_box_p(np.concatenate(parts), groups) == pytest.approx(min(want), rel=1e-9)
    assert np.isnan(ljung_box_p(parts[0][:30]))  # too short for 10 lags: no verdict



def _ar_noise(rng, coeffs, n):
    x, w = np.zeros(n), rng.standard_normal(n)
    for i in range(n):
        x[i] = w[i] + sum(a * x[i - j - 1] for j, a in enumerate(coeffs) if i > j)
    return x


def _whitened(J, r, a):
    """(K, e) written out: eₜ = rₜ − Σ aⱼ rₜ₋ⱼ and Kₛ = Σᵤ hᵤ Jₛ₊ᵤ with h the AR filter's
    impulse response, so that Σ Jₜ rₜ = Σ Kₛ eₛ."""
    n = len(r)
    e = np.array([r[t] - sum(a[j] * r[t - j - 1] for j in range(len(a)) if t > j)
                  for t in range(n)])
    h = np.zeros(n)
    for u in range(n):
        h[u] = 1.0 if u == 0 else sum(a[j] * h[u - j - 1] for j in range(len(a)) if u > j)
    lag = np.subtract.outer(np.arange(n), np.arange(n))  # t − s at [s, t]: negative
    K = np.where(lag <= 0, h[np.abs(lag)], 0.0) @ J
    assert K.T @ e == pytest.approx(J.T @ r, rel=1e-9)  # the identity the estimator rests on
    return K, e


def _reference_sandwich(J, parts):
    """(JᵀJ)⁻¹ Σ Kₛ Kₛᵀ eₛ² (JᵀJ)⁻¹ · n/(n − p) over the signals' (K, e)."""
    n, p = J.shape
    Hinv = np.linalg.inv(J.T @ J)
    S = sum((K * e[:, None]).T @ (K * e[:, None]) for K, e in parts)
    return Hinv @ S @ Hinv * n / (n - p)


def test_sandwich_is_the_ar_prewhitened_formula():
    """AR(2) residuals: the order and coefficients are statsmodels' (ar_select_order by
    AIC over Schwert's 12·(n/100)^¼ = 15 lags, AutoReg on the same sample), the covariance
    the formula written out, the details the residuals' own numbers."""
    from statsmodels.tsa.ar_model import AutoReg, ar_select_order
    from statsmodels.tsa.stattools import acf

    from pneunet.truth.core.intervals import sandwich

    rng = np.random.default_rng(3)
    n = 300
    t = np.linspace(0.0, 6.0, n)
    J = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2), np.ones(n)])
    r = _ar_noise(rng, [0.6, 0.25], n)
    assert ar_select_order(r, maxlag=15, ic="aic", trend="n").ar_lags == [1, 2]
    a = AutoReg(r, lags=2, trend="n", hold_back=15).fit().params
    K, e = _whitened(J, r, a)
    cov, info = sandwich(J, r)
    np.testing.assert_allclose(cov, _reference_sandwich(J, [(K, e)]), rtol=1e-9)
    assert info["ar_order"] == 2 and info["ar_sum"] == pytest.approx(a.sum(), rel=1e-12)
    assert info["rho1"] == pytest.approx(acf(r, nlags=1)[1], rel=1e-12)
    long_run = float(e @ e) / (1 - a.sum()) ** 2
    assert info["dof_eff"] == pytest.approx(n * np.sum((r - r.mean()) ** 2) / long_run,
                                            rel=1e-9)


def test_sandwich_of_ar1_residuals_corrects_the_coefficients_bias():
    """An AR(1) of least-squares residuals is biased low (Kendall: −(1+3ρ)/n after a
    mean; −(p·(1+ρ) + 2ρ)/n after p smooth parameters): ρ̂ + that is used."""
    from statsmodels.tsa.ar_model import AutoReg, ar_select_order

    from pneunet.truth.core.intervals import sandwich

    rng = np.random.default_rng(11)
    n = 400
    t = np.linspace(0.0, 6.0, n)
    J = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2)])
    r = _ar_noise(rng, [0.5], n)
    kmax = int(12 * (n / 100) ** 0.25)
    assert ar_select_order(r, maxlag=kmax, ic="aic", trend="n").ar_lags == [1]
    rho = AutoReg(r, lags=1, trend="n", hold_back=kmax).fit().params[0]
    a = np.array([rho + (2 * (1 + rho) + 2 * rho) / n])
    cov, info = sandwich(J, r)
    assert info["ar_order"] == 1 and info["ar_sum"] == pytest.approx(a[0], rel=1e-12)
    np.testing.assert_allclose(cov, _reference_sandwich(J, [_whitened(J, r, a)]), rtol=1e-9)


def test_sandwich_keeps_each_signal_to_itself():
    """Two signals: one AR pooled over both (least squares on the stacked lags), no lag
    crossing from one signal to the other, the rows' order between the signals
    irrelevant; a random walk's AR is kept stationary (its roots inside |z| ≤ 0.99)."""
    from pneunet.truth.core.intervals import _autoregression, sandwich

    rng = np.random.default_rng(7)
    n, kmax = 200, 14
    t = np.linspace(0.0, 6.0, n)
    J1 = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2)])
    J2 = np.column_stack([0.5 * np.exp(-t / 2), np.zeros(n)])
    r1, r2 = _ar_noise(rng, [0.5], n), _ar_noise(rng, [0.5], n)
    J, r, groups = np.vstack([J1, J2]), np.concatenate([r1, r2]), np.repeat([0, 1], n)
    cov, info = sandwich(J, r, groups)
    assert info["ar_order"] == 1
    lagged = np.concatenate([r1[kmax - 1:-1], r2[kmax - 1:-1]])
    rho = float(lagged @ np.concatenate([r1[kmax:], r2[kmax:]]) / (lagged @ lagged))
    a = np.array([rho + (2 * (1 + rho) + 2 * rho * 2) / (2 * n)])
    assert info["ar_sum"] == pytest.approx(a[0], rel=1e-12)
    want = _reference_sandwich(J, [_whitened(J1, r1, a), _whitened(J2, r2, a)])
    np.testing.assert_allclose(cov, want, rtol=1e-9)
    # the same rows interleaved (signal 0, 1, 0, 1, ...): the same covariance
    order = np.argsort(np.r_[np.arange(n), np.arange(n)] * 2 + groups, kind="stable")
    np.testing.assert_allclose(sandwich(J[order], r[order], groups[order])[0], cov,
                               rtol=1e-12)
    walk, k, _ = _autoregression([np.cumsum(rng.standard_normal(500))], 2)
    assert k >= 1 and np.max(np.abs(np.roots(np.r_[1.0, -walk]))) <= 0.99 + 1e-12


def _white_se(J, r):
    n, p = J.shape
    return np.sqrt(np.diag(float(r @ r) / (n - p) * np.linalg.inv(J.T @ J)))


@pytest.mark.parametrize("confidence", [0.95, 0.9])
def test_intervals_are_estimate_plus_minus_student_t_standard_errors(confidence):
    """White residuals: s.e. √(s²·diag (JᵀJ)⁻¹), s² = rᵀr/(n − p), Student t with n − p
    degrees of freedom; ends exp(x ∓ t·s.e.) for ln-parameters, x ∓ t·s.e. otherwise."""
    from scipy import stats

    from pneunet.truth.core.intervals import intervals

    rng = np.random.default_rng(2)
    n = 40
    J = np.column_stack([np.ones(n), np.linspace(0.0, 1.0, n)])
    r = rng.standard_normal(n)
    x = np.array([np.log(5.0), np.log(0.2)])
    ci, se, info = intervals(x, J, r, ["a", "b"], confidence=confidence)
    assert info["method"] == "white" and info["ljung_box_p"] >= 0.01
    want_se = _white_se(J, r)
    tq = stats.t.ppf(0.5 + confidence / 2, n - 2)
    assert [se["a"], se["b"]] == pytest.approx(want_se, rel=1e-12)
    assert ci["a"] == pytest.approx(np.exp(x[0] + np.array([-1, 1]) * tq * want_se[0]),
                                    rel=1e-12)
    assert info["dof"] == n - 2 and info["s"] == pytest.approx(np.sqrt(r @ r / (n - 2)))
    lin, _, _ = intervals(x, J, r, ["a", "b"], confidence=confidence, log=False)
    assert lin["b"] == pytest.approx(x[1] + np.array([-1, 1]) * tq * want_se[1], rel=1e-12)


@pytest.mark.parametrize("rho", [0.8, -0.6])
def test_autocorrelated_intervals_use_the_sandwich_never_narrower_than_white(rho):
    """Ljung–Box p < 0.01: s.e. the larger of the sandwich's and the white one (positive
    correlation widens; negative would narrow and is not allowed to), Student t with the
    effective degrees of freedom less p."""
    from scipy import stats

    from pneunet.truth.core.intervals import intervals, sandwich

    rng = np.random.default_rng(4)
    n = 200
    t = np.linspace(0.0, 6.0, n)
    J = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2)])
    r = _ar_noise(rng, [rho], n)
    x = np.array([1.0, 2.0])
    ci, se, info = intervals(x, J, r, ["a", "b"], log=False)
    assert info["method"] == "hac" and info["ljung_box_p"] < 0.01
    cov, hac = sandwich(J, r)
    hac_se, white = np.sqrt(np.diag(cov)), _white_se(J, r)
    assert (hac_se > white).all() if rho > 0 else (hac_se < white).all()
    want = np.maximum(hac_se, white)
    assert [se["a"], se["b"]] == pytest.approx(want, rel=1e-12)
    assert info["dof"] == pytest.approx(hac["dof_eff"] - 2, rel=1e-12)
    tq = stats.t.ppf(0.975, hac["dof_eff"] - 2)
    assert ci["b"] == pytest.approx(x[1] + np.array([-1, 1]) * tq * want[1], rel=1e-12)


def test_sandwich_of_short_signals_and_of_a_perfect_fit():
    """Signals of 20 samples: at most 20 // 4 = 5 lags (statsmodels' reference with that
    maxlag); residuals all zero: a zero covariance with n degrees of freedom; an explosive
    least-squares AR is pulled back to its largest root at exactly 0.99."""
    from statsmodels.tsa.ar_model import AutoReg, ar_select_order

    from pneunet.truth.core.intervals import _autoregression, sandwich

    rng = np.random.default_rng(8)
    n = 20
    J = np.column_stack([np.ones(n), np.linspace(0.0, 1.0, n)])
    r = _ar_noise(rng, [0.4], n)
    k = len(ar_select_order(r, maxlag=5, ic="aic", trend="n").ar_lags)
    a = AutoReg(r, lags=k, trend="n", hold_back=5).fit().params if k else np.zeros(0)
    if k == 1:
        a = a + (2 * (1 + a) + 2 * a) / n
    cov, info = sandwich(J, r)
    assert info["ar_order"] == k
    np.testing.assert_allclose(cov, _reference_sandwich(J, [_whitened(J, r, a)]), rtol=1e-9)
    cov, info = sandwich(J, np.zeros(n))
    assert not cov.any() and info["dof_eff"] == n
    for coeffs in ([1.02], [0.5, 0.6]):  # largest roots 1.02 and 1.064
        boom = _ar_noise(np.random.default_rng(0), coeffs, 300)
        a, k, _ = _autoregression([boom], 2)
        assert k == len(coeffs)
        assert np.max(np.abs(np.roots(np.r_[1.0, -a]))) == pytest.approx(0.99, abs=1e-9)


def test_ar_order_and_coefficients_are_statsmodels_at_any_scale():
    """AR(3) residuals in kPa, Pa or MPa: the order statsmodels' AIC picks (3; the penalty
    2 per coefficient), the same coefficients, a covariance scaling with the square."""
    from statsmodels.tsa.ar_model import AutoReg, ar_select_order

    from pneunet.truth.core.intervals import sandwich

    n = 300
    t = np.linspace(0.0, 6.0, n)
    J = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2)])
    r = _ar_noise(np.random.default_rng(0), [0.5, -0.3, 0.4], n)
    assert ar_select_order(r, maxlag=15, ic="aic", trend="n").ar_lags == [1, 2, 3]
    a = AutoReg(r, lags=3, trend="n", hold_back=15).fit().params
    want = _reference_sandwich(J, [_whitened(J, r, a)])
    details = sandwich(J, r)[1]
    for scale in (1e-3, 1.0, 1e3):
        cov, info = sandwich(J, scale * r)
        assert info["ar_order"] == 3 and info["ar_sum"] == pytest.approx(a.sum(), rel=1e-9)
        np.testing.assert_allclose(cov, scale ** 2 * want, rtol=1e-9)
        assert info["dof_eff"] == pytest.approx(details["dof_eff"], rel=1e-9)
        assert info["rho1"] == pytest.approx(details["rho1"], rel=1e-9)


def test_white_residuals_give_the_heteroskedasticity_consistent_sandwich():
    """AR order 0 (white): (JᵀJ)⁻¹ Σ Jₜ Jₜᵀ rₜ² (JᵀJ)⁻¹ · n/(n − p), White's HC1."""
    from pneunet.truth.core.intervals import sandwich

    n = 300
    J = np.column_stack([np.ones(n), np.linspace(0.0, 1.0, n)])
    r = np.random.default_rng(0).standard_normal(n)
    cov, info = sandwich(J, r)
    assert info["ar_order"] == 0 and info["ar_sum"] == 0.0
    Hinv = np.linalg.inv(J.T @ J)
    want = Hinv @ (J * r[:, None] ** 2).T @ J @ Hinv * n / (n - 2)
    np.testing.assert_allclose(cov, want, rtol=1e-9)


def test_negatively_correlated_residuals_keep_their_coefficient_and_n_dof():
    """ρ̂ < 0: no bias correction (it is for the positive correlation a fit hides); the
    effective degrees of freedom are at most n."""
    from statsmodels.tsa.ar_model import AutoReg

    from pneunet.truth.core.intervals import sandwich

    n = 300
    J = np.column_stack([np.ones(n), np.linspace(0.0, 1.0, n)])
    r = _ar_noise(np.random.default_rng(0), [-0.6], n)
    cov, info = sandwich(J, r)
    a = AutoReg(r, lags=1, trend="n", hold_back=15).fit().params
    assert info["ar_order"] == 1 and info["ar_sum"] == pytest.approx(a[0], rel=1e-12)
    np.testing.assert_allclose(cov, _reference_sandwich(J, [_whitened(J, r, a)]), rtol=1e-9)
    assert info["dof_eff"] == n


def test_ljung_box_needs_more_than_three_times_its_lags():
    from pneunet.truth.core.intervals import ljung_box_p

    r = np.random.default_rng(0).standard_normal(31)
    assert 0.0 < ljung_box_p(r) <= 1.0
    assert np.isnan(ljung_box_p(r[:30])) and np.isnan(ljung_box_p(r[:20]))


def test_ar_order_is_statsmodels_aic_choice_on_forty_records():
    """40 records of 120 samples, random AR(4) coefficients in ±0.3: the order chosen is
    statsmodels' ar_select_order (AIC, at most 12 lags) every time (orders 0 to 9 here)."""
    from statsmodels.tsa.ar_model import ar_select_order

    from pneunet.truth.core.intervals import _autoregression

    rng = np.random.default_rng(1)
    records = [_ar_noise(rng, rng.uniform(-0.3, 0.3, 4), 120) for _ in range(40)]
    want = [len(ar_select_order(x, maxlag=12, ic="aic", trend="n").ar_lags or [])
            for x in records]
    assert len(set(want)) >= 5
    assert [_autoregression([x], 2)[1] for x in records] == want


def test_intervals_keep_at_least_one_degree_of_freedom():
    """Three points and two parameters: one degree of freedom, s² = rᵀr/1, t(1) = 12.71;
    two points: a zero residual, still one (not 0, not a division by zero); residuals
    like a random walk (effective dof 1.1 − 2 parameters): one."""
    from scipy import stats

    from pneunet.truth.core.intervals import intervals

    J = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]])
    r = np.array([0.5, -1.0, 0.5])
    ci, se, info = intervals(np.zeros(2), J, r, ["a", "b"], log=False)
    assert info["dof"] == 1.0 and info["s"] == pytest.approx(np.sqrt(1.5), rel=1e-12)
    want = np.sqrt(1.5 * np.linalg.inv(J.T @ J)[0, 0])
    assert ci["a"] == pytest.approx((-12.7062 * want, 12.7062 * want), rel=1e-5)
    ci, se, info = intervals(np.ones(2), J[:2], np.zeros(2), ["a", "b"], log=False)
    assert info["dof"] == 1.0 and ci["a"] == (1.0, 1.0)
    n = 200
    t = np.linspace(0.0, 6.0, n)
    J = np.column_stack([np.exp(-t / 2), t * np.exp(-t / 2)])
    walk = np.cumsum(np.random.default_rng(1).standard_normal(n))
    ci, se, info = intervals(np.zeros(2), J, walk, ["a", "b"], log=False)
    assert info["method"] == "hac" and info["dof_eff"] < 3 and info["dof"] == 1.0
    assert ci["b"][1] == pytest.approx(stats.t.ppf(0.975, 1) * se["b"], rel=1e-12)
