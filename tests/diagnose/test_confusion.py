"""Done-when 1 and 2 of issue 5 at realistic size: the paper's 4410-point protocol
(every other p_ctrl sweep rising) on the virtual bench of issue 4, with its default
noise, setpoint errors and outlet regulator.  The confusion matrix of
docs/diagnose.md is these cases (``python benchmarks/bench_diagnose.py --confusion``)."""
import functools

import pytest

from pneunet.truth.valves.diagnose.scenarios import (LIBRARY_SCENARIOS, UNLISTED_SCENARIOS,
                                                     run_scenario)

PAIRS = ["leak+hysteresis", "choked+laminar", "internal-drop+leak"]


@functools.lru_cache(maxsize=None)
def run(name):
    diag, floor, _ = run_scenario(name, seed=0)
    return diag, floor


def test_clean_data_is_adequate():
    diag, floor = run("clean")
    j = diag.to_json()
    assert j["verdict"] == "adequate" and j["accepted"] == []
    assert not any(r["accepted"] for r in j["ranking"])
    # the data-based noise floor is close to the floor the bench was given
    assert abs(j["noise_floor"] / floor - 1) < 0.2
    assert j["baseline"]["cv_rmse"] < 1.15 * floor


@pytest.mark.parametrize("effect", list(LIBRARY_SCENARIOS))
def test_library_effect_is_named_first(effect):
    diag, floor = run(effect)
    j = diag.to_json()
    assert j["ranking"][0]["effect"] == effect
    assert j["accepted"] == [effect]
    assert j["verdict"] == "explained"
    # done-when 2: after accepting the effect the CV error is at the noise floor
    assert j["final"]["cv_rmse"] <= 1.15 * floor
    assert j["final"]["cv_rmse"] < j["baseline"]["cv_rmse"]
    # the fitted effect parameter is near the truth: within 10 % and within 3 of its
    # standard errors (|z| ≤ 2.25 over the six effects at seed 0), and its 95 % interval
    # is the estimate ± 1.96 of them
    (pname, truth), = LIBRARY_SCENARIOS[effect].items()
    fitted = j["final"]["effects"][effect][pname]
    assert abs(fitted["value"] - truth) < 0.1 * abs(truth)
    assert abs(fitted["value"] - truth) <= 3 * fitted["stderr"], fitted
    assert fitted["ci95"] == pytest.approx(
        [fitted["value"] - 1.959964 * fitted["stderr"],
         fitted["value"] + 1.959964 * fitted["stderr"]], rel=0, abs=1e-3 * fitted["stderr"])
    # the accepted effect is in the model card
    assert f"{effect.replace('-', '_')}_{pname}=" in j["model_card"]


@pytest.mark.parametrize("name", list(UNLISTED_SCENARIOS))
def test_unlisted_effect_is_flagged_unexplained(name):
    diag, floor = run(name)
    j = diag.to_json()
    assert j["unexplained"] is True and j["adequate"] is False
    assert j["accepted"] == []  # no wrong effect named
    top2 = [w["feature"] for w in j["where"][:2]]
    assert set(top2) & set(UNLISTED_SCENARIOS[name].expect), top2
    assert j["regions"]["baseline"], "plain-language regions expected"
    assert j["verdict"] == "unexplained"
    # the claimed model is the six-parameter one, and its structure is real
    assert j["baseline"]["cv_rmse"] > 1.2 * floor


@pytest.mark.slow
@pytest.mark.parametrize("pair", PAIRS)
def test_pairs_of_effects_are_both_named(pair):
    diag, floor = run(pair)
    j = diag.to_json()
    assert sorted(j["accepted"]) == sorted(pair.split("+"))
    assert j["unexplained"] is False
    assert j["final"]["cv_rmse"] <= 1.15 * floor
    costs = [s["cv_rmse"] for s in j["waterfall"]]
    assert costs == sorted(costs, reverse=True)
