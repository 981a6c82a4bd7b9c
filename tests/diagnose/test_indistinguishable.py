"""Two candidates that fit a recording alike (:func:`pneunet.truth.core.verdict.indistinguishable`
and the diagnosis' parsimony, :func:`pneunet.truth.circuits.candidate_fits.parsimonious_first`):
the mean of the squared residuals' difference against its Newey–West standard error,
checked against what the residuals are built from."""
from types import SimpleNamespace

import numpy as np

from pneunet.truth.circuits.candidate_fits import CandidateFits, parsimonious_first, ranked
from pneunet.truth.core.verdict import indistinguishable

N = 3000


def _ar1(rng, phi, n=N):
    """AR(1) noise of unit variance (a recording's residuals are autocorrelated)."""
    e = rng.standard_normal(n) * np.sqrt(1 - phi ** 2)
    out = np.empty(n)
    out[0] = rng.standard_normal()
    for i in range(1, n):
        out[i] = phi * out[i - 1] + e[i]
    return out


def test_the_same_noise_and_a_tiny_change_fit_alike():
    rng = np.random.default_rng(1)
    noise = _ar1(rng, 0.5)
    assert indistinguishable(noise, noise + 0.001 * rng.standard_normal(N))
    assert indistinguishable(noise, noise.copy())


def test_a_misfit_of_a_third_of_the_noise_is_told_apart_both_ways():
    rng = np.random.default_rng(2)
    noise = _ar1(rng, 0.5)
    misfit = noise + 0.35 * np.sin(np.linspace(0, 20 * np.pi, N))  # 1.06× the rms
    assert not indistinguishable(noise, misfit)
    assert not indistinguishable(misfit, noise)


def test_autocorrelation_widens_the_standard_error():
    """Two independent AR(1) residual sets of the same variance (φ = 0.95: a
    correlation time of 20 samples): their mean squares differ by chance, which the
    white-noise standard error (no lags) calls a difference far more often than 5 %."""
    told_apart = {0: 0, None: 0}
    for seed in range(40):
        rng = np.random.default_rng(100 + seed)
        a, b = _ar1(rng, 0.95), _ar1(rng, 0.95)
        told_apart[None] += not indistinguishable(a, b)
        d = a ** 2 - b ** 2
        told_apart[0] += abs(d.mean()) > 2 * d.std(ddof=1) / np.sqrt(N)
    assert told_apart[None] <= 6  # nominally 5 % of 40, Newey–West somewhat liberal
    assert told_apart[0] >= 15


def test_nan_where_a_model_is_not_compared_is_left_out():
    rng = np.random.default_rng(3)
    a = rng.standard_normal(N)
    b = a + 0.001
    a[:100] = np.nan
    assert indistinguishable(a, b)


def _fit(residuals, n_params):
    return SimpleNamespace(scaled_residuals=lambda window: residuals,
                           error=lambda window: float(np.sqrt(np.nanmean(residuals ** 2))),
                           effects=(SimpleNamespace(params=dict.fromkeys(range(n_params))),))


def test_the_candidate_with_fewer_parameters_goes_first_when_they_fit_alike():
    rng = np.random.default_rng(4)
    noise = rng.standard_normal(N)
    fits = {"tube": _fit(noise, 2), "dead_volume": _fit(noise * 1.0001, 1),
            "leak": _fit(noise + 0.5, 1)}
    order, note = parsimonious_first(["tube", "dead_volume", "leak"], fits, None, 1.0, 1.5)
    assert order == ["dead_volume", "tube", "leak"]
    assert "dead_volume and tube fit the held-out record alike" in note
    # told apart: the best stays first and nothing is said
    fits["dead_volume"] = _fit(noise + 0.3, 1)
    assert parsimonious_first(["tube", "dead_volume", "leak"], fits, None, 1.0, 1.5) == (
        ["tube", "dead_volume", "leak"], "")


def test_a_simpler_candidate_across_the_verdicts_threshold_is_not_taken():
    """The best just at the floor (1.495×), a one-parameter candidate 0.7 % worse and
    just above it (1.505×): alike by the rms, but taking it would turn `explained` into
    `unexplained`."""
    rng = np.random.default_rng(5)
    noise = rng.standard_normal(N)
    noise *= 1.495 / np.sqrt(np.mean(noise ** 2))
    fits = {"tube": _fit(noise, 2), "dead_volume": _fit(noise * (1.505 / 1.495), 1)}
    assert parsimonious_first(["tube", "dead_volume"], fits, None, 1.0, 1.5) == (
        ["tube", "dead_volume"], "")
    fits["dead_volume"] = _fit(noise * (1.4951 / 1.495), 1)
    assert parsimonious_first(["tube", "dead_volume"], fits, None, 1.0, 1.5)[0] == [
        "dead_volume", "tube"]


def test_candidates_are_ranked_by_the_worse_of_held_out_and_fitted_error():
    """The amplifier inflated once with heat exchange and a control-line tube: its
    held-out half is the relaxation tail.  A tube at the in-valve's output met it at
    0.75 kPa held out (13.4 fitted); the control-line tube at 1.14 (2.68 fitted) is the
    one to build the pair on.  By held-out error alone the first led, and no pair
    reached the floor (`unexplained`, 2.5× held out).  On its logger's clock a dead
    volume (one parameter fewer) fitted the tail like the control-line tube and missed
    the fitted window (22 kPa): alike on the held-out window alone, it was put first."""
    rng = np.random.default_rng(6)
    noise = rng.standard_normal(N)
    windows = {"test": (7.5, 15.0), "train": (0.0, 7.5)}

    def fit(held_out, fitted, n_params=2):
        err = {windows["test"]: held_out, windows["train"]: fitted}
        return SimpleNamespace(scaled_residuals=lambda window: noise * err[window],
                               error=lambda window: err[window],
                               effects=(SimpleNamespace(params=dict.fromkeys(range(n_params))),))

    fits = {"none": fit(3.98, 23.2), "tube@Xin.out": fit(0.75, 13.4),
            "tube@Xin.ctrl": fit(1.14, 2.68), "dead_volume@act": fit(1.1401, 21.9, 1)}

    class Fitting:  # CandidateFits' windows and thresholds, its own step and score
        test, train, floor, tolerance = windows["test"], windows["train"], 0.3, 1.5
        step, score = CandidateFits.step, CandidateFits.score

    order, note = ranked(fits, Fitting())
    assert order == ["tube@Xin.ctrl", "tube@Xin.out", "dead_volume@act"] and note == ""
    # alike on both windows: the one with fewer parameters first, as before
    fits["dead_volume@act"] = fit(1.1401, 2.6801, 1)
    order, note = ranked(fits, Fitting())
    assert order[0] == "dead_volume@act" and "fit the record alike" in note
