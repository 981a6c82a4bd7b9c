"""Language features: units and scale factors, expressions, subcircuits, includes, models, .meas."""
import numpy as np
import pytest

from pneunet.engine import measure as M
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_file, parse_netlist
from pneunet.physics.waveforms import Pulse, Sine, Step


def params(text, name):
    return parse_netlist(text).circuit.elements[name].params


@pytest.mark.parametrize("value,expected", [
    ("496kPa", 496), ("4.96bar", 496), ("72psi", 496.42), ("200kPag", 296), ("2k", 2000),
    ("0.5meg", 5e5), ("500m", 0.5)])
def test_pressure_units_and_scale_factors(value, expected):
    text = f".options ambient=96kPa\nP1 n {value}\nV1 n 1mL\n"
    assert params(text, "P1")["value"].level == pytest.approx(expected, rel=1e-4)


@pytest.mark.parametrize("value,slot_param,expected", [
    ("200mL", "V", 200), ("0.2L", "V", 200), ("1u", "V", 1e-6)])
def test_volume_units(value, slot_param, expected):
    assert params(f"P1 n 2bar\nV1 n {value}\n", "V1")[slot_param] == pytest.approx(expected)


def test_units_win_over_scale_factors_in_their_dimension():
    p = params("P1 a 2bar\npipe T1 a b length=1m diameter=1.2mm\nV1 b 1mL\n", "T1")
    assert p["length"] == 1000.0 and p["diameter"] == 1.2     # 1m = one metre in a length
    w = params("P1 a STEP(1bar 2bar 5ms 5m)\nV1 a 1mL\n", "P1")["value"]
    assert (w.at, w.rise) == (0.005, 0.005)                    # 5ms unit, 5m = milli


def test_resistance_and_flow_units():
    p = params("P1 a 2bar\nR1 a b 0.566kPa*s/mg\nF1 b 0 40L/min\nV1 b 1mL\n", "F1")
    assert p["value"].level == pytest.approx(40 * 1e3 / 60 * 1.2923, rel=1e-3)  # normal litres
    with pytest.raises(NetlistError, match=r"R needs kPa·s/mg, got kPa"):
        parse_netlist("P1 a 2bar\nR1 a b 3kPa\nV1 b 1mL\n")


def test_expressions_and_params():
    text = """.param Rf=0.566 Rout={2*Rf} n=3
.param big={max(1, sqrt(16)) ^ 2 + (n > 2 ? 1 : 0)}
P1 a 4bar
R1 a b {Rout}
R2 b c {big}
V1 c {n*100}mL
"""
    deck = parse_netlist(text)
    assert deck.circuit.elements["R1"].params["R"] == pytest.approx(1.132)
    assert deck.circuit.elements["R2"].params["R"] == 17.0
    assert deck.circuit.elements["V1"].params["V"] == 300.0
    assert deck.params["Rout"] == pytest.approx(1.132)


def test_expressions_never_use_python_eval():
    with pytest.raises(NetlistError):
        parse_netlist(".param a={__import__('os')}\n")


def test_comments_continuation_case_insensitive():
    text = """* title line
.PARAM r=2 ; a comment
P1 a 4bar
R1 a b
+ {r}   ; continued
V1 b 1mL
.TRAN 1
"""
    deck = parse_netlist(text)
    assert deck.title == "title line"
    assert deck.circuit.elements["R1"].params["R"] == 2.0
    assert deck.analyses[0].t_stop == 1.0


def test_waveforms():
    p = params("P1 a PULSE(96kPa 496kPa 1 10m 10m 2 4)\nV1 a 1mL\n", "P1")["value"]
    assert p == Pulse(96, 496, 1, 0.01, 0.01, 2, 4)
    s = params("P1 a SIN(300kPa 1bar 2Hz)\nV1 a 1mL\n", "P1")["value"]
    assert s == Sine(300, 100, 2)
    s = params(".options ambient=96kPa\nP1 a STEP(initial=0kPag final=200kPag at=1)\nV1 a 1mL\n",
               "P1")["value"]
    assert s == Step(96, 296, 1)


def test_subcircuit_nesting_parameters_and_arrays():
    text = """.subckt INNER a b R=1
R1 a b {R}
.ends
.subckt OUTER a b k=1
Xi a m INNER R={k*2}
Vm m 1mL
Xj m b INNER
.ends
P1 s 3bar
Xo[0:2] s n[0:2] OUTER k={index+1}
Vn[0:2] n[0:2] 2mL
"""
    c = parse_netlist(text).circuit
    assert c.elements["Xo[2].Xi.R1"].params["R"] == 6.0
    assert c.elements["Xo[2].Xi.R1"].nodes == ("s", "Xo[2].m")
    assert c.elements["Xo[0].Xj.R1"].nodes == ("Xo[0].m", "n[0]")
    c.validate()


