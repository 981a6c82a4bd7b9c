"""Which screened candidates a diagnosis fits fully (candidate_fits.fit_screened): the
best and those within SCREEN_KEEP of it (three at most), the second best whatever its
merit when none of those reaches the floor, then — while none does — the next
ones the screen cannot tell from the best, in its order, until one does, then second
starts for the first round and for later ones that stayed in the base fit's valley, then
the best fit continued where its budget stopped it; a candidate the screen shows clearly
worse is never fitted."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from pneunet.truth.circuits.candidate_fits import (CONTINUATIONS, STAYED, CandidateFits,
                                                  fit_screened)
from pneunet.truth.circuits.clock import CLOCK_NUDGES
from pneunet.truth.circuits.initial_state import StartState
from pneunet.truth.circuits.screen import SCREEN_KEEP

FLOOR = 1.0


class Fitting:
    """Stand-in for CandidateFits: a candidate's fit reaches ``held_out[name]``."""

    pool, test, train = None, (0.0, 1.0), (0.0, 1.0)
    step, score = CandidateFits.step, CandidateFits.score

    def __init__(self, held_out, base=10.0, stopped=()):
        self.held_out, self.calls, self.failed = held_out, [], {}
        self.base = SimpleNamespace(error=lambda window=None: base)
        self.stopped = set(stopped)  # candidates whose fits stop on their budget

    def start(self, eff, x_start, max_nfev, kind, state=None):
        """A second start halves a candidate's held-out error, and so does each
        continuation (a start from a fit's own values and its start state)."""
        kind = {"screen point": "first", "second start": "second"}.get(kind, kind)
        assert kind != "continued" or x_start.get("from") == eff.name == state.of
        self.calls.append((eff.name, kind))
        if self.held_out[eff.name] is None:  # its fit cannot be made (e.g. nothing compared)
            self.failed[eff.name] = "fit failed"
            return None
        err = x_start.get("err", self.held_out[eff.name]) * (1.0 if kind == "first" else 0.5)
        stopped = eff.name in self.stopped
        return SimpleNamespace(error=lambda window=None: err, effects=(eff,),
                               stopped_on_budget=lambda: stopped,
                               values={"from": eff.name, "err": err},
                               start_state=SimpleNamespace(of=eff.name, clock_ci=()))

    def base_start(self, guesses=False):
        return {}

    def second_start(self, row):
        return {}

    def reached(self, fits):
        return any(f.error() <= 1.5 * FLOOR for n, f in fits.items() if n != "none")


def rows(*merits):
    return [{"effect": SimpleNamespace(name=f"e{i}", params={}), "rss": m, "x": {}}
            for i, m in enumerate(merits)]


def test_the_next_inseparable_candidates_are_fitted_until_one_reaches_the_floor():
    screened = rows(1.0, 1.05, 1.1, 1.2, 1.3, SCREEN_KEEP * 1.01)
    fitting = Fitting({"e0": 9, "e1": 9, "e2": 9, "e3": 1.2, "e4": 0.9, "e5": 0.5})
    fits = {}
    fit_screened(screened, fits, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first"),
                             ("e3", "first")]  # e3 reaches the floor: no more, no seconds


def test_a_candidate_that_cannot_be_fitted_gives_its_place_to_the_next_in_the_screen():
    """Two tubes whose states settle only after the fit window ranked first: they fail,
    and the next two in the screen's order are fitted instead, however much worse their
    merits (the 400 mL oscillator's hidden dead volume was screened out behind them)."""
    screened = rows(1.0, 1.05, 2 * SCREEN_KEEP, 3 * SCREEN_KEEP, 4 * SCREEN_KEEP)
    fitting = Fitting({"e0": None, "e1": None, "e2": 9, "e3": 0.9, "e4": 0.5})
    fits = {}
    fit_screened(screened, fits, fitting, 2, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first"),
                             ("e3", "first")]
    assert set(fits) == {"e2", "e3"} and set(fitting.failed) == {"e0", "e1"}


def test_one_the_screen_shows_clearly_worse_is_never_fitted():
    screened = rows(1.0, 1.05, 1.1, SCREEN_KEEP * 1.01)
    fitting = Fitting({"e0": 9, "e1": 9, "e2": 9, "e3": 0.5})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    # second starts for the first round only (none later), best first; e3 never
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first"),
                             ("e0", "second"), ("e1", "second"), ("e2", "second")]


