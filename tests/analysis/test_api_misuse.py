"""Misused analysis functions say what they expected (issue 16), not a TypeError."""
from pathlib import Path

import pytest

from pneunet.design.logic import truth_table
from pneunet.netlist.builder import NetlistBuilder
from pneunet.design.sweep import run_sweep
from pneunet.common.errors import PneunetError
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


def test_oscillation_calls_given_the_wrong_object_say_which_call_fits():
    from pneunet.engine.oscillation import analyze_oscillation, oscillator_period
    from pneunet.design.paper_circuits import oscillator

    sol = oscillator().tran("2s", t_step="50ms")  # times may carry units
    assert sol.t[-1] == 2.0 and sol.t[1] == pytest.approx(0.05)
    with pytest.raises(PneunetError, match="takes a Circuit to simulate, got Solution") as e:
        oscillator_period(sol)
    assert "analyze_oscillation(sol.t" in e.value.hint
    with pytest.raises(PneunetError, match="takes a time array and a signal array"):
        analyze_oscillation(sol)


@pytest.mark.parametrize("points", [{"Rout": 1.0}, "Rout=1"], ids=["dict", "str"])
def test_run_sweep_wants_a_list_of_points(points):
    from pneunet.design.circuits import oscillator as build

    with pytest.raises(PneunetError, match="takes a list of points") as e:
        run_sweep(build, points, workers=1, progress=False)
    assert "grid(lin(" in e.value.hint


def test_run_sweep_given_an_axis_says_to_wrap_it_in_a_grid():
    from pneunet.design.circuits import oscillator as build
    from pneunet.design.sweep import lin

    with pytest.raises(PneunetError, match="got Axis"):
        run_sweep(build, lin("Rout", 0.0, 1.0, 2), workers=1, progress=False)


def test_a_time_that_is_no_time_is_a_parameter_error():
    from pneunet.common.errors import ParameterError
    from pneunet.design.paper_circuits import oscillator

    with pytest.raises(ParameterError, match="t_stop"):
        oscillator().tran("30kPa")


def test_data_calls_given_a_solution_or_a_circuit():
    from pneunet.design.circuits import oscillator as build
    from pneunet.truth.valves.diagnose import diagnose
    from pneunet.common.errors import DataError
    from pneunet.truth.circuits import diagnose_trace, fit_trace, read_trace

    sol = build().tran(3.0, t_step=0.05)
    recording = read_trace(sol)  # a simulation stands in for a recording
    assert recording.columns[0] == "time_s" and "p_tank_kPa" in recording
    with pytest.raises(DataError, match="diagnose takes bench data.*got Solution"):
        diagnose(sol)
    for call in (fit_trace, diagnose_trace):
        with pytest.raises(PneunetError, match="takes a function from a point"):
            call(build(), sol, {"Rvent": (3.0, 1.0, 10.0)})


def test_solution_plot_takes_bare_names_and_names_a_misspelt_one():
    from pneunet.design.paper_circuits import oscillator

    sol = oscillator().tran(1.0)
    fig = sol.plot(signals=["tank", "Rvent"])
    assert [line.get_label() for ax in fig.axes for line in ax.get_lines()] == ["tank", "Rvent"]
    with pytest.raises(PneunetError, match="no signal 'tnak'") as e:
        sol.plot(signals=["tnak"])
    assert "p_tank" in e.value.hint
