"""Misused analysis functions say what they expected (issue 16), not a TypeError."""
from pathlib import Path

import pytest

from pneunet.analysis.logic import truth_table
from pneunet.analysis.sweep import NetlistBuilder, run_sweep
from pneunet.errors import PneunetError
from pneunet.netlist import parse_file

INVERTER = Path(__file__).parents[2] / "netlists" / "inverter.pn"


@pytest.mark.parametrize("call", [
    lambda c: truth_table(c, {"A": "Pin"}, ["out2"]),
    lambda c: run_sweep(c, [{"Rpull": 10.0}], workers=1, progress=False),
], ids=["truth_table", "run_sweep"])
def test_a_circuit_instead_of_a_builder_is_explained(call):
    with pytest.raises(PneunetError, match="takes a function from a point .* got a Circuit") as e:
        call(parse_file(INVERTER).circuit)
    assert "NetlistBuilder" in e.value.hint


@pytest.mark.parametrize("inputs, outputs, words", [
    (["Pin"], ["out2"], "inputs must be a dict"),
    ({"A": "Pin"}, "out2", "outputs must be a list of node names"),
    ({"A": "Pin"}, ["nowhere"], "not nodes of the circuit"),
])
def test_truth_table_arguments_are_checked(inputs, outputs, words):
    with pytest.raises(PneunetError, match=words):
        truth_table(NetlistBuilder(INVERTER), inputs, outputs)


def test_truth_table_repr_names_inputs_outputs_and_margin():
    tt = truth_table(NetlistBuilder(INVERTER), {"A": "Pin"}, ["out1"], t_settle=2.0,
                     expected=lambda bits: (1 - bits[0],))
    text = repr(tt)
    assert text.startswith("<TruthTable: inputs A, outputs out1, rows 2")
    assert "as expected 2 of 2" in text and "smallest margin" in text
