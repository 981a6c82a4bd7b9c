import numpy as np
import pytest

from pneunet.design.circuits import oscillator
from pneunet.truth.circuits import fit_trace, read_trace, split_by_cycles, synthetic_trace
from pneunet.common.errors import DataError

TRUE = {"Rout": 1.132, "Rvent": 3.0, "V": 50.0}


@pytest.fixture(scope="module")
def trace():
    # V = 50 mL keeps the period at 1.49 s: 3 cycles in 5 s of record
    return synthetic_trace(oscillator, TRUE, 5.0, dt=0.025, noise=0.5, seed=1,
                           signals=("p_tank",))


@pytest.mark.slow
def test_recovers_rout_rvent_and_v_inside_their_intervals(trace):
    # all three from guesses 30-40 % off: the cycle gives the start (R_out from the
    # branch turning points, R_vent from the rise fraction, V from the period), then LM
    f = fit_trace(oscillator, trace, {"Rout": (1.5, 0.3, 5), "Rvent": (4.0, 0.5, 20),
                                      "V": (70, 5, 500)}, node="tank", max_nfev=45)
    assert f.extras["stage1"]["method"] == "branches"
    for k in ("Rout", "Rvent", "V"):
        lo, hi = f.ci[k]
        assert f.values[k] == pytest.approx(TRUE[k], rel=3e-3)
        assert lo < TRUE[k] < hi and hi - lo < 0.01 * TRUE[k]
    # the residual is the noise: 0.5 kPa
    assert f.rmse["p_tank"] == pytest.approx(0.5, rel=0.15)
    assert abs(f.period_error) < 2e-3
    assert f.nfev <= 45
    assert set(f.phase_rms.columns) == {"phase", "p_tank"} and len(f.phase_rms) == 20
    assert np.nanmax(f.phase_rms["p_tank"]) < 1.0


def test_cycle_start_needs_no_fit():
    # the branch turning points and quadrature give R_out and R_vent within a few per cent
    from pneunet.truth.circuits import FIT_OPTIONS, TraceModel
    from pneunet.truth.circuits.start import initial_values

    tr = synthetic_trace(oscillator, TRUE, 5.0, dt=0.05, noise=0.5, seed=2, signals=("p_tank",))
    t, y = tr["time_s"].to_numpy(), tr["p_tank_kPa"].to_numpy()
    names = ["Rout", "Rvent", "V"]
    x, info = initial_values(TraceModel(oscillator, options=FIT_OPTIONS), names,
                             np.log([1.5, 4.0, 70.0]), np.log([0.3, 0.5, 5]),
                             np.log([5, 20, 500]), t, y, "tank")
    got = dict(zip(names, np.exp(x)))
    assert info["roles"] == {"Rout": "Rout", "Rvent": "Rvent", "V": "V"}
    for k in names:
        assert got[k] == pytest.approx(TRUE[k], rel=0.05)
    assert len(info["history"]) <= 4


def test_trace_format_is_checked(tmp_path, trace):
    bad = tmp_path / "bad.csv"
    trace.rename(columns={"time_s": "t"}).to_csv(bad, index=False)
    with pytest.raises(DataError):
        read_trace(bad)
    good = tmp_path / "good.csv"
    good.write_text("# recorded\n" + trace.to_csv(index=False))
    assert list(read_trace(good).columns) == ["time_s", "p_tank_kPa"]
    train, test = split_by_cycles(good, "tank")
    assert train[0] == 0 and train[1] == test[0] < test[1] == pytest.approx(5.0)


def test_a_parameter_stopped_at_its_bound_is_said_so(trace):
    """R_vent's range made to exclude the truth (3.0): the fit stops at 2.5 and the
    report says that its interval means nothing there; with the truth inside, no note."""
    fixed = {"Rout": 1.132, "V": 50.0}
    f = fit_trace(oscillator, trace, {"Rvent": (2.0, 0.5, 2.5)}, fixed=fixed, node="tank",
                  max_nfev=12, features=False)
    assert f.values["Rvent"] == pytest.approx(2.5, rel=1e-6)
    (name, side, bound), = f.extras["intervals"]["at_bound"]
    assert (name, side) == ("Rvent", "upper") and bound == pytest.approx(2.5, rel=1e-12)
    assert "Rvent stopped at its upper bound 2.5" in f.report()
    assert "* caution: Rvent stopped at its upper bound 2.5" in f.corrected_netlist()
    free = fit_trace(oscillator, trace, {"Rvent": (2.0, 0.5, 20.0)}, fixed=fixed,
                     node="tank", max_nfev=12, features=False)
    assert free.values["Rvent"] == pytest.approx(3.0, rel=0.01)
    assert "at_bound" not in free.extras["intervals"]
    assert "bound" not in free.report() and "caution" not in free.corrected_netlist()
