"""Budgeted LM in ln-parameters (truth/core/lsq.py), checked against scipy's bounded
trust-region solver on cheap analytic models: every simulation counts, so no point
is evaluated twice, and LM that steps past a bound restarts from it and still
converges in the other parameters."""
import numpy as np
import pytest
from scipy import optimize

from pneunet.truth.core.lsq import FIRST_RADIUS, Abandoned, least_squares_log

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


def test_first_step_stays_within_the_first_radius():
    """LM's first trial point lies within FIRST_RADIUS of the start in ln x (MINPACK lets
    a step exceed its radius by 10 %): its own first radius, 100·‖x‖, let the first
    step of a circuit fit go to a corner of the box, where every parameter was held at
    its bound.  From (1, 0.05) the optimum (2, 0.7) is 2.7 away; LM gets there by
    widening its radius."""
    fun = Decay()
    lb, ub = np.log([0.1, 0.001]), np.log([50.0, 10.0])
    x0 = np.log([1.0, 0.05])
    res = least_squares_log(fun, x0, lb, ub, max_nfev=80, diff_step=1e-4)
    away = [float(np.linalg.norm(c - x0)) for c in fun.calls]
    first = next(d for d in away if d > 10 * 1e-4)  # past the Jacobian's columns
    assert first <= 1.1 * FIRST_RADIUS
    assert max(away) > 2.0  # the radius widened
    np.testing.assert_allclose(np.exp(res.x), np.exp(_reference(lb, ub, x0)), rtol=1e-3)


class WithBaseline:
    """Residual of y = a·exp(−b·t) + c with the model seeing ``unit``·exp(x), data from
    (a, b, c) = (2.0, 0.7, 1.0)."""

    TRUE = np.array([2.0, 0.7, 1.0])

    def __init__(self, unit=(1.0, 1.0, 1.0)):
        self.unit = np.asarray(unit, float)
        self.data = self.model(np.log(self.TRUE / self.unit)) + NOISE

    def model(self, x):
        a, b, c = self.unit * np.exp(x)
        return a * np.exp(-b * T) + c

    def __call__(self, x):
        return self.model(x) - self.data


@pytest.mark.parametrize("start", [(1.0, 1.0, 1.0), (1.0, 0.01, 1.0), (1.0, 10.0, 1.0),
                                   (50.0, 1.0, 0.01)])
def test_stopping_rule_does_not_depend_on_units_or_a_value_of_one(start):
    """Parameters that start at exactly 1 in their unit (ln x = 0), or at an end of
    their range: LM reaches the optimum (scipy's bounded solver as reference), and
    writing them in other units (×1000, ×1/1000: ln x shifted) changes neither the
    estimates nor the number of evaluations (MINPACK's radius < xtol·‖D·x‖, with D the
    Jacobian's column norms, did: a parameter at ln x = 0 adds nothing to it)."""
    lb, ub = np.log([0.1, 0.01, 0.01]), np.log([50.0, 10.0, 20.0])
    fun = WithBaseline()
    ref = optimize.least_squares(fun, np.log(start).clip(lb + 1e-9, ub - 1e-9),
                                 bounds=(lb, ub), method="trf", xtol=1e-12, ftol=1e-12,
                                 gtol=1e-12).x
    res = least_squares_log(fun, np.log(start), lb, ub, max_nfev=200, diff_step=1e-5)
    np.testing.assert_allclose(np.exp(res.x), np.exp(ref), rtol=1e-3)
    unit = np.array([1e3, 1e-3, 1e3])
    other = least_squares_log(WithBaseline(unit), np.log(start) - np.log(unit),
                              lb - np.log(unit), ub - np.log(unit), max_nfev=200,
                              diff_step=1e-5)
    np.testing.assert_allclose(unit * np.exp(other.x), np.exp(res.x), rtol=1e-6)
    assert other.nfev == res.nfev


def test_lm_stopped_by_its_call_cap_goes_on_with_the_simulations_left():
    """MINPACK caps its calls as if each had a Jacobian (``max_nfev`` // (n + 1)); its
    rejected steps have none, so it stopped with simulations unused (the inverter chain
    forced to start at rest: 28 of 40, R_pull 18.8 [17.2, 20.7] for a true 23).
    Rosenbrock's valley in ln p from (0.3, 3), where LM rejects steps, on 24
    simulations: it stopped after 18 at a cost of 0.16; going on with the six left it
    reaches 0.044, and no point is simulated twice."""
    class Rosenbrock:
        def __init__(self):
            self.calls = []

        def __call__(self, x):
            self.calls.append(np.array(x))
            p = np.exp(x)
            return np.array([10.0 * (p[1] - p[0] ** 2), 1.0 - p[0]])

    fun = Rosenbrock()
    lb, ub = np.log([0.01, 0.01]), np.log([10.0, 10.0])
    res = least_squares_log(fun, np.log([0.3, 3.0]), lb, ub, max_nfev=24, diff_step=1e-6)
    assert 24 - 2 * 3 < res.nfev <= 24
    assert len({c.tobytes() for c in fun.calls}) == len(fun.calls) == res.nfev
    assert float(res.fun @ res.fun) < 0.1


