"""Recordings as a logger makes them, diagnosed whole (issue 31; one to four minutes each).
CI runs the ``study`` cases (``python -m pytest -m study``): the new user's recording, an
oscillator of other values sampled at 50 Hz, a slow one recorded for two and a half
cycles, the oscillator's heat exchange recorded
mid-run, the clean driven one and, on an amplifier of other values, a dead volume the
screen leaves out, found through the tube that fits it.
The single effects, heat plus a tube at once (both effects named; 4.6 min), the leak and
the compliant actuator (outside the library; 4–5 min each) are ``study_long``
(``python -m pytest -m study_long``;
``benchmarks/study_trace_diagnosis.py --driven`` runs the same cases for its table).

* The new user's recording: the oscillator of ``netlists/oscillator.pn`` with R_vent 3.5
  (netlist: 3) and a hidden 3 mL volume at ``out``, 20 Hz, 0.3 kPa noise (and at 50 Hz,
  0.5 kPa), the logger
  started 8 s after switch-on (tank at ~200 kPa mid-cycle), 40 s: ``explained`` by
  ``dead_volume@out`` with intervals covering R_vent, V and the 3 mL.
* A driven circuit: the flow amplifier (``netlists/amplifier.pn``) filling a 30 mL
  actuator through a 0.24 kPa·s/mg line, both valves switched by antiphase pulses,
  p_act and p_muscle at 100 Hz from a time 0–20 s on the sources' clock, 0.3 kPa noise:
  clean → ``adequate`` with intervals covering the truth; heat exchange in the actuator,
  a dead volume between the valves, a tube on the in-valve's control line, heat exchange
  plus that tube → each named; an actuator leak and a compliant actuator (outside the
  library) → ``unexplained``.

Recordings from stand-alone models only (:mod:`.standalone`, :mod:`.standalone_driven`).
"""
import functools

import numpy as np
import pytest

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import diagnose_trace

from .standalone import oscillator_record
from .standalone_driven import amplifier_record

DRIVEN_PARAMS = {"Rtube.R": (0.2, 0.02, 2.0), "Amck.V": (25.0, 5.0, 200.0)}
DRIVEN_TRUTH = {"Rtube.R": 0.24, "Amck.V": 30.0}


@pytest.mark.study
@pytest.mark.parametrize("dt, noise", [(0.05, 0.3), (0.02, 0.5)], ids=["20Hz", "50Hz"])
def test_new_users_mid_run_recording_is_explained_by_the_dead_volume(tmp_path, dt, noise):
    """At 20 Hz as the issue recorded it, and at 50 Hz: there the valve output's edges
    span samples, and the dead volume's valley is narrower than the screen's grid
    (unexplained, 2.5–5.2× the floor, before both were handled)."""
    rec = oscillator_record(48.0, dt=dt, noise=noise, seed=3, V=200.0, Rvent=3.5, V_out=3.0)
    rec = rec[rec["time_s"] >= 8.0 - 1e-9].reset_index(drop=True)
    rec["time_s"] -= 8.0
    path = tmp_path / "mid.csv"
    rec.to_csv(path, index=False)
    d = diagnose_trace(NetlistBuilder("netlists/oscillator.pn"), path,
                       {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0),
                        "Vtank.V": (250.0, 50.0, 600.0)}, node="tank")
    j = d.to_json()
    assert j["start_state"]["mode"] == "record"
    assert j["verdict"] == "explained" and j["accepted"] == ["dead_volume@out"], d.report()
    for k, truth in {"Rvent": 3.5, "Vtank.V": 200.0, "V_dead@out": 3.0}.items():
        lo, hi = j["fit"]["ci"][k]
        assert lo <= truth <= hi, (k, lo, hi)
    # every candidate is accounted for: fitted, screened out (with its merit) or failed
    for row in j["ranking"][1:]:
        assert row["status"] in ("fitted", "screened out", "failed")
        assert row["status"] != "screened out" or row["screen_rms"] is not None


@pytest.mark.study
def test_an_oscillator_sampled_finer_than_its_fits_resolve_is_fitted_on_fewer_samples():
    """Other values, 50 Hz: the 240 mL oscillator (R_out 1.0) with a hidden 3 mL dead
    volume, from 9.9 s, 8.8 s cycles.  A difference step of 0.005 moves a cycle's end by
    2.2 samples; fitted on every sample, each dead-volume fit stopped at 2.5–4.9× the
    floor and a wrong pair (dead volume + supply tube, 1.22×) was accepted with every
    interval missing the truth.  On one sample in 3: the dead volume, intervals covering."""
    j = dead_volume_found(9.9, 40.0, dt=0.02, noise=0.4, seed=23, V=240.0, Rvent=3.5,
                          Rout=1.0, V_out=3.0)
    assert j["fitted_every_nth_sample"] == 3
    assert any("one sample in 3" in n for n in j["notes"])


