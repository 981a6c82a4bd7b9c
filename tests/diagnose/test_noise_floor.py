"""The noise floor from second differences (pneunet.truth.core.noise) against its formulas and
on a stand-alone record: white noise of known σ under a smooth misfit, with a few sharp
places, and records cut into groups (issue 39: the module had no direct test)."""
import numpy as np
import pytest

from pneunet.truth.core.noise import (MAD_TO_SIGMA, difference_sigma, robust_sigma,
                                      second_differences, segments)


def test_second_differences_by_hand_and_within_groups():
    r = np.array([1.0, 4.0, 9.0, 16.0, 25.0, 30.0])
    np.testing.assert_array_equal(second_differences(r), [2.0, 2.0, 2.0, -4.0])
    d2, centres = second_differences(r, centres=True)
    np.testing.assert_array_equal(centres, [1, 2, 3, 4])
    # a difference whose three samples are not all in one group is left out
    d2, centres = second_differences(r, groups=[0, 0, 0, 1, 1, 1], centres=True)
    np.testing.assert_array_equal(d2, [2.0, -4.0])
    np.testing.assert_array_equal(centres, [1, 4])
    for labels in ([1, 1, 1, 0, 0, 0], [5, 5, 5, 7, 7, 7]):  # any labels, any order
        np.testing.assert_array_equal(second_differences(r, labels, centres=True)[1], [1, 4])
    # a NaN sample drops the three differences it is in
    d2, centres = second_differences([0.0, 1.0, np.nan, 9.0, 16.0, 25.0, 36.0], centres=True)
    np.testing.assert_array_equal(centres, [4, 5])
    assert second_differences([1.0, 4.0, 9.0]).tolist() == [2.0]  # three samples: one
    for short in ([1.0, 2.0], [1.0], []):
        assert second_differences(short).size == 0
        assert [a.size for a in second_differences(short, centres=True)] == [0, 0]


def test_robust_sigma_is_the_normalised_mad_over_root_six():
    d2 = np.array([-3.0, 1.0, 2.0, -0.5, 6.0])  # median |d2| = 2
    assert robust_sigma(d2) == pytest.approx(1.4826 * 2.0 / np.sqrt(6.0), rel=1e-12)
    assert MAD_TO_SIGMA == pytest.approx(1 / 0.6744897501960817, rel=1e-4)  # 1/Φ⁻¹(¾)


def test_difference_sigma_finds_the_noise_under_a_smooth_misfit():
    """σ = 0.4 kPa white noise plus a 30 kPa slow misfit, a constant offset and 1 % of
    50 kPa steps (a fold): σ within 5 % from 20,000 samples; the misfit alone (no noise)
    gives ~0."""
    rng = np.random.default_rng(39)
    t = np.linspace(0.0, 40.0, 20000)
    misfit = 30.0 * np.sin(2 * np.pi * t / 6.0) + 7.0 + 50.0 * (np.sin(t) > 0.99)
    r = misfit + 0.4 * rng.standard_normal(t.size)
    assert difference_sigma(r) == pytest.approx(0.4, rel=0.05)
    assert difference_sigma(misfit) < 0.01
    # a trend of the second differences (a constant curvature) is taken out by the median
    assert difference_sigma(r + 0.5 * t ** 2) == pytest.approx(0.4, rel=0.05)
    # two records joined: the jump between them counts for nothing within groups
    joined = np.concatenate([r[:10000], r[10000:] + 1e4])
    groups = np.repeat([1, 0], 10000)  # any labels, in any order
    assert difference_sigma(joined, groups) == pytest.approx(difference_sigma(r), rel=1e-3)


def test_too_few_points_give_nan():
    assert np.isnan(difference_sigma(np.arange(11.0)))  # 9 differences < 10
    assert difference_sigma(np.arange(12.0) ** 2) == 0.0  # 10: enough
    assert np.isnan(difference_sigma(np.arange(30.0), min_points=29))


def test_segments_number_the_runs_and_isolate_each_gap():
    g = segments([True, True, False, False, True, True, True, False])
    assert g[0] == g[1] and g[4] == g[5] == g[6] and g[0] != g[4] and g[0] >= 0
    assert g[2] < 0 and g[3] < 0 and g[7] < 0 and len({g[2], g[3], g[7]}) == 3
    assert set(g[[0, 4]]).isdisjoint(g[[2, 3, 7]])
    h = segments([False, False, True, True, False])  # "−1 where False": negative, each its own
    assert (h[[0, 1, 4]] < 0).all() and len(set(h[[0, 1, 4]])) == 3 and h[2] == h[3] >= 0
    # used as groups, no difference spans a gap
    r = np.arange(8.0) ** 2
    np.testing.assert_array_equal(second_differences(r, g, centres=True)[1], [5])


