"""Issue 6, criterion 4 (second half): an adiabatic tank hidden in the trace."""
import pytest

from pneunet.analysis.circuits import oscillator
from pneunet.analysis.fit_trace import rank_effects, synthetic_trace


@pytest.mark.slow
def test_hidden_adiabatic_volume_ranks_polytropic_first():
    # n = 1.4 shortens the period to 0.82 s: ~7 cycles in 6 s, sampled at 10 Hz
    true = {"Rout": 1.132, "Rvent": 3.0, "V": 50.0, "n": 1.4}
    trace = synthetic_trace(oscillator, true, 6.0, dt=0.1, noise=0.5, seed=3, signals=("p_tank",))
    table, fits = rank_effects(oscillator, trace, {"Rvent": (3.3, 0.5, 20), "V": (55, 5, 500)},
                               fixed={"Rout": true["Rout"]}, node="tank", max_nfev=20)
    assert table.effect.iloc[0] == "polytropic_volume"
    row = table.set_index("effect")
    assert row.loc["polytropic_volume", "improvement"] > 0.3
    print(table.drop(columns=["values"]).to_string())
    # the isothermal fit matches the period on the training cycles through a smaller V;
    # on the held-out cycles its period error is larger than the polytropic fit's
    base_err = row.loc["none", "abs_period_error"]
    poly_err = row.loc["polytropic_volume", "abs_period_error"]
    assert poly_err < base_err
    # the isothermal model absorbs the stiffer tank into a smaller V; n moves towards 1.4
    assert fits["none"].values["V"] < 0.7 * true["V"]
    assert fits["polytropic_volume"].values["n"] > 1.15
