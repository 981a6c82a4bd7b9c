"""Pairs of effects (candidate_fits.fit_pairs): the best single with each second effect
in turn until a pair reaches the floor; a pair stopped on its budget while improving on
the best single is fitted on from where it stopped, as the best single is."""
from types import SimpleNamespace

from pneunet.truth.circuits.candidate_fits import CONTINUATIONS, CandidateFits, fit_pairs
from pneunet.truth.core.verdict import Step


class Fitting:
    """Stand-in for CandidateFits: a pair's fit reaches ``held_out[second]``, halved by
    each start from a pair's own values; those in ``stopped`` stop on their budget."""

    test, train, floor, tolerance = (1.0, 2.0), (0.0, 1.0), 1.0, 1.5
    step, score, at_floor = CandidateFits.step, CandidateFits.score, CandidateFits.at_floor

    def __init__(self, held_out, stopped=(), fitted=None):
        self.held_out, self.stopped, self.calls = held_out, set(stopped), []
        self.fitted = fitted or {}

    def pair(self, effects, x_start, max_nfev, notes, state=None):
        """A pair starts from the best single's start state, a continuation from its
        own fit's (the clock each fitted)."""
        second = effects[1].name
        again = x_start.get("from") == second
        assert state == (f"a + {second}" if again else "a"), state
        self.calls.append((second, "continued" if again else "first"))
        err = x_start["err"] * 0.5 if again else self.held_out[second]
        fitted = self.fitted.get(second, err)  # its error on the fitted window
        stopped = second in self.stopped
        return SimpleNamespace(error=lambda window=None: fitted if window == self.train
                               else err, effects=effects,
                               stopped_on_budget=lambda: stopped,
                               values={"from": second, "err": err},
                               start_state=f"a + {second}")


def _run(fitting, *seconds):
    best = SimpleNamespace(name="a", effects=(SimpleNamespace(name="a"),), start_state="a")
    fits = {"a": best}
    steps = [Step("base model", 10.0), Step("a", 4.0, effects=("a",))]
    fit_pairs(fits, "a", [(SimpleNamespace(name=n), {}) for n in seconds], steps, fitting,
              100, [], lambda m: None)
    return fits, steps


def test_a_pair_stopped_on_its_budget_is_fitted_on_while_it_improves():
    fitting = Fitting({"b": 3.2, "c": 0.9}, stopped={"b"})
    fits, steps = _run(fitting, "b", "c")
    # b: 3.2 on its budget, on to 1.6, 0.8 (the floor): c is never fitted
    assert fitting.calls == [("b", "first")] + [("b", "continued")] * CONTINUATIONS
    assert fits["a + b"].error() == 0.8 and steps[-1].held_out == 0.8


def test_a_converged_pair_or_one_worse_than_the_single_is_not_continued():
    fitting = Fitting({"b": 3.2, "c": 6.0, "d": 0.9}, stopped={"c"})
    _run(fitting, "b", "c", "d")
    assert fitting.calls == [("b", "first"), ("c", "first"), ("d", "first")]


def test_a_pair_at_the_floor_held_out_only_does_not_end_the_search():
    """b meets the held-out window (0.9) but misses its fitted one (4.0): c is tried, and
    the waterfall's last step is c's pair, at the floor on both."""
    fitting = Fitting({"b": 0.9, "c": 1.1}, fitted={"b": 4.0})
    fits, steps = _run(fitting, "b", "c")
    assert fitting.calls == [("b", "first"), ("c", "first")]
    assert steps[-1].effects == ("a", "c") and steps[-1].worst == 1.1
