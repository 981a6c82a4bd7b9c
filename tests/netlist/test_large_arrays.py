"""A 10,000-cell array netlist elaborates to the expected circuit (issue 18); ``pneunet check``
summarises a large circuit.  Speed is measured by benchmarks/bench_frontend.py, not here."""
from pathlib import Path

import pytest

from pneunet import Circuit
from pneunet.interfaces.cli import main
from pneunet.netlist import parse_file, parse_netlist, print_circuit
from pneunet.physics.waveforms import Pulse

CELLS = Path(__file__).resolve().parents[2] / "benchmarks" / "cells10k.pn"


def cells_text(n: int) -> str:
    text = CELLS.read_text().replace(".param N=10000", f".param N={n}")
    return text.replace("[0:9999]", f"[0:{n - 1}]").replace("act[9999]", f"act[{n - 1}]")


def built_in_python(n: int) -> Circuit:
    """The same N cells through the Python API, element by element."""
    c = Circuit("Independent valve cells (N of them, .param N) on one supply line (issue 18)")
    c.pressure_source("PS", "sup", 496)
    c.resistor("RS", "sup", "line", R=0.3 / n)
    c.volume("VL", "line", V=20 * n, p0=496)
    for k in range(n):
        x = f"Xcell[{k}]"
        c.pressure_source(f"{x}.PC", f"{x}.c", Pulse(101.325, 400, delay=0.2 + 4 * k / n,
                                                    rise=0.05, fall=0.05, width=2, period=4))
        c.resistor(f"{x}.RC", f"{x}.c", f"{x}.ctl", R=5)
        c.volume(f"{x}.VC", f"{x}.ctl", V=10)
        c.valve(f"{x}.XV", "line", f"act[{k}]", f"{x}.ctl", model="axi")
        c.volume(f"{x}.VA", f"act[{k}]", V=50)
        c.resistor(f"{x}.RV", f"act[{k}]", "atm", R=3)
    return c


def test_ten_thousand_cells_elaborate_to_the_expected_circuit():
    deck = parse_file(CELLS)
    circuit = deck.circuit
    circuit.validate()
    assert len(circuit.nodes) == 3 * 10_000 + 3 and len(circuit.elements) == 6 * 10_000 + 3
    kinds = {}
    for e in circuit.elements.values():
        kinds[e.kind] = kinds.get(e.kind, 0) + 1
    assert kinds == {"pressure_source": 10_001, "resistor": 20_001, "volume": 20_001,
                     "valve": 10_000}
    assert circuit.elements["RS"].params["R"] == pytest.approx(0.3 / 10_000)
    assert circuit.elements["VL"].params["V"] == pytest.approx(200_000)
    last = circuit.elements["Xcell[9999].PC"].params["value"]
    assert last.delay == pytest.approx(0.2 + 4 * 9999 / 10_000) and last.high == 400
    assert circuit.elements["Xcell[9999].XV"].nodes == ("line", "act[9999]", "Xcell[9999].ctl")
    assert circuit.elements["Xcell[5000].RV"].params["R"] == 3


def test_a_small_array_is_the_circuit_written_out_cell_by_cell():
    deck = parse_netlist(cells_text(12), str(CELLS))
    assert print_circuit(deck.circuit) == print_circuit(built_in_python(12))


def test_check_lists_at_most_twenty_names_unless_verbose(tmp_path, capsys):
    path = tmp_path / "cells.pn"
    path.write_text(cells_text(10))  # 33 nodes, 63 elements
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "33 nodes, 63 elements" in out and "  valve: 10" in out
    nodes = next(line for line in out.splitlines() if line.startswith("  nodes: "))
    assert len(nodes.split(" … ")[0].split()) == 1 + 20 and "… and 13 more" in nodes
    assert "… and 43 more" in out
    assert main(["check", "--verbose", str(path)]) == 0
    out = capsys.readouterr().out
    assert "more" not in out and "act[9]" in out and "Xcell[9].RV" in out


def test_check_warns_about_twenty_dangling_nodes_then_counts_the_rest(tmp_path, capsys):
    path = tmp_path / "cells.pn"  # every cell vents into a node of its own: 300 dangling nodes
    path.write_text(cells_text(300).replace("RV act atm", "RV act vent"))
    assert main(["check", str(path)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 21 and err[-1] == "warning: … and 280 more nodes with one connection"
    assert "node 'Xcell[0].vent' has one connection (Xcell[0].RV); did you mean" in err[0]
    assert "node 'Xcell[19].vent' has one connection (Xcell[19].RV)" in err[19]


def test_ic_in_an_arrayed_subcircuit_and_a_long_save_line():
    text = cells_text(50).replace("VC ctl 10mL\n", "VC ctl 10mL\n.ic ctl=150kPa\n")
    text += ".save " + " ".join(f"p(act[{k}])" for k in range(50)) + "\n"
    deck = parse_netlist(text, str(CELLS))
    assert deck.circuit.initial == {f"Xcell[{k}].ctl": 150.0 for k in range(50)}
    assert [s.target for s in deck.saves][-50:] == [f"act[{k}]" for k in range(50)]
