"""Issue 11, criterion 1: circuit recordings made by a stand-alone model (scipy Radau of
the oscillator with each effect written out by hand, :mod:`.standalone`), 0.4 kPa noise,
20 Hz, 8 cycles, both recorded signals.

* clean: ``adequate``, and the 95 % intervals cover the true R_out, R_vent and V;
* every library effect in each of its published forms (dead volume; polytropic tank as
  p·V^n; the gas energy balance with a
  constant wall conductance, the gas entering at wall temperature and leaving at its
  own; tubes on the control and on the supply line): named first, the held-out error
  within 1.5× the noise floor the diagnosis estimated from the data, its size found;
* the polytropic tank in Richer–Hurmuzlu's form ṗ = n·R·T/(M·V)·ṁ with a constant n is
  the isothermal tank of volume V/n, which no recording can tell apart: ``adequate``,
  with the interval of V covering V/n;
* physics outside the library (membrane creep, a supply ripple): ``unexplained``, no
  effect named, and the report says where the residual sits.

Each diagnosis takes about a minute (``slow``): the default suite runs the clean, the
Richer–Hurmuzlu and the dead-volume cases; the others are marked ``study``
(``python -m pytest -m study``; CI runs both), but the two outside the library, 4–6
minutes each, ``study_long``.  ``benchmarks/study_trace_diagnosis.py``
prints the same cases as a table.
"""
import functools
import math

import pytest

from pneunet.design.circuits import oscillator
from pneunet.truth.circuits import diagnose_trace

from .standalone import oscillator_record

TRUE = {"Rout": 1.132, "Rvent": 3.0, "V": 50.0}
PARAMS = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "V": (65.0, 5.0, 500.0)}

#: hidden effect → (stand-alone keywords, effect the diagnosis must name first, the
#: fitted effect parameters and their true values in the library's form (None: a
#: different published form, its parameter is not the library's))
LIBRARY = {
    "dead volume at the valve output (1.5 mL)": (
        {"V_out": 1.5}, "dead_volume@out", {"V_dead@out": 1.5}),
    "polytropic tank, p·V^n (n = 1.3)": (
        {"poly_n": 1.3}, "polytropic_volume", {"n": 1.3}),
    # hA = m(200 kPa)·c_v/τ with τ = 0.5 s is τ = 0.5·96/200 s at the library's 96 kPa
    "energy balance, constant wall conductance (τ = 0.5 s at 200 kPa)": (
        {"heat_tau": 0.5}, "volume_heat_transfer", {"tau": 0.24}),
    # the control line carries little flow, where the quadrature law's regularisation
    # band (1 kPa² here, 10 in pneunet) shapes it: R·V is found, its split less sharply
    "tube on the control line (R = 10, V = 2 mL)": (
        {"tube_ctrl": (10.0, 2.0)}, "tube@X1.ctrl", {"R_tube@X1.ctrl*V_tube@X1.ctrl": 20.0}),
    "tube on the supply line (R = 0.5, V = 20 mL)": (
        {"tube_supply": (0.5, 20.0)}, "tube@X1.in", {"R_tube@X1.in": 0.5,
                                                      "V_tube@X1.in": 20.0}),
}
OUTSIDE = {
    "membrane creep (p_close drifts 0.4 kPa/s)": {"creep": 0.4},
    "supply ripple (12 kPa at 0.37 Hz)": {"ripple": (12.0, 0.37)},
}


@functools.lru_cache(maxsize=None)
def diagnosis(key):
    kw = dict(key)
    return diagnose_trace(oscillator, oscillator_record(12.0, noise=0.4, seed=1, **kw),
                          PARAMS, node="tank")


def run(kw):
    return diagnosis(tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v)
                                  for k, v in kw.items())))


def test_clean_recording_is_adequate_with_intervals_covering_the_truth():
    d = run({})
    j = d.to_json()
    assert j["verdict"] == "adequate" and j["accepted"] == []
    assert j["rms_unit"] == "kPa"
    assert j["noise_floor"] == pytest.approx(0.4, rel=0.2)  # from the data alone
    assert j["ranking"][0]["effect"] == "none"
    assert j["ranking"][0]["held_out_rms"] <= 1.5 * j["noise_floor"]
    for k, truth in TRUE.items():
        lo, hi = j["fit"]["ci"][k]
        assert lo < truth < hi, (k, lo, hi)
        assert hi - lo < 0.05 * truth  # and they say something
    for result, words in ((d, ("<TraceDiagnosis adequate:", "accepted nothing", "noise floor")),
                          (d.final, ("<TraceFit base model:", "estimates (95 % CI)", "Rvent"))):
        text = repr(result)  # one short line, not the residual table
        assert len(text) < 400 and "\n" not in text and all(w in text for w in words), text


#: the cases the default suite runs; the others are marked ``study`` (a minute each:
#: ``python -m pytest -m study``, which CI runs too)
#: the default suite's cases (the others, and the unexplained creep whose candidates are
#: each fitted from two starts, ~90 s, run with -m study)
IN_SUITE = ("dead volume at the valve output (1.5 mL)",)


#: cases left to ``python -m pytest -m study_long`` for CI's time (4–6 min each: nothing
#: explains them, so every candidate is fitted from two starts and with a second effect);
#: CI keeps the supply ripple recorded mid-run (tests/traces/test_midrun_study.py)
LONG_CASES = ("membrane creep (p_close drifts 0.4 kPa/s)", "supply ripple (12 kPa at 0.37 Hz)")


def _cases(names):
    return [pytest.param(n, marks=() if n in IN_SUITE else
                         pytest.mark.study_long if n in LONG_CASES else pytest.mark.study)
            for n in names]


