"""Issue 32: a law used outside its range, or an element that never did its job, is a
warning once per element and run naming the element's line, the time and the quantity,
whatever the run saves (like the muscle's "cannot lift" warning)."""
import re
import warnings

import numpy as np
import pytest

from pneunet.interfaces.cli import main
from pneunet.physics.elements.run_checks import RangeWarning
from pneunet.netlist import parse_netlist

WATER = """.options fluid=water
P1 pump 3bar
laminar_tube T1 pump act length=1m diameter=1mm
accumulator A1 act 20mL 0.05mL/kPa
laminar_tube T2 act atm length=2m diameter=0.5mm
"""


def _run(text, t_stop=0.5):
    deck = parse_netlist(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = deck.circuit.tran(t_stop, t_step=0.01)
    return sol, [str(w.message) for w in caught if issubclass(w.category, RangeWarning)]


def test_a_laminar_tube_past_re_2000_warns_once_with_its_reynolds_number():
    sol, found = _run(WATER)
    assert len(found) == 1 and found[0].startswith("<netlist>:3:14: element T1: Reynolds")
    re_at, t_at = (float(x) for x in re.search(r"number (\S+) at t = (\S+) s", found[0]).groups())
    # Re = 4·ṁ/(π·D·μ) of water at 20 °C from the solution's own flow at that time
    mdot = np.interp(t_at, sol.t, sol.flow("T1")) * 1e-6
    assert re_at == pytest.approx(4 * mdot / (np.pi * 1e-3 * 1.002e-3), rel=1e-3)
    assert re_at > 2000.0
    early = sol.t[np.argmax(sol["Re_T1"] > 2000.0)]
    assert t_at == pytest.approx(early, abs=1e-9)
    sol["Re_T1"]  # read again: no second warning for the same run


def test_a_laminar_tube_in_its_range_is_quiet():
    _, found = _run(WATER.replace("diameter=1mm", "diameter=0.3mm"))
    assert found == []


def test_a_check_valve_wired_backwards_warns_and_one_wired_right_does_not():
    text = "P1 pump 300kPa\nD1 {a} {b} 0.5 pcrack=10kPa\nVt tank 20mL\nR1 tank atm 5\n"
    _, found = _run(text.format(a="tank", b="pump"))
    assert len(found) == 1 and "<netlist>:2:1: element D1: the check valve never opened" in found[0]
    assert "reverse-biased by 198.7 kPa at t = 0 s" in found[0] and "swap its nodes" in found[0]
    sol, found = _run(text.format(a="pump", b="tank"))
    assert found == [] and sol["opening_D1"].max() > 0.99


def test_a_relief_valve_that_had_no_need_to_open_is_quiet():
    _, found = _run("P1 pump 150kPa\nD1 pump atm 0.5 pcrack=100kPa\nR1 pump x 1\nVx x 1mL\n")
    assert found == []


def test_the_cli_prints_the_warning_even_when_the_element_is_not_saved(tmp_path, capsys):
    net = tmp_path / "w.pn"
    net.write_text(WATER + ".tran 10ms 0.5s\n.save p(act)\n")
    assert main(["run", str(net), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert err.count("warning:") == 1 and "element T1: Reynolds number" in err
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q"]) == 0
    assert "warning" not in capsys.readouterr().err
