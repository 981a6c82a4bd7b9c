"""The one-parameter sweep figure: a panel per quantity with units, nothing dropped."""
import numpy as np
import pandas as pd

from pneunet.design.sweep import lin
from pneunet.design.sweep_plot import plot_sweep


def test_swept_values_are_rounded():
    assert lin("Rout", 0.2, 3.0, 15).values[8] == 1.8  # linspace gives 1.7999999999999998


def test_failed_and_non_oscillating_points_are_marked_on_every_panel():
    nan = float("nan")
    table = pd.DataFrame({
        "Rout": [0.0, 1.0, 2.0, 3.0], "period_s": [nan, 5.8, 8.2, nan],
        "p_min": [167.0, 181.0, 193.0, nan], "p_max": [167.0, 311.0, 348.0, nan],
        "duty_cycle": [nan, 0.39, 0.52, nan], "oscillating": [False, True, True, False],
        "error": [None, None, None, "SolverError: IDA stopped"]})
    fig = plot_sweep(table, "Rout")
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["period (s)", "pressure extremes (kPa abs)",
                      "duty cycle (fraction of a period)"]
    assert fig.axes[-1].get_xlabel() == "R_out (kPa·s/mg)"
    assert "1 failed" in fig._suptitle.get_text() and "1 without oscillation" in \
        fig._suptitle.get_text()
    for ax in fig.axes:
        marked = {line.get_label(): np.asarray(line.get_xdata()) for line in ax.get_lines()}
        assert list(marked["simulation failed"]) == [3.0]
        assert list(marked["no oscillation"]) == [0.0]
    assert fig.legends  # one legend, outside the panels


def test_a_meas_sweep_has_one_panel_per_unit_and_marks_missing_values():
    nan = float("nan")
    table = pd.DataFrame({"Rvent": [2.0, 5.0], "period": [4.6, nan], "freq": [0.22, nan],
                          "p_max": [320.0, 185.0], "p_min": [184.0, 184.0],
                          "error": [None, None]})
    fig = plot_sweep(table, "Rvent", units={"period": "s", "freq": "Hz", "p_max": "kPa",
                                            "p_min": "kPa"})
    assert [ax.get_ylabel() for ax in fig.axes] == ["period (s)", "freq (Hz)",
                                                    "p_max, p_min (kPa)"]
    marks = {line.get_label(): list(line.get_xdata()) for line in fig.axes[0].get_lines()}
    assert marks["not measured"] == [5.0]
