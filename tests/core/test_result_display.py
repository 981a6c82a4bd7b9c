"""Results as a user sees them: short reprs and plots a report can use."""
import re

from pneunet.engine.oscillation import oscillator_period
from pneunet.design.paper_circuits import oscillator


def assert_short(text, *words):
    assert len(text) < 400 and "\n" not in text, text
    assert "array(" not in text and not re.search(r"\d\.\d{6,}", text), text  # no dumps
    for word in words:
        assert word in text, (word, text)


def test_solution_operating_point_and_period_result_reprs_are_short_and_informative():
    circuit = oscillator()
    sol = circuit.tran(3.0)
    assert_short(repr(sol), "'oscillator R_out=1.132'", "0–3 s", f"points {sol.t.size}",
                 "sol.pressure(node)")
    assert_short(repr(circuit.op()), "tank 186.4 kPa", "UNSTABLE", "op.stability")
    result = oscillator_period(circuit, t_initial=20.0)
    assert_short(repr(result), "limit_cycle", f"period {result.period_s:.4g} s", ".solution")
    assert "<table>" in result._repr_html_() and "<table>" in sol._repr_html_()


def test_solution_plot_draws_coinciding_flows_once_with_the_legend_outside():
    fig = oscillator().tran(8.0).plot()
    flows = fig.axes[1]
    labels = [line.get_label() for line in flows.get_lines()]
    assert "PH = X1 = Rout" in labels  # one series-flow path: one line, not three on top
    assert sum("Rvent" in label for label in labels) == 1
    legend = flows.get_legend()
    assert legend.get_bbox_to_anchor().x0 > flows.get_window_extent().x1  # right of the data
    assert any("drawn once" in text.get_text() for text in flows.texts)


def test_circuit_deck_branches_and_measurements_reprs_are_short():
    from pathlib import Path

    from pneunet.physics.oscillator_branches import stationary_branches
    from pneunet.truth.valves.identify import load_measurements
    from pneunet.netlist import parse_file

    root = Path(__file__).parents[2]
    deck = parse_file(root / "netlists" / "oscillator.pn")
    assert_short(repr(deck), "elements 5", "analyses .tran", ".circuit")
    assert_short(repr(deck.circuit), "4 nodes, 5 elements", ".tran(t_stop)")
    assert_short(repr(stationary_branches()), "oscillation", "186.4 kPa (unstable)",
                 "predicted cycle p_c 183.5–319.8 kPa")
    assert_short(repr(load_measurements(root / "examples" / "data" / "bench_axi.csv")),
                 "points 4410", "excluded 0", ".frame")


def test_sweep_result_repr_counts_points_not_the_table():
    from pneunet.design.circuits import oscillator as build
    from pneunet.design.sweep import OscillationMeasure, grid, lin, run_sweep

    result = run_sweep(build, grid(lin("Rout", 0.0, 1.0, 2)), OscillationMeasure(t_stop=3.0),
                       workers=1, progress=False)
    assert_short(repr(result), "points 2 (2 computed, 0 reused)", "failed 0", ".table")
