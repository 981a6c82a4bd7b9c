"""Budgeted LM in ln-parameters (truth/lsq.py), checked against scipy's bounded
trust-region solver on cheap analytic models: every simulation counts, so no point
is evaluated twice, and LM that steps past a bound restarts from it and still
converges in the other parameters."""
import numpy as np
import pytest
from scipy import optimize

from pneunet.truth.lsq import least_squares_log

T = np.linspace(0.0, 4.0, 60)
NOISE = 0.01 * np.random.default_rng(7).standard_normal(T.size)


class Decay:
    """Residual of y = a·exp(−b·t) against data from (a, b) = (2.0, 0.7); records calls."""

    def __init__(self):
        self.calls = []
        self.data = 2.0 * np.exp(-0.7 * T) + NOISE

    def __call__(self, x):
        self.calls.append(np.array(x))
        a, b = np.exp(x)
        return a * np.exp(-b * T) - self.data


def _reference(lb, ub, x0):
    model = Decay()
    return optimize.least_squares(model, x0, bounds=(lb, ub), method="trf", xtol=1e-12,
                                  ftol=1e-12, gtol=1e-12).x


def test_unbounded_fit_matches_scipy_and_evaluates_no_point_twice():
    fun = Decay()
    lb, ub = np.log([0.1, 0.01]), np.log([50.0, 10.0])
    x0 = np.log([1.0, 0.3])
    res = least_squares_log(fun, x0, lb, ub, max_nfev=60, diff_step=1e-4)
    np.testing.assert_allclose(np.exp(res.x), np.exp(_reference(lb, ub, x0)), rtol=1e-4)
    keys = {c.tobytes() for c in fun.calls}
    assert len(keys) == len(fun.calls) == res.nfev
    # the Jacobian returned is the one at the solution
    assert res.jac.shape == (T.size, 2)


def test_optimum_past_a_bound_restarts_and_fits_the_other_parameter():
    """a ≤ 1.5 < 2.0: the constrained optimum has a at its bound and b refitted."""
    fun = Decay()
    lb, ub = np.log([0.1, 0.01]), np.log([1.5, 10.0])
    x0 = np.log([1.0, 3.0])
    res = least_squares_log(fun, x0, lb, ub, max_nfev=80, diff_step=1e-4)
    ref = _reference(lb, ub, x0)
    assert res.x[0] == pytest.approx(ub[0])
    np.testing.assert_allclose(np.exp(res.x), np.exp(ref), rtol=1e-3)
    assert res.nfev <= 80


def test_a_step_past_a_bound_is_released_when_the_optimum_is_inside():
    """From (1, 0.05) LM's first run overshoots b's bound 1.0 (to b ≈ 120; the optimum
    0.7 is inside): b is held at 1.0 while a is fitted, then released, and the fit ends
    at the unbounded optimum."""
    fun = Decay()
    lb, ub = np.log([0.1, 0.01]), np.log([50.0, 1.0])
    x0 = np.log([1.0, 0.05])
    res = least_squares_log(fun, x0, lb, ub, max_nfev=80, diff_step=1e-4)
    np.testing.assert_allclose(np.exp(res.x), np.exp(_reference(lb, ub, x0)), rtol=1e-3)
