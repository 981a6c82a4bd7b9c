"""Issue 32: ordinary careless inputs give a located warning or error that points the
right way, never a silently implausible reading (bare numbers, SPICE scale factors, kind
words that are element names, units in .param, a unit apart from its number)."""
import warnings

import pytest

from pneunet.common.errors import InputWarning, NetlistError
from pneunet.netlist import parse_netlist

HEAD = "P1 a 200kPa\n"


def _warnings(text):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        deck = parse_netlist(text)
    return deck, [w.message for w in caught if isinstance(w.message, InputWarning)]


@pytest.mark.parametrize("line, word, meant", [
    ("mckibben M1 a L0=53cm D0=12mm theta0=0.35 mass=200g", "theta0=0.35", "0.35rad (20.05 deg)"),
    ("mckibben M1 a L0=53cm D0=12mm theta0=25 mass=200", "mass=200", "200g (0.2 kg)"),
    ("tube L1 a b length=3 diameter=2mm\nVb b 1mL", "length=3", "3m (3000 mm)"),
    ("pipe T1 a b length=2 diameter=1mm\nVb b 1mL", "length=2", "2m (2000 mm)"),
    ("A1 a length=0.2 diameter=20mm", "length=0.2", "0.2m (200 mm)"),
    ("P2 b 4\nR1 a b 1", "4", "4bar (400 kPa)"),
])
def test_a_bare_number_outside_its_usual_range_is_a_located_warning(line, word, meant):
    text = HEAD + line + "\n.tran 1s\n"
    _, found = _warnings(text)
    assert len(found) == 1, [str(w) for w in found]
    w = found[0]
    row = text.splitlines().index(next(s for s in text.splitlines() if word in s.split()))
    assert w.span.line == row + 1
    assert text.splitlines()[row][w.span.column - 1:].startswith(word.split("=")[-1]) or \
        text.splitlines()[row][w.span.column - 1:].startswith(word)
    assert "bare number" in w.message and meant in w.hint
    assert w.report().startswith(f"{w.span}: warning: ")


@pytest.mark.parametrize("line", [
    "mckibben M1 a L0=53cm D0=12mm theta0=25deg mass=200g",
    "mckibben M1 a L0=53cm D0=12mm theta0=0.35rad mass=200kg",   # a unit says what is meant
    "tube L1 a b length=3m diameter=2mm\nVb b 1mL",
    "A1 a length=173mm diameter=20mm",
])
def test_usual_values_and_values_with_their_unit_pass_quietly(line):
    assert _warnings(HEAD + line + "\n.tran 1s\n")[1] == []


def test_a_value_far_outside_its_laws_sense_warns_even_with_a_unit():
    _, found = _warnings(HEAD + "tube L1 a b length=30m diameter=4m\nVb b 1mL\n.tran 1s\n")
    assert len(found) == 1 and "diameter=4m is 4000 mm" in found[0].message


def test_a_tube_shorter_than_its_bore_is_an_error_at_check_time():
    # 3M is SPICE milli: 3 µm, which reached the solver and ended in numpy warnings
    with pytest.raises(NetlistError) as info:
        _warnings(HEAD + "tube L1 a b length=3M diameter=2mm\nVb b 1mL\n.tran 1s\n")
    err = info.value
    assert (err.span.line, err.span.column) == (2, 6)
    assert "shorter than the bore" in err.message and "M and m are milli" in err.hint
    for kind in ("pipe", "laminar_tube"):
        fluid = ".options fluid=water\n" if kind == "laminar_tube" else ""
        with pytest.raises(NetlistError, match="shorter than the bore"):
            parse_netlist(fluid + HEAD + f"{kind} L1 a atm length=1mm diameter=2mm\n.tran 1s\n")


def test_the_spice_milli_m_warns_where_a_length_is_far_too_small():
    _, found = _warnings(HEAD + "tube L1 a b length=30M diameter=0.01mm\nVb b 1mL\n.tran 1s\n")
    assert any("M is SPICE milli" in w.message for w in found)


