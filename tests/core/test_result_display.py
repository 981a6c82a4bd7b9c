"""Results as a user sees them: short reprs and plots a report can use."""
import re

from pneunet.analysis.oscillation import oscillator_period
from pneunet.paper_circuits import oscillator


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
