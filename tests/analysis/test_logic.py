from pathlib import Path

from pneunet.design.circuits import inverter, nor_gate
from pneunet.design.logic import truth_table
from pneunet.netlist.builder import NetlistBuilder

ROOT = Path(__file__).resolve().parents[2]


def test_python_nor_gate_truth_table():
    tt = truth_table(nor_gate, {"A": "PA", "B": "PB"}, ["y"], t_settle=3.0,
                     expected=lambda b: (int(not (b[0] or b[1])),))
    assert tt.ok() and len(tt.table) == 4
    m = tt.margins.iloc[0]
    assert m["margin_kPa"] > 300
    assert 0 < m["max_settle_s"] < 3.0


def test_inverter_netlist_truth_table():
    tt = truth_table(NetlistBuilder(ROOT / "netlists" / "inverter.pn"), {"in": "Pin"},
                     ["out1", "out2"], t_settle=3.0, expected=lambda b: (1 - b[0], b[0]))
    assert tt.ok()
    assert (tt.margins["margin_kPa"] > 300).all()