def test_a_valve_flow_logged_in_whole_steps_has_at_least_its_rounding_as_floor():
    """Flows displayed in steps of 2 mg/s with 0.05 mg/s of meter noise: the floor of a
    right model is the rounding's 2/√12 mg/s (second differences alone gave 0.35)."""
    from pneunet.truth.valves.diagnose.features import noise_floor, prepare
    from pneunet.truth.valves.diagnose.scenarios import bench, scenario_truth

    truth = scenario_truth("clean")
    data = bench(truth, seed=4, reduced=True, noise_mdot=0.05, noise_rel=0.0, noise_p=0.0)
    data["mdot_mg_s"] = np.round(data["mdot_mg_s"] / 2.0) * 2.0
    df, _ = prepare(data)
    pred = truth(df)
    est = noise_floor(df, df["mdot_mg_s"].to_numpy() - pred, pred)
    assert est["rmse"] == pytest.approx(2.0 / np.sqrt(12.0), rel=0.1)
    assert all(s >= 2.0 / np.sqrt(12.0) for _, _, s, _ in est["bins"])


def test_record_sigma_of_a_swinging_record_is_its_noise():
    """A record's own noise from its fourth differences, normalised by √C(8, 4) = √70:
    white noise of σ 2 on a 100-unit swing of period 6 s at 20 Hz; within groups only
    (a 1000-unit step between two groups adds nothing); NaN with too few differences."""
    from pneunet.truth.core.noise import record_sigma

    rng = np.random.default_rng(3)
    t = np.arange(0, 60, 0.05)
    y = 100 * np.sin(2 * np.pi * t / 6) + 2.0 * rng.standard_normal(len(t))
    assert record_sigma(y) == pytest.approx(2.0, rel=0.08)
    groups = np.arange(len(t)) // 8  # sweeps of 8 samples, each 1000 units above the last
    stepped = y + 1000.0 * groups
    assert record_sigma(stepped, groups) == pytest.approx(2.0, rel=0.12)
    assert record_sigma(stepped) > 3.0  # differences across the sweeps' steps
    assert np.isnan(record_sigma(y[:4]))  # no fourth difference
    assert np.isnan(record_sigma(y[:13]))  # 9 differences < 10
    assert np.isfinite(record_sigma(y[:14]))  # 10 differences


def _ar1(phi, n, seed):
    """AR(1) noise of coefficient ``phi`` and unit variance (a first-order filter of white
    noise, written out here)."""
    w = np.random.default_rng(seed).standard_normal(n + 200)
    e = np.zeros_like(w)
    for i in range(1, len(w)):
        e[i] = phi * e[i - 1] + np.sqrt(1.0 - phi ** 2) * w[i]
    return e[200:]


def test_second_difference_correlation_of_white_and_ar1_noise_against_their_formulas():
    """White noise's second differences correlate at −2/3 from sample to sample; AR(1)
    noise's at (−4 + 7φ − 4φ² + φ³)/(6 − 8φ + 2φ²) (the covariance of
    e[i−1] − 2e[i] + e[i+1] with its neighbour, by hand); a few sharp corners (a valve's
    switching in a model error) do not move the robust estimate; pairs do not span
    groups."""
    from pneunet.truth.core.noise import WHITE_D2_CORRELATION, difference_correlation

    n = 4000
    se = 1.05 / np.sqrt(n)
    white = np.random.default_rng(3).standard_normal(n)
    c, pairs = difference_correlation(white)
    assert pairs == n - 3 and abs(c - WHITE_D2_CORRELATION) < 4 * se, c
    for phi in (0.3, 0.7):
        want = (-4 + 7 * phi - 4 * phi ** 2 + phi ** 3) / (6 - 8 * phi + 2 * phi ** 2)
        c, _ = difference_correlation(_ar1(phi, n, seed=4))
        assert abs(c - want) < 5 * se, (phi, c, want)
    corners = white.copy()
    corners[::200] += 30.0  # a kink every 200 samples
    assert abs(difference_correlation(corners)[0] - WHITE_D2_CORRELATION) < 4 * se
    groups = np.repeat([0, 1], n // 2)
    assert difference_correlation(white, groups)[1] == n - 6
    assert np.isnan(difference_correlation(white[:20])[0])


def test_the_coloured_noise_note_names_correlated_signals_only():
    """A diagnosis' note for residuals whose second differences are correlated beyond
    :data:`~pneunet.truth.circuits.diagnosis.COLOURED_SE` standard errors: named per
    signal; white noise's (as measured) and too few pairs give none."""
    from pneunet.truth.circuits.diagnosis import coloured_note
    from pneunet.truth.core.noise import difference_correlation

    n = 1800
    white = difference_correlation(np.random.default_rng(5).standard_normal(n))
    ar = difference_correlation(_ar1(0.7, n, seed=6))
    note = coloured_note({"second_difference_correlation": {"p_t1": ar[0], "p_t2": white[0]},
                          "correlation_pairs": {"p_t1": ar[1], "p_t2": white[1]}})
    assert note is not None and "p_t1" in note and "p_t2" not in note
    assert "--max-rows" in note
    assert coloured_note({"second_difference_correlation": {"p_t2": white[0]},
                          "correlation_pairs": {"p_t2": white[1]}}) is None
    assert coloured_note({"second_difference_correlation": {"p": float("nan")},
                          "correlation_pairs": {"p": 0}}) is None
