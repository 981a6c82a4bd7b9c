"""Which screened candidates a diagnosis fits fully (candidate_fits.fit_screened): the
best two (a third within SCREEN_KEEP), then — when none reaches the floor — the next
ones the screen cannot tell from the best, in its order, until one does, then second
starts for the first round; a candidate the screen shows clearly worse is never fitted."""
from types import SimpleNamespace

from pneunet.truth.circuits.candidate_fits import fit_screened
from pneunet.truth.circuits.screen import SCREEN_KEEP

FLOOR = 1.0


class Fitting:
    """Stand-in for CandidateFits: a candidate's fit reaches ``held_out[name]``."""

    pool, test = None, (0.0, 1.0)

    def __init__(self, held_out):
        self.held_out, self.calls, self.failed = held_out, [], {}

    def start(self, eff, x_start, max_nfev):
        second = x_start.get("second", False)
        self.calls.append((eff.name, "second" if second else "first"))
        err = self.held_out[eff.name] * (0.5 if second else 1.0)
        return SimpleNamespace(error=lambda window=None: err)

    def base_start(self, guesses=False):
        return {"second": True}

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


def test_one_the_screen_shows_clearly_worse_is_never_fitted():
    screened = rows(1.0, 1.05, 1.1, SCREEN_KEEP * 1.01)
    fitting = Fitting({"e0": 9, "e1": 9, "e2": 9, "e3": 0.5})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    # second starts for the first round only, best first; e3 never
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first"),
                             ("e0", "second"), ("e1", "second"), ("e2", "second")]


def test_a_first_round_at_the_floor_stops_there():
    screened = rows(1.0, 1.05, 1.1)
    fitting = Fitting({"e0": 0.9, "e1": 9, "e2": 9})
    fit_screened(screened, {}, fitting, 3, 160, lambda m: None)
    assert fitting.calls == [("e0", "first"), ("e1", "first"), ("e2", "first")]
