"""Steady cycles (pneunet.design.cycles): an autonomous oscillator's transient ended once
its cycle repeats measures what the whole transient measures; anything else is the
plain transient."""
import pickle
from pathlib import Path

import numpy as np
import pytest

from pneunet.design.cycles import steady_transient
from pneunet.engine import measure
from pneunet.netlist import parse_file
from pneunet.netlist.builder import NetlistBuilder
from pneunet.netlist.runner import evaluate_measures, run_deck

NETLIST = Path(__file__).resolve().parents[2] / "netlists" / "oscillator_design.pn"


def measures(deck, sol):
    values, failures = evaluate_measures(deck.measures, [(deck.analyses[0], sol)])
    assert not failures
    return values


@pytest.mark.parametrize("pclose", [None, 92.0, 101.0])
def test_steady_cycle_measures_what_the_whole_transient_measures(pclose):
    """The 12 s transient of netlists/oscillator_design.pn, stopped at its first repeated
    cycle (~5 s) and copied on: period, swing and extremes as the whole run's, to within
    its own error (5e-4 s, 0.01 kPa), the jumps at the same times, the rows to 12 s."""
    build = NetlistBuilder(NETLIST)
    point = {"Rout": 1.23, "Rvent": 2.36, "V": 114.7}
    if pclose is not None:
        point["X1.pclose"] = pclose
    deck = build.deck(point)
    whole = build(point).tran(12.0, t_step=0.01)
    steady = steady_transient(build(point), 12.0, 0.01)
    cycle = steady.stats["steady_cycle"]
    assert cycle["simulated_to_s"] <= 6.0
    a, b = measures(deck, steady), measures(deck, whole)
    assert a["period"] == pytest.approx(b["period"], abs=5e-4)
    assert cycle["period_s"] == pytest.approx(b["period"], abs=5e-4)
    for key in ("swing", "p_min", "p_max"):
        assert a[key] == pytest.approx(b[key], abs=1e-2)
    for signal in ("tank", "out"):  # out jumps: both sides of every jump are kept
        a, b = (sol.pressure(signal)[sol.t >= 5.0] for sol in (steady, whole))
        assert (a.min(), a.max()) == pytest.approx((b.min(), b.max()), abs=0.05)
    for tj in steady.jumps:  # the state just before each jump is a row, as in the whole run
        assert np.any((steady.t < tj) & (steady.t > tj - 5e-4))
    assert len(steady.jumps) == len(whole.jumps)
    assert np.allclose(steady.jumps, whole.jumps, atol=1e-3)
    assert steady.t[-1] == 12.0 and np.all(np.diff(steady.t) > 0)  # as the whole run's
    late = steady.t > 8.0  # copied rows: the whole run's signal at their times
    assert np.allclose(steady.pressure("tank")[late],
                       np.interp(steady.t[late], whole.t, whole.pressure("tank")), atol=0.2)


@pytest.mark.parametrize("supply", ["PULSE(96kPa 496kPa 0 1ms 1ms 30s 60s)",
                                    "SIN(496kPa 5kPa 0.1Hz)"])
def test_time_varying_sources_are_not_shortened(tmp_path, supply):
    """A supply that varies (a PULSE with corners, a SIN without) makes the circuit
    non-autonomous: no steady cycle (None), and a design measures the plain transient."""
    from pneunet.design.problem import Problem

    text = NETLIST.read_text().replace("PH supply 496kPa", f"PH supply {supply}")
    path = tmp_path / "pulsed.pn"
    path.write_text(text)
    deck = parse_file(path)
    assert steady_transient(deck.circuit, 12.0, 0.01) is None
    row = Problem(path, ["swing>=130kPa"], workers=1).evaluate([{}])[0]
    assert row["swing"] == run_deck(parse_file(path)).measures["swing"]


def test_a_circuit_that_never_switches_gets_the_plain_transient(monkeypatch):
    """No jump in the first third of the span (an actuator filling): that piece is
    dropped at once and the result is the plain transient's, to the bit."""
    from pneunet.engine import single_rate

    calls = []
    real = single_rate.integrate
    monkeypatch.setattr(single_rate, "integrate",
                        lambda *a, **k: calls.append(a[2]) or real(*a, **k))
    deck = parse_file(Path(__file__).resolve().parents[2] / "netlists" / "fill_time.pn")
    steady = steady_transient(deck.circuit, 0.4, 1e-3)
    assert calls == [pytest.approx(0.4 / 3)]  # the first piece only (then the plain run)
    whole = deck.circuit.tran(0.4, t_step=1e-3)
    assert "steady_cycle" not in steady.stats
    assert np.array_equal(steady.t, whole.t)
    assert np.array_equal(steady.pressure("act_v"), whole.pressure("act_v"))