def test_a_second_best_the_screen_shows_clearly_worse_is_fitted_only_if_the_best_misses():
    """The best reaches the floor: a second best screened more than SCREEN_KEEP worse is
    not fitted (it would only cost time).  The best misses the floor: the second best is
    fitted however much worse its merit (the screen misranked a control-line tube behind
    a dead volume), and it reaching the floor ends the search."""
    screened = rows(1.0, 2 * SCREEN_KEEP, 3 * SCREEN_KEEP)
    fitting = Fitting({"e0": 0.9, "e1": 0.5, "e2": 0.5})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first")]
    fitting = Fitting({"e0": 9, "e1": 0.9, "e2": 0.5})
    fits = {}
    fit_screened(screened, fits, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first")] and set(fits) == {"e0", "e1"}


def test_a_first_round_at_the_floor_stops_there():
    screened = rows(1.0, 1.05, 1.1)
    fitting = Fitting({"e0": 0.9, "e1": 9, "e2": 9})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first")]


def test_a_later_candidate_that_stayed_in_the_base_valley_gets_a_second_start():
    """e3 and e4 are fitted after the first round; e3's fit ends where the base fit's did
    (it tested nothing), e4's left that valley: only e3 is started again."""
    screened = rows(1.0, 1.05, 1.1, 1.2, 1.3)
    fitting = Fitting({"e0": 9, "e1": 9, "e2": 9, "e3": STAYED * 10.0, "e4": 6.0})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    assert fitting.calls[5:] == [("e0", "second"), ("e1", "second"), ("e2", "second"),
                                 ("e3", "second")]


def test_the_best_fit_stopped_on_its_budget_is_continued():
    """e2's second start reaches 2.4 (above the floor's 1.5) on its budget: it goes on
    from there, and on again while its budget stops it (1.2, then 0.6: the verdict and
    the intervals are not taken where a budget stopped it); e0, better than the base but
    converged, is not continued."""
    screened = rows(1.0, 1.05, 1.1)
    fitting = Fitting({"e0": 6, "e1": 9, "e2": 4.8}, stopped={"e2"})
    fits = {}
    fit_screened(screened, fits, fitting, 3, 160, lambda m: None)
    assert fitting.calls[-2:] == [("e2", "continued")] * 2 and fits["e2"].error() == 0.6
    assert fitting.calls.count(("e2", "continued")) == CONTINUATIONS == 2
    assert ("e0", "continued") not in fitting.calls


def test_a_first_round_fit_at_the_floor_stopped_on_its_budget_is_continued():
    screened = rows(1.0, 1.05, 1.1)
    fitting = Fitting({"e0": 1.2, "e1": 9, "e2": 9}, stopped={"e0"})
    fits = {}
    fit_screened(screened, fits, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first"),
                             ("e0", "continued"), ("e0", "continued")]


def test_a_converged_best_fit_is_not_continued():
    screened = rows(1.0, 1.05, 1.1)
    fitting = Fitting({"e0": 6, "e1": 9, "e2": 4.8})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    assert ("e2", "continued") not in fitting.calls


class ClockFitting(Fitting):
    """Stand-in whose fits fit the logger's clock: a fit's error is
    ``errors[first sample's netlist time]`` (0.02 s samples), its state the one given."""

    df = pd.DataFrame({"time_s": 0.02 * np.arange(100)})

    def __init__(self, errors, **kw):
        super().__init__({"e0": errors[0.0]}, **kw)
        self.errors = errors
        self.first = StartState("record", time_offset=0.0, driven=True, clock="estimated",
                                clock_period=4.0, clock_ci=(-0.001, 0.001))

    def start(self, eff, x_start, max_nfev, kind, state=None):
        state = state or self.first
        self.calls.append((eff.name, kind, round(state.time_offset, 6), state.clock_ci))
        err = self.errors[round(state.time_offset, 6)]
        return SimpleNamespace(error=lambda window=None: err, effects=(eff,),
                               stopped_on_budget=lambda: False, values={}, start_state=state)


@pytest.mark.parametrize("better", [-0.01, 0.01, None])
def test_the_best_fit_on_a_fitted_clock_is_started_half_a_sample_either_way(better):
    """A fit above the floor on a fitted clock is fitted again from its clock moved half
    a sample (0.01 s) each way; the lower cost is kept."""
    errors = {0.0: 3.0, -0.01: 4.0, 0.01: 5.0}
    if better is not None:
        errors[better] = 1.2
    fitting = ClockFitting(errors)
    fits = {}
    fit_screened(rows(1.0), fits, fitting, 3, 160, lambda m: None)
    moved = [c for c in fitting.calls if c[1].startswith("clock moved")]
    assert [c[2] for c in moved] == [0.02 * k for k in CLOCK_NUDGES]
    assert all(c[3] == () for c in moved)  # a moved clock has no interval yet
    assert fits["e0"].error() == (1.2 if better is not None else 3.0)
    assert fits["e0"].start_state.time_offset == pytest.approx(better or 0.0)


def test_a_fit_at_the_floor_or_on_the_files_clock_is_not_started_again():
    fitting = ClockFitting({0.0: 1.0})  # at the floor
    fit_screened(rows(1.0), {}, fitting, 3, 160, lambda m: None)
    assert len(fitting.calls) == 1
    fitting = ClockFitting({0.0: 3.0})
    fitting.first = StartState("record", driven=True)  # the file's clock: none fitted
    fit_screened(rows(1.0), {}, fitting, 3, 160, lambda m: None)
    assert all(not c[1].startswith("clock") for c in fitting.calls)