def test_include_relative_to_including_file(tmp_path):
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "valves.pn").write_text('.model fast VALVE(axi Rf=0.3)\n.include "more.pn"\n')
    (tmp_path / "lib" / "more.pn").write_text(".param pH=496kPa\n")
    (tmp_path / "top.pn").write_text('.include "lib/valves.pn"\nP1 a {pH}\n'
                                     'X1 a b b fast\nV1 b 1mL\nR1 b 0 3\n')
    c = parse_file(tmp_path / "top.pn").circuit
    assert c.elements["X1"].params["model"].Rf == 0.3
    assert c.elements["P1"].params["value"].level == 496.0


def test_model_cards_and_paper_valves():
    deck = parse_netlist(".model m VALVE(mirror pclose=25kPa)\nP1 a 4bar\nX1 a b b m\n"
                         "X2 a b b axi\nV1 b 1mL\n")
    assert deck.circuit.elements["X1"].params["model"].pclose == 25.0
    assert deck.circuit.elements["X2"].params["model"].Rf == 0.566


def test_model_card_with_effect_parameters():
    from pneunet.physics.valve_effects import available_effects, get_effect

    eid = available_effects()[0]
    eff = get_effect(eid)
    pname, par = next(iter(eff.params.items()))
    value = (par.lo + par.hi) / 2 if np.isfinite(par.hi) else par.lo + 1
    deck = parse_netlist(f".model m VALVE(axi {eff.card_prefix()}{pname}={value!r})\n"
                         "P1 a 4bar\nX1 a b b m\nV1 b 1mL\n")
    model = deck.circuit.elements["X1"].params["model"]
    assert callable(getattr(model, "flow", None))
    with pytest.raises(NetlistError, match="unknown valve model parameter"):
        parse_netlist(".model m VALVE(axi nosuch_effect=1)\n")


def test_ic_and_gauge_with_ambient():
    c = parse_netlist(".options ambient=96kPa\nP1 a 4bar\nR1 a b 1\nV1 b 1mL\n"
                      ".ic p(b)=100kPag\n").circuit
    assert c.initial == {"b": 196.0}
    assert c.options.ambient == 96.0


def test_analyses_and_steps():
    deck = parse_netlist(""".param R=1 C=1
P1 a 4bar
R1 a b {R}
V1 b 1mL
.tran 1ms 2s
.op
.dc P1 200kPa 400kPa 100kPa
.step param R 1 2 0.5
.step param C list 3 4
""")
    kinds = [a.kind for a in deck.analyses]
    assert kinds == ["tran", "op", "dc"]
    assert deck.analyses[2].values == [200, 300, 400]
    assert len(deck.step_points()) == 6
    assert deck.variant({"R": 2.0}).circuit.elements["R1"].params["R"] == 2.0


# ---- measurements on synthetic data ------------------------------------------------------
T = np.linspace(0, 10, 20001)
Y = 200 + 50 * np.sin(2 * np.pi * 0.4 * T)


def test_measure_basic():
    assert M.value_at(T, Y, 0.625) == pytest.approx(250, abs=1e-3)
    assert M.maximum(T, Y) == pytest.approx(250, abs=1e-3)
    assert M.minimum(T, Y, 0, 1) == pytest.approx(200, abs=1e-9)
    assert M.peak_to_peak(T, Y) == pytest.approx(100, abs=1e-3)
    assert M.average(T, Y, 0, 5) == pytest.approx(200, abs=1e-4)
    assert M.rms(T, Y - 200, 0, 5) == pytest.approx(50 / np.sqrt(2), rel=1e-4)


def test_measure_crossings_period_frequency():
    assert M.period(T, Y) == pytest.approx(2.5, rel=1e-6)
    assert M.frequency(T, Y, level=210, cycles=2) == pytest.approx(0.4, rel=1e-6)
    assert M.when(T, Y, 200, "rise", 1) == pytest.approx(2.5, abs=1e-6)  # t=0 is no crossing
    assert M.when(T, Y, 200, "fall", 1) == pytest.approx(1.25, abs=1e-6)
    assert M.when(T, Y, 225, "rise", -1) == pytest.approx(7.5 + 1 / 12 / 0.4, abs=1e-6)
    with pytest.raises(M.MeasureError):
        M.when(T, Y, 400, "rise")
    with pytest.raises(M.MeasureError):
        M.period(T, np.full_like(T, 3.0))


def test_measure_rise_fall_and_trig_targ():
    t = np.linspace(0, 1, 1001)
    y = 96 + 200 * (1 - np.exp(-t / 0.1))
    expected = 0.1 * (np.log(200 / 180) * -1 + np.log(200 / 20))
    assert M.transition_time(t, y, 116, 276) == pytest.approx(expected, rel=1e-4)
    assert M.transition_time(t, 392 - y, 276, 116) == pytest.approx(expected, rel=1e-4)
    d = M.trig_targ(T, Y, {"val": 225, "edge": "rise", "n": 1}, T, Y, {"val": 250, "edge": "cross"})
    assert d == pytest.approx(0.625 - 1 / 12 / 0.4, abs=1e-3)