def test_pickled_builders_parse_their_netlist_once_per_process(monkeypatch):
    """A sweep sends its builder with every point: the copies share one parse."""
    import pneunet.netlist as netlist

    calls = []
    real = netlist.load_file
    monkeypatch.setattr(netlist, "load_file", lambda *a, **k: calls.append(a) or real(*a, **k))
    build = NetlistBuilder(NETLIST)
    copies = [pickle.loads(pickle.dumps(build)) for _ in range(3)]
    circuits = [c({"Rout": 1.0 + k}) for k, c in enumerate(copies)]
    assert len(calls) == 1
    assert [c.elements["Rout"].params["R"] for c in circuits] == [1.0, 2.0, 3.0]
    assert copies[0].deck({"V": 50}).params["V"] == 50
    assert len(calls) == 1
    from pneunet.netlist import builder as B

    for _ in range(B.LOADED_KEPT + 2):  # more builders: only the last few sources are kept
        pickle.loads(pickle.dumps(NetlistBuilder(NETLIST)))({})
    assert len(B._LOADED) == B.LOADED_KEPT


def test_a_cycle_still_settling_is_not_taken_for_a_repeat():
    """A second, large volume on the vent (tank -> 1.0 -> v2 300 mL -> 0.8 -> atm) settles
    over cycles: jump states agree to ~3 kPa after two cycles, to ~0.02 kPa after four.  An
    early match would copy an unsettled cycle (a tolerance 1000x looser: period 5.383 s
    instead of 5.408 s); the steady result measures what the whole run measures."""
    from pneunet.netlist import parse_netlist

    text = NETLIST.read_text().replace(
        "Rvent tank atm {Rvent}kPa*s/mg",
        "Rvent tank v2 1.0kPa*s/mg\nV2 v2 300mL\nR2 v2 atm 0.8kPa*s/mg")
    whole = parse_netlist(text).circuit.tran(24.0, t_step=0.01)
    steady = steady_transient(parse_netlist(text).circuit, 24.0, 0.01)
    period = [measure.period(s.t, s.pressure("tank"), t_from=5.0) for s in (steady, whole)]
    assert period[0] == pytest.approx(period[1], abs=2e-3)
    assert steady.pressure("v2")[-1] == pytest.approx(whole.pressure("v2")[-1], abs=0.05)


def test_a_design_measures_the_steady_cycle_unless_told_not_to():
    """Problem's samples: on the steady cycle by default (within 5e-4 s of the whole
    run, not equal to it), the whole transient's own values with steady=False."""
    from pneunet.design.problem import Problem

    point = {"Rout": 1.23, "Rvent": 2.36, "V": 114.7}
    plain = run_deck(parse_file(NETLIST, overrides=point)).measures["period"]
    problem = Problem(NETLIST, ["period=3s"], workers=1)
    steady = problem.evaluate([point])[0]["period"]
    problem.analysis.steady = False
    problem._cache.clear()
    assert problem.evaluate([point])[0]["period"] == plain
    assert steady == pytest.approx(plain, abs=5e-4) and steady != plain


def test_each_points_params_reach_its_measurements(tmp_path):
    """The samples' deck is elaborated once per .param values (the analyses and .meas
    lines of the last one are reused): a .meas that reads a .param follows each point."""
    from pneunet.design.problem import Problem

    text = NETLIST.read_text().replace(".param Rout=1.132", ".param TM=6 Rout=1.132") + \
        ".meas tran p_at FIND p(tank) AT={TM}\n"
    path = tmp_path / "at.pn"
    path.write_text(text)
    problem = Problem(path, ["p_at>=100kPa"], workers=1)
    times = (6.0, 7.5, 6.2)
    rows = problem.evaluate([{"TM": tm} for tm in times])
    for row, tm in zip(rows, times):
        whole = run_deck(parse_file(path, overrides={"TM": tm})).measures["p_at"]
        assert row["p_at"] == pytest.approx(whole, abs=0.05)
    assert len({row["p_at"] for row in rows}) == 3