@pytest.mark.slow
@pytest.mark.parametrize("name", _cases(LIBRARY))
def test_library_effect_is_named_first_and_reaches_the_floor(name):
    kw, effect, truth = LIBRARY[name]
    d = run(kw)
    j = d.to_json()
    assert j["ranking"][0]["effect"] == effect, [r["effect"] for r in j["ranking"]]
    assert j["verdict"] == "explained"
    assert j["accepted"][0] == effect
    assert j["ranking"][0]["held_out_rms"] <= 1.5 * j["noise_floor"]
    base = next(r for r in j["ranking"] if r["effect"] == "none")
    assert base["held_out_rms"] > 1.5 * j["noise_floor"]
    steps = [w["held_out_rms"] for w in j["waterfall"]]
    assert steps == sorted(steps, reverse=True) and len(steps) >= 2
    for k, value in (truth or {}).items():  # a parameter, or a product a*b
        fitted = math.prod(j["fit"]["values"][part] for part in k.split("*"))
        assert fitted == pytest.approx(value, rel=0.15), k


def test_a_constant_polytropic_factor_is_a_smaller_tank_and_adequate():
    n = 1.25
    j = run({"gas_law_n": n}).to_json()
    assert j["verdict"] == "adequate" and j["accepted"] == []
    lo, hi = j["fit"]["ci"]["V"]
    assert lo < TRUE["V"] / n < hi


@pytest.mark.slow
@pytest.mark.parametrize("name", _cases(OUTSIDE))
def test_physics_outside_the_library_is_unexplained(name):
    d = run(OUTSIDE[name])
    j = d.to_json()
    assert j["verdict"] == "unexplained"
    assert j["accepted"] == []
    assert any(w.startswith("p_tank") and "cycle phase" in w for w in j["where"])
    assert j["waterfall"][0]["held_out_rms"] > 1.5 * j["noise_floor"]
    assert all(r["held_out_rms"] is None or r["held_out_rms"] > 1.5 * j["noise_floor"]
               for r in j["ranking"])


@pytest.mark.slow
def test_a_candidate_whose_fit_fails_is_reported_not_a_crash(monkeypatch):
    """A candidate fit that cannot simulate the whole record (SolverError) is a failed
    candidate with the solver's message; the diagnosis still gives its verdict."""
    from pneunet.common.errors import SolverError
    from pneunet.truth.circuits import candidate_fits as module
    from pneunet.truth.circuits.effects import DeadVolume

    def failing(*args, **kwargs):
        raise SolverError("IDA stopped at t = 10 s", time=10.0)

    monkeypatch.setattr(module.CandidateFits, "_fit", failing)  # every start of every candidate
    d = diagnose_trace(oscillator, oscillator_record(12.0, noise=0.4, seed=1, V_out=1.5),
                       PARAMS, node="tank", effects=[DeadVolume("out")])
    j = d.to_json()
    assert j["verdict"] == "unexplained" and j["accepted"] == []
    row = next(r for r in j["ranking"] if r["effect"] == "dead_volume@out")
    assert row["held_out_rms"] is None and row["note"].startswith("fit failed: IDA stopped")
    assert row["status"] == "failed"


def test_the_screens_simulations_are_all_counted(monkeypatch):
    """``timing.screen_simulations`` counts every screening simulation: the grid's points,
    their zoom and start steps, and the second starts' screens (here every fit fails, so
    each candidate gets one).  Counted in this process (one worker)."""
    from pneunet.common.errors import SolverError
    from pneunet.truth.circuits import candidate_fits as module
    from pneunet.truth.circuits.effects import DeadVolume
    from pneunet.truth.circuits.screen import ScreenTask

    counted = []
    call, step = ScreenTask.__call__, ScreenTask.step

    def counting_call(self):
        out = call(self)
        counted.append(out["simulations"])
        return out

    def counting_step(self, at):
        values, calls = step(self, at)
        counted.append(calls)
        return values, calls

    def failing(*args, **kwargs):
        raise SolverError("IDA stopped at t = 10 s", time=10.0)

    monkeypatch.setattr(ScreenTask, "__call__", counting_call)
    monkeypatch.setattr(ScreenTask, "step", counting_step)
    monkeypatch.setattr(module.CandidateFits, "_fit", failing)
    d = diagnose_trace(oscillator, oscillator_record(12.0, noise=0.4, seed=1, V_out=1.5),
                       PARAMS, node="tank", effects=[DeadVolume("out")], workers=1)
    assert len(counted) > 5 + 2 * 3  # the grid, at least the first zoom's rounds, a step
    assert d.timing["screen_simulations"] == sum(counted)


def test_every_fits_simulations_are_counted_the_refinement_too(monkeypatch):
    """``timing.simulations`` counts the simulations of every fit, the base fit's and
    its refinement's alike (the refined fit replaces the base fit it refines, whose count
    stays); each fit's final simulation of its result is outside its count.  A clean
    recording, `adequate`: nothing is screened.  Counted in this process (one worker)."""
    from pneunet.truth.circuits.model import TraceModel

    calls = []
    simulate = TraceModel.simulate

    def counting(self, *args, **kwargs):
        calls.append(1)
        return simulate(self, *args, **kwargs)

    monkeypatch.setattr(TraceModel, "simulate", counting)
    d = diagnose_trace(oscillator, oscillator_record(24.0, noise=0.4, seed=1), PARAMS,
                       node="tank", workers=1)
    assert d.verdict == "adequate" and "screen_simulations" not in d.timing
    assert d.timing["refine_simulations"] > 0
    assert d.timing["simulations"] + 2 == len(calls), (d.timing, len(calls))
