"""Issue 32: inputs that used to give a wrong number without a word now give the true one
(source jumps on the output grid and in .meas, liquid volume flows, the gas constant, a
saved run equal to its solution)."""
import numpy as np
import pytest

from pneunet.physics.gas import AIR, GAS_CONSTANT
from pneunet.netlist import parse_netlist, runner

JUMP = "PWL(0 100kPa 1 300kPa 1 200kPa 2 200kPa)"   # 300 kPa just before t = 1, 200 after


def _run(text, name="<netlist>"):
    return runner.run_deck(parse_netlist(text, name))


@pytest.mark.parametrize("method", ["single", "multirate"])
@pytest.mark.parametrize("volume", [True, False])   # with unknowns, and sources only
def test_a_pwl_jump_keeps_both_sides_on_the_output_grid_and_in_meas(method, volume):
    text = (f".options method={method}\nP1 s {JUMP}\n"
            + ("R1 s t 1\nV1 t 10mL\nR2 t atm 5\n" if volume else "R1 s atm 1\n")
            + ".tran 10ms 2s\n.meas tran pb FIND p(s) AT=0.999s\n.meas tran pm MAX p(s)\n"
              ".meas tran qb FIND mdot(R1) AT=0.999s\n")
    if method == "multirate" and not volume:
        return  # nothing to integrate: no multirate run
    run = _run(text)
    sol = run.results[0][1]
    p = sol.pressure("s")
    at_jump = np.flatnonzero(sol.t == 1.0)
    assert at_jump.size == 2 and list(p[at_jump]) == pytest.approx([300.0, 200.0], abs=1e-9)
    assert run.measures["pm"] == pytest.approx(300.0, abs=1e-9)
    assert run.measures["pb"] == pytest.approx(100.0 + 200.0 * 0.999, abs=1e-6)   # 299.8
    # the resistor's flow just before the jump is driven by 300 kPa, not 200 kPa
    assert sol.flow("R1")[at_jump[0]] > 1.3 * sol.flow("R1")[at_jump[1]]


def test_a_pwl_file_jump_and_a_flow_source_jump_keep_both_sides(tmp_path):
    (tmp_path / "s.csv").write_text("time_s,p_kPa\n0,100\n1,300\n1,200\n2,200\n")
    net = tmp_path / "n.pn"
    net.write_text('P1 s PWL(FILE="s.csv")\nF1 atm t PWL(0 0 0.5 0 0.5 100 2 100)\n'
                   "R1 s t 1\nV1 t 10mL\n.tran 10ms 2s\n.meas tran pb FIND p(s) AT=0.999s\n"
                   ".meas tran fb FIND mdot(F1) AT=0.499s\n")
    run = _run(net.read_text(), str(net))
    sol = run.results[0][1]
    assert run.measures["pb"] == pytest.approx(299.8, abs=1e-6)
    assert run.measures["fb"] == pytest.approx(0.0, abs=1e-9)
    half = np.flatnonzero(sol.t == 0.5)
    assert list(sol.flow("F1")[half]) == [0.0, 100.0]


def test_a_volume_flow_in_a_liquid_circuit_is_the_liquids_own_volume():
    text = (".options fluid=water\nF1 atm act 1L/min\naccumulator A1 act 20mL 0.05mL/kPa\n"
            "laminar_tube T1 act atm length=1m diameter=4mm\n.tran 0.1s\n"
            ".meas tran q FIND mdot(F1) AT=0.05\n")
    assert _run(text).measures["q"] == pytest.approx(998.2 * 1000.0 / 60.0, rel=1e-12)
    gas = _run("F1 atm act 1L/min\nV1 act 10mL\nR1 act atm 1\n.tran 0.1s\n"
               ".meas tran q FIND mdot(F1) AT=0.05\n").measures["q"]
    assert gas == pytest.approx(1000.0 / 60.0 * 101.325 * 28.965 / (8.314462618 * 273.15),
                                rel=1e-12)


def test_standard_litres_are_refused_in_a_liquid_circuit():
    from pneunet.common.errors import NetlistError

    with pytest.raises(NetlistError) as info:
        parse_netlist(".options fluid=water\nF1 atm act 2slpm\naccumulator A1 act 20mL "
                      "0.05mL/kPa\nlaminar_tube T1 act atm length=1m diameter=4mm\n.tran 1s\n")
    assert "gas unit" in info.value.message and info.value.span.line == 2
    assert "L/min" in info.value.hint


def test_the_gas_constant_is_codata():
    assert GAS_CONSTANT == 8.314462618
    # 200 mL of air at 20 °C: M·V/(R·T) with the exact constant
    assert AIR.capacitance(200.0) == pytest.approx(28.965 * 200.0 / (8.314462618 * 293.15),
                                                   rel=1e-15)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_a_saved_run_equals_its_solution(tmp_path, suffix):
    from pneunet import read_run

    deck = parse_netlist(f"P1 s {JUMP}\nR1 s t 1\nV1 t 10mL\n.tran 50ms 2s\n")
    sol = deck.circuit.tran(2.0, t_step=0.05)
    sol.save(tmp_path / f"run{suffix}", deck.circuit)
    again = read_run(tmp_path / f"run{suffix}").solution
    assert again == sol and not (again != sol)
    other = deck.circuit.tran(2.0, t_step=0.1)
    assert sol != other