@pytest.mark.study
def test_a_record_of_two_and_a_half_cycles_is_explained_by_the_dead_volume():
    """A slow oscillator (380 mL, R_vent 3.4: ~15 s cycles) recorded at 50 Hz for 40 s
    from 9 s: the fit window holds one cycle, on which the states that a tube or heat
    exchange adds cannot settle before they are compared.  The screen ranked those
    first; their fits fail (with the reason) and the screen's next ones are fitted in
    their place.  Before, the dead volume was screened out behind them and the verdict
    was ``unexplained`` (the base model 4.9× the floor)."""
    j = dead_volume_found(9.0, 40.0, dt=0.02, noise=0.3, seed=42, V=380.0, Rvent=3.4,
                          V_out=3.5)
    failed = {r["effect"] for r in j["ranking"] if r["status"] == "failed"}
    assert "tube@X1.ctrl" in failed  # its states settle after the fit window


def dead_volume_found(start, seconds, **record):
    """The JSON of the diagnosis of the stand-alone oscillator (``record``: its values,
    a hidden ``V_out``) logged for ``seconds`` from ``start`` s, its clock from 0, with the
    new user's guesses, once asserted ``explained`` by ``dead_volume@out`` with every
    interval covering the truth."""
    rec = oscillator_record(start + seconds, **record)
    rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    d = diagnose_trace(NetlistBuilder("netlists/oscillator.pn"), rec,
                       {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0),
                        "Vtank.V": (250.0, 50.0, 600.0)}, node="tank")
    j = d.to_json()
    assert j["verdict"] == "explained" and j["accepted"] == ["dead_volume@out"], d.report()
    truth = {"Rout": record.get("Rout", 1.132), "Rvent": record["Rvent"],
             "Vtank.V": record["V"], "V_dead@out": record["V_out"]}
    for k, value in truth.items():
        lo, hi = j["fit"]["ci"][k]
        assert lo <= value <= hi, (k, lo, hi)
    return j


@functools.lru_cache(maxsize=None)
def driven(case):
    kw = dict(case)
    start = float(np.random.default_rng(len(case)).uniform(0.0, 20.0))
    rec = amplifier_record(start, 30.0, dt=0.01, noise=0.3, seed=5,
                           R_line=DRIVEN_TRUTH["Rtube.R"], V=DRIVEN_TRUTH["Amck.V"], **kw)
    return diagnose_trace(NetlistBuilder("netlists/amplifier.pn"), rec, DRIVEN_PARAMS,
                          node="muscle")


@pytest.mark.study
def test_clean_driven_recording_is_adequate_and_covered():
    d = driven(())
    j = d.to_json()
    assert j["verdict"] == "adequate", d.report()
    assert j["start_state"]["driven"]
    for k, truth in DRIVEN_TRUTH.items():
        lo, hi = j["fit"]["ci"][k]
        assert lo <= truth <= hi, (k, lo, hi)


LONG = pytest.mark.study_long


@pytest.mark.parametrize("case, expected", [
    pytest.param((("heat_tau", 1.0),), {"volume_heat_transfer"}, marks=LONG),
    pytest.param((("V_act", 6.0),), {"dead_volume@act"}, marks=LONG),
    pytest.param((("tube_ctrl", (5.0, 5.0)),), {"tube@Xin.ctrl"}, marks=LONG),
    pytest.param((("heat_tau", 1.0), ("tube_ctrl", (5.0, 5.0))),
                 {"volume_heat_transfer", "tube@Xin.ctrl"}, marks=LONG),
])
def test_driven_hidden_effect_is_named(case, expected):
    d = driven(case)
    assert d.verdict == "explained" and set(d.accepted) == expected, d.report()


@pytest.mark.parametrize("case", [pytest.param((("leak", 15.0),), marks=LONG),
                                  pytest.param((("compliance", 0.004),), marks=LONG)])
def test_driven_physics_outside_the_library_is_unexplained(case):
    d = driven(case)
    assert d.verdict == "unexplained", d.report()
    assert d.where


@pytest.mark.study
def test_a_dead_volume_the_screen_misses_is_found_through_the_tube_that_fits_it():
    """The amplifier of other values (R_line 0.4, V 50 mL) with 4 mL between its valves,
    from 7.3 s: the dead volume's best grid point (1.0 mL) had it screened out, and the
    record was `explained` by ``tube@Xin.out`` (R 0.0073, V 3.997 mL: the same volume at
    the same node).  The dead volume at a fitted tube's node is fitted from the tube's
    volume, and fits alike with fewer parameters."""
    rec = amplifier_record(7.3, 30.0, dt=0.01, noise=0.35, seed=17, R_line=0.4, V=50.0,
                           V_act=4.0)
    d = diagnose_trace(NetlistBuilder("netlists/amplifier.pn"), rec, DRIVEN_PARAMS,
                       node="muscle")
    assert d.verdict == "explained" and d.accepted == ["dead_volume@act"], d.report()
    for k, truth in {"Rtube.R": 0.4, "Amck.V": 50.0, "V_dead@act": 4.0}.items():
        lo, hi = d.final.ci[k]
        assert lo <= truth <= hi, (k, lo, hi)