def test_an_element_named_like_a_kind_word_is_an_element():
    deck = parse_netlist(HEAD + "R1 a tank 1\nVt tank 50mL\n.tran 1s\n")
    spec = deck.circuit.elements["Vt"]
    assert spec.kind == "volume" and spec.params["V"] == 50.0
    deck = parse_netlist(HEAD + "R1 a tank 1\nVT V2 tank th 50mL tau=0.2\n.tran 1s\n")
    assert deck.circuit.elements["V2"].kind == "thermal_volume"
    with pytest.raises(NetlistError) as info:   # neither reading works: say how it was read
        parse_netlist(HEAD + "R1 a tank 1\nVt tank\n.tran 1s\n")
    assert "read as a thermal_volume (kind word 'Vt')" in info.value.hint


@pytest.mark.parametrize("text, value", [
    ("2kg", 2.0), ("5newton", 5.0), ("0.5N/mm", 500.0), ("20N*s/m", 20.0), ("25deg", 25.0),
    ("0.1mL/kPa", 0.1), ("0.35rad", 20.053522829578812), ("40L/min", 861.51629507551),
    ("2g/s", 2000.0),
])
def test_a_param_takes_every_dimension_an_element_parameter_takes(text, value):
    deck, found = _warnings(f".param m={text}\n{HEAD}R1 a b 1\nVb b 1mL\n.tran 1s\n")
    assert deck.params["m"] == pytest.approx(value, rel=1e-12) and found == []


@pytest.mark.parametrize("text, value", [("300g", 3e11), ("5N", 5e-9), ("2t", 2e12)])
def test_a_scale_letter_that_is_also_a_unit_warns_in_a_param(text, value):
    deck, found = _warnings(f".param m={text}\n{HEAD}R1 a b 1\nVb b 1mL\n.tran 1s\n")
    assert deck.params["m"] == pytest.approx(value)   # SPICE, as documented ...
    assert len(found) == 1 and "SPICE scale factor" in found[0].message   # ... but said
    assert (found[0].span.line, found[0].span.column) == (1, 10)


def test_a_param_mass_reaches_the_muscle():
    deck = parse_netlist(".param m=2kg\n" + HEAD + "mckibben M1 a L0=53cm D0=12mm "
                         "theta0=25deg mass={m}\n.tran 1s\n")
    assert deck.circuit.elements["M1"].params["mass"] == 2.0


@pytest.mark.parametrize("line, column", [
    ("tube L1 a b length=3 m diameter=2mm\nVb b 1mL", 22),
    ("R1 a b 1 kPa*s/mg\nVb b 1mL", 10),
    ("R1 a b 1\nVb b 250 mL", 10),
])
def test_a_unit_apart_from_its_number_gets_the_remove_the_space_hint(line, column):
    with pytest.raises(NetlistError) as info:
        parse_netlist(HEAD + line + "\n.tran 1s\n")
    err = info.value
    assert "without a number" in err.message and "remove the space" in err.hint
    assert err.span.column == column


def test_a_pressure_level_and_an_option_far_from_the_usual_warn():
    _, found = _warnings("P1 a PULSE(0 200kPa 0.1 1m 1m 0.3 1)\nR1 a b 1\nVb b 1mL\n.tran 1s\n")
    assert len(found) == 1 and "low=0 is read as 0 kPa" in found[0].message
    assert found[0].hint.startswith("did you mean 0kPag (101.3 kPa)?")
    assert (found[0].span.line, found[0].span.column) == (1, 12)
    _, found = _warnings(".options temperature=20\n" + HEAD + "R1 a b 1\nVb b 1mL\n.tran 1s\n")
    assert len(found) == 1 and "20degC (293.1 K)" in found[0].hint
    _, found = _warnings(".options temperature=20degC ambient=96kPa\n" + HEAD +
                         "P2 c PWL(0 100kPa 1 3bar)\nR1 a b 1\nVb b 1mL\nR2 c b 1\n.tran 1s\n")
    assert found == []


def test_an_initial_pressure_far_from_the_usual_warns_where_it_is_written():
    _, found = _warnings(HEAD + "R1 a b 1\nVb b 1mL p0=3\n.ic b=5\n.tran 1s\n")
    assert [(w.span.line, w.span.column) for w in found] == [(3, 13), (4, 7)]
    assert found[0].hint.startswith("did you mean 3bar (300 kPa)")
    assert _warnings(HEAD + "R1 a b 1\nVb b 1mL p0=3bar\n.ic b=150kPa\n.tran 1s\n")[1] == []