def test_a_fit_out_of_simulations_says_so_and_a_converged_one_does_not():
    """``on_budget`` comes from MINPACK's status, not from the wording of its message."""
    lb, ub = np.log([0.1, 0.01]), np.log([50.0, 10.0])
    x0 = np.log([0.2, 5.0])
    short = least_squares_log(Decay(), x0, lb, ub, max_nfev=6, diff_step=1e-4)
    assert not short.success and short.on_budget
    full = least_squares_log(Decay(), x0, lb, ub, max_nfev=200, diff_step=1e-4)
    assert full.success and not full.on_budget


def _beside_a_cliff(x):
    """A quadratic bowl at (0.1, −0.2) with a cliff where x₀ > 0.3025, just beyond the
    start (0.3, 0): there every residual is 100 whatever x (an oscillation that
    stopped)."""
    if x[0] > 0.3025:
        return np.full(3, 100.0)
    return np.array([3.0 * (x[0] - 0.1) + x[1] + 0.2, 2.0 * (x[1] + 0.2), x[0] - 0.1])


def test_lm_stopped_beside_a_cliff_starts_again_away_from_it():
    """From beside the cliff the forward difference in x₀ crosses it: x₀'s column is
    ~2e4 and LM moves x₁ alone, stopping where x₁ fits best for x₀ = 0.3 (cost 0.44).
    The other side's column is 3.2: a cliff; LM starts again 0.1 away from it and finds
    the bowl's bottom."""
    lb, ub = np.full(2, -5.0), np.full(2, 5.0)
    res = least_squares_log(_beside_a_cliff, np.array([0.3, 0.0]), lb, ub, max_nfev=200,
                            diff_step=5e-3)
    assert res.success
    assert res.x == pytest.approx([0.1, -0.2], abs=1e-6)
    assert res.fun @ res.fun == pytest.approx(0.0, abs=1e-10)
    assert res.nfev <= 200
    assert res.other_jac is None  # well conditioned at the bottom: no cliff to look for


def test_a_fit_that_cannot_reach_its_give_up_cost_is_abandoned_and_one_that_can_is_not():
    """``give_up`` (the base model fitted again from a candidate's values, of use only
    below the base fit's error): a fit creeping along far above that cost is abandoned
    in fewer than half the simulations it would take to converge, with the cost it had
    reached; from starts a factor 2–20
    off, where its first steps are long, a fit that can reach the cost is not, and it
    ends where it would without the rule."""
    lb, ub = np.log([0.1, 0.01]), np.log([50.0, 10.0])

    class Stuck(Decay):
        """The decay with a wrong model in a valley of its own: b cannot fall below 1.5,
        so the cost stays far above the noise whatever LM does."""

        def __call__(self, x):
            a, b = np.exp(x)
            return super().__call__(np.log([a, 1.5 + b]))

    best = least_squares_log(Decay(), np.log([1.0, 0.3]), lb, ub, max_nfev=200,
                             diff_step=1e-4).fun
    floor = float(best @ best)
    stuck = least_squares_log(Stuck(), np.log([2.0, 0.5]), lb, ub, max_nfev=120,
                              diff_step=1e-4)
    assert float(stuck.fun @ stuck.fun) > 100 * floor and stuck.nfev > 20
    with pytest.raises(Abandoned) as gave_up:
        least_squares_log(Stuck(), np.log([2.0, 0.5]), lb, ub, max_nfev=120,
                          diff_step=1e-4, give_up=1.5 * floor)
    assert gave_up.value.nfev < stuck.nfev / 2 and gave_up.value.cost > 100 * floor
    for start in ([1.0, 0.3], [0.2, 5.0], [20.0, 0.02], [10.0, 5.0], [50.0, 0.01]):
        free = least_squares_log(Decay(), np.log(start), lb, ub, max_nfev=60, diff_step=1e-4)
        ruled = least_squares_log(Decay(), np.log(start), lb, ub, max_nfev=60,
                                  diff_step=1e-4, give_up=1.01 * floor)
        np.testing.assert_array_equal(ruled.x, free.x)