@pytest.mark.study
def test_a_dead_volume_that_a_tube_fits_alike_is_named_with_its_fewer_parameters():
    """The 6 mL dead volume between the valves, recorded from 10.77 s (the driven study's
    seed 1): a tube at the in-valve's output (R 0.012, V 5.98 mL) and the dead volume
    (6.0 mL) both reach the floor, held out 0.2983 kPa each, and the tube came first by
    the fourth digit.  The recording cannot tell them apart: the dead volume, one
    parameter, is taken, and the note says so."""
    rec = amplifier_record(10.766, 30.0, dt=0.01, noise=0.3, seed=1,
                           R_line=DRIVEN_TRUTH["Rtube.R"], V=DRIVEN_TRUTH["Amck.V"], V_act=6.0)
    # from the record's first samples, as when this was found (``auto`` now also fits
    # from rest driven to the first sample and keeps that: there the dead volume is
    # still named, but the two no longer fit alike)
    d = diagnose_trace(NetlistBuilder("netlists/amplifier.pn"), rec, DRIVEN_PARAMS,
                       node="muscle", start_state="record")
    assert d.verdict == "explained" and d.accepted == ["dead_volume@act"], d.report()
    assert any("cannot tell them apart" in n for n in d.notes), d.notes
    lo, hi = d.final.ci["V_dead@act"]
    assert lo <= 6.0 <= hi


@pytest.mark.study
def test_oscillator_heat_exchange_recorded_mid_run_is_named():
    """The oscillator's tank with an energy balance (constant hA, τ 0.5 s at 200 kPa),
    the logger started 4.9 s after switch-on (``study_trace_diagnosis.py --mid-run``),
    the tank at 315 kPa and the valve open.  It came out ``unexplained`` (6.47 → 3.65×
    the floor): heat exchange makes the tank a thermal chamber whose inlet nodes were
    started at the valve output's pressure, which closed the valve at the first sample,
    and the consistent state failed at random trial R_out (a continuation 2-cycle around
    the closed valve's root), so no fit moved R_out from the base's 1.006 (truth 1.132).
    Now named, each 95 % interval covering the truth."""
    from pneunet.design.circuits import oscillator

    start = float(np.random.default_rng([1, 7]).uniform(2.0, 10.0))
    rec = oscillator_record(12.0 + start, noise=0.4, seed=1, heat_tau=0.5)
    rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    params = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "V": (65.0, 5.0, 500.0)}
    d = diagnose_trace(oscillator, rec, params, node="tank")
    assert d.verdict == "explained" and d.accepted == ["volume_heat_transfer"], d.report()
    # the gas temperature at the first sample is a guess (the wall's): compared from the
    # first cycle start it left 1.18× the floor and R_out's interval [1.133, 1.151] missed
    # 1.132; from the second (one whole cycle to settle), every interval covers.  τ in
    # pneunet's reference (hA = m_ref·c_v/τ, m_ref at p_ref = ambient 96 kPa): 0.5·96/200
    assert d.waterfall.steps[-1].held_out < 1.1 * d.noise_floor
    for k, truth in {"Rout": 1.132, "Rvent": 3.0, "V": 50.0, "tau": 0.24}.items():
        lo, hi = d.final.ci[k]
        assert lo <= truth <= hi, (k, d.final.values[k], d.final.ci[k])


@pytest.mark.study_long  # 291 s of a worker; CI keeps test_confusion's unlisted effects
def test_a_supply_ripple_recorded_mid_run_is_unexplained_and_its_waterfall_never_rises():
    """A 12 kPa, 0.37 Hz ripple on the oscillator's supply (outside the library), the
    logger started 4.9 s after switch-on.  Every candidate fits the held-out cycles worse
    than the base model (the best, ``dead_volume@out``, 82.66× the floor against the
    base's 64.56×), and that fit was drawn as a waterfall step, a "drop" that was a
    rise.  A step is now an effect that lowers the held-out error; the candidates stay in
    the ranking."""
    from pneunet.design.circuits import oscillator

    start = float(np.random.default_rng([1, 7]).uniform(2.0, 10.0))
    rec = oscillator_record(12.0 + start, noise=0.4, seed=1, ripple=(12.0, 0.37))
    rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    params = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "V": (65.0, 5.0, 500.0)}
    d = diagnose_trace(oscillator, rec, params, node="tank")
    assert d.verdict == "unexplained" and d.accepted == [], d.report()
    errors = [s.held_out for s in d.waterfall.steps]
    assert errors == sorted(errors, reverse=True), d.waterfall.table()
    fitted = [r for r in d.ranking if r["effect"] != "none" and r["held_out_rms"] is not None]
    assert fitted  # the candidates were fitted and are reported
