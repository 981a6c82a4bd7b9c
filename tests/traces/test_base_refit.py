"""Parsimony before an effect is accepted (candidate_fits.base_refit): the base model
fitted again from the best model's values of its parameters replaces a base fit that
stopped in a wrong valley, and the verdict is then decided on it."""
from types import SimpleNamespace

from pneunet.truth.circuits.candidate_fits import CandidateFits, base_refit
from pneunet.truth.core.lsq import Abandoned
from pneunet.truth.core.verdict import Step, decide

TEST, TRAIN = (10.0, 20.0), (0.0, 10.0)


class Fit(SimpleNamespace):
    def error(self, window=None):
        assert window in (TEST, TRAIN)
        return self.held_out


class Fitting:
    """Stand-in for CandidateFits: records the start it was given, returns ``refit``."""

    params = {"Rpull": (20.0, 2.0, 200.0), "V": (2.5, 0.2, 20.0)}
    test, train = TEST, TRAIN
    step, score = CandidateFits.step, CandidateFits.score

    def __init__(self, refit):
        self.refit, self.started = refit, []

    def start(self, eff, x_start, max_nfev, kind, state=None, give_up_rms=None):
        self.started.append((eff, dict(x_start), max_nfev, kind, state, give_up_rms))
        return self.refit


def setup(refit_error):
    fits = {"none": Fit(held_out=5.0, unit="kPa", values={"Rpull": 160.0, "V": 0.5},
                        start_state="base clock"),
            "tube@X1.in": Fit(held_out=0.31, unit="kPa",
                              values={"Rpull": 23.0, "V": 3.5, "R_tube@X1.in": 0.03},
                              start_state="the tube's fitted clock")}
    steps = [Step("base model", 5.0), Step("tube@X1.in", 0.31, effects=("tube@X1.in",))]
    refit = None if refit_error is None else Fit(held_out=refit_error, unit="kPa",
                                                   values={"Rpull": 23.0, "V": 3.5})
    return fits, steps, Fitting(refit)


def test_a_base_fit_in_a_wrong_valley_is_replaced_and_the_effect_not_needed():
    fits, steps, fitting = setup(0.30)
    notes = []
    assert base_refit(fits, steps, fitting, 120, notes, print)
    # started from the best model's base values only (not its effect's) and its start
    # state (its fitted clock), the base budget, of use only below the base's error
    assert fitting.started == [(None, {"Rpull": 23.0, "V": 3.5}, 120, "tube@X1.in's values",
                                "the tube's fitted clock", 5.0)]
    assert fits["none"] is fitting.refit and steps[0].held_out == 0.30
    assert decide(steps, 0.3) == ("adequate", [])
    assert "5 → 0.3 kPa" in notes[0]


def test_a_refit_no_better_than_the_base_changes_nothing():
    for err in (5.0, 7.0, None):  # as good, worse, failed
        fits, steps, fitting = setup(err)
        base = fits["none"]
        assert not base_refit(fits, steps, fitting, 120, [], print)
        assert fits["none"] is base and steps[0].held_out == 5.0
        assert decide(steps, 0.3) == ("explained", ["tube@X1.in"])


def test_nothing_is_refitted_when_no_model_beats_the_base():
    fits, steps, fitting = setup(0.30)
    steps[1] = Step("tube@X1.in", 6.0, effects=("tube@X1.in",))
    assert not base_refit(fits, steps, fitting, 120, [], print)
    assert fitting.started == []


def test_a_refit_that_cannot_beat_the_base_is_abandoned_with_a_note():
    fits, steps, fitting = setup(None)
    fitting.refit = Abandoned(9, 2.3e6)
    base, notes = fits["none"], []
    assert not base_refit(fits, steps, fitting, 120, notes, print)
    assert fits["none"] is base and decide(steps, 0.3) == ("explained", ["tube@X1.in"])
    assert notes == ["base model fitted again from tube@X1.in's values: abandoned after 9 "
                     "simulations, at its pace it could not reach the base fit's 5 kPa"]


def test_a_pair_fitted_on_everything_is_at_the_floor_only_as_the_verdict_judges_it():
    """With nothing held out (train = test) the verdict takes two effects only within
    NEAR_FLOOR × the floor, and the pair fits stop at the first pair 'at the floor' by
    the same rule (one at 1.4× would have stopped them short of a better pair)."""
    class Judged(Fitting):
        at_floor = CandidateFits.at_floor
        floor, tolerance = 0.3, 1.5

    pair = Fit(held_out=0.42, effects=("heat", "tube"))  # 1.4× the floor
    single = Fit(held_out=0.42, effects=("heat",))
    fitting = Judged(None)
    assert fitting.at_floor(single) and fitting.at_floor(pair)
    fitting.test = fitting.train
    assert fitting.at_floor(single) and not fitting.at_floor(pair)
    assert fitting.at_floor(Fit(held_out=0.35, effects=("heat", "tube")))  # 1.17×
