"""Every signal ``pneunet run`` writes can be a recorded column (issue 40): a McKibben
muscle's contraction beside the tank pressure (the paper's Fig. 12 rig), read in other
units with a notice, refused with the circuit's own signal list when the circuit lacks
it, and fitted together with the pressures, each signal weighted by its own noise.

The recordings come from tests/traces/standalone_muscle.py (scipy's Radau on equations
written out by hand, no pneunet code)."""
import json
from pathlib import Path

import numpy as np
import pytest

from pneunet.interfaces.cli import main
from pneunet.common.errors import DataError
from pneunet.truth.circuits import read_trace
from pneunet.truth.circuits.fit import NOISE_UNIT, residual_scales

from .standalone_muscle import fig12_record

ROOT = Path(__file__).resolve().parents[2]
FIG12 = ROOT / "netlists" / "fig12_mckibben.pn"
FIT = ["--fit", "Rout=1.4:0.3:5", "--fit", "Rvent=3.8:0.5:20", "--fit", "Vtank.V=250:50:600"]
TRUTH = {"Rout": 1.132, "Rvent": 3.0, "Vtank.V": 200.0}


@pytest.fixture(scope="module")
def fig12():
    """25 s of the rig, the logger started 12.3 s after switch-on (mid-cycle)."""
    return fig12_record(t_end=25.0, start=12.3, dt=0.05, noise=0.3, noise_mm=0.05, seed=1)


@pytest.fixture(scope="module")
def short_rig():
    """The rig's first 3 s (for the checks that fail before any fit)."""
    return fig12_record(t_end=3.0, dt=0.05, noise=0.3, noise_mm=0.05, seed=1)


def run(capfd, *args):
    code = main([str(a) for a in args])
    out, err = capfd.readouterr()
    return code, out, err


def test_encoder_column_in_cm_and_force_in_kN_are_converted_with_a_notice(tmp_path):
    t = np.arange(8) * 0.1
    raw = {"time_s": t, "p_tank_kPa": 100 + t, "contraction_M1_cm": 1.5 + t,
           "force_M1_kN": 0.002 + 0 * t, "T_V1_degC": 20 + t, "opening_X1": 0.5 + 0 * t}
    path = tmp_path / "rig.csv"
    import pandas as pd

    pd.DataFrame(raw).to_csv(path, index=False)
    df = read_trace(path)
    assert list(df.columns) == ["time_s", "p_tank_kPa", "contraction_M1_mm", "force_M1_N",
                                "T_V1_K", "opening_X1"]
    np.testing.assert_allclose(df["contraction_M1_mm"], 10 * (1.5 + t))
    np.testing.assert_allclose(df["force_M1_N"], 2.0)
    np.testing.assert_allclose(df["T_V1_K"], 293.15 + t)
    assert "column contraction_M1_cm read as contraction_M1_mm (unit cm)" in df.attrs["notes"]


@pytest.mark.parametrize("column, words", [
    ("contraction_M1", ["contraction_M1", "needs its unit", "contraction_M1_mm"]),
    ("contraction_M1_kPa", ["contraction_M1_kPa", "not a length unit"]),
    ("force_M1_furlong", ["force_M1_furlong", "not a force unit"]),
])
def test_an_element_signal_in_a_wrong_or_missing_unit_is_a_located_error(column, words):
    import pandas as pd

    frame = pd.DataFrame({"time_s": np.arange(6.0), "p_tank_kPa": np.full(6, 100.0),
                          column: np.ones(6)})
    frame.attrs["source"] = "rig.csv"
    with pytest.raises(DataError) as err:
        read_trace(frame)
    text = str(err.value)
    assert "rig.csv" in text and all(w in text for w in words), text


@pytest.mark.parametrize("column, words", [
    ("contraction_M2_mm", ["contraction_M2_mm", "no element 'M2'", "contraction_M1_mm"]),
    ("contraction_Vtank_mm", ["element Vtank has no contraction signal", "force_M1_N"]),
])
def test_a_column_naming_a_signal_the_circuit_lacks_exits_2_listing_its_signals(
        tmp_path, capfd, short_rig, column, words):
    path = tmp_path / "rig.csv"
    short_rig.rename(columns={"contraction_M1_mm": column}).to_csv(path, index=False)
    code, out, err = run(capfd, "fit-trace", path, FIG12, *FIT, "--max-nfev", 2)
    assert code == 2 and "Traceback" not in err
    assert str(path) in err and all(w in err for w in words), err


def test_each_signal_is_weighted_by_its_own_noise():
    """A smooth swing of 200 mm and one of 200 kPa with white noise of 0.05 mm and 0.3 kPa:
    the divisors are those noise levels (robust second differences), not the ranges."""
    rng = np.random.default_rng(0)
    t = np.arange(2000) * 0.05
    meas = {"p_tank": 200 + 100 * np.sin(t) + 0.3 * rng.standard_normal(t.size),
            "contraction_M1": 100 + 100 * np.sin(t) + 0.05 * rng.standard_normal(t.size)}
    keep = {s: np.ones(t.size, bool) for s in meas}
    unit, scales = residual_scales(meas, keep)
    assert unit == NOISE_UNIT
    assert scales["p_tank"] == pytest.approx(0.3, rel=0.1)
    assert scales["contraction_M1"] == pytest.approx(0.05, rel=0.15)
    # pressures alone stay in kPa
    assert residual_scales({"p_tank": meas["p_tank"]}, keep) == ("kPa", {"p_tank": 1.0})


def test_per_signal_table_gives_each_floor_and_verdict_in_the_signals_own_unit():
    """The pooled floor is in noise units; the table multiplies back: a contraction whose
    scale is 0.05 mm and whose residual floor is 1.1 noise units has a 0.055 mm floor."""
    from pneunet.truth.circuits.diagnosis import signal_table

    class Fit:
        scales = {"p_tank": 0.3, "contraction_M1": 0.05}

        def __init__(self, held):
            self.held = held

        def signals(self):
            return list(self.scales)

        def errors_by_signal(self, window):
            return self.held

    base = Fit({"p_tank": 3.0, "contraction_M1": 0.5})
    final = Fit({"p_tank": 0.33, "contraction_M1": 0.2})
    table = signal_table(base, final, (10.0, 20.0),
                         {"per_signal": {"p_tank": 1.0, "contraction_M1": 1.1}})
    assert table["contraction_M1"]["noise_floor"] == pytest.approx(0.055)
    assert table["contraction_M1"]["unit"] == "mm" and table["p_tank"]["unit"] == "kPa"
    assert table["contraction_M1"]["ratio_to_floor"] == pytest.approx(0.2 / 0.055)
    assert table["contraction_M1"]["at_floor"] is False and table["p_tank"]["at_floor"] is True
    assert table["p_tank"]["base_held_out"] == 3.0


@pytest.mark.study  # the stand-alone rig and the fit: ~40 s
def test_a_clean_rig_recording_with_its_encoder_fits_every_column_to_its_noise(
        tmp_path, capfd, fig12):
    path = tmp_path / "rig.csv"
    fig12.to_csv(path, index=False)
    code, out, err = run(capfd, "fit-trace", path, FIG12, *FIT, "--json", "--quiet")
    assert code == 0, err
    fit = json.loads(out)["fit"]
    assert fit["unit"] == NOISE_UNIT
    # each signal's rms at its own noise: 0.3 kPa, 0.3 kPa, 0.05 mm
    assert fit["rmse"]["p_tank"] == pytest.approx(0.3, rel=0.15)
    assert fit["rmse"]["p_out"] == pytest.approx(0.3, rel=0.15)
    assert fit["rmse"]["contraction_M1"] == pytest.approx(0.05, rel=0.15)
    for k, truth in TRUTH.items():
        lo, hi = fit["ci"][k]
        assert lo <= truth <= hi, (k, fit["values"][k], lo, hi)
        assert hi / lo < 1.02  # and the intervals are not vacuous


@pytest.mark.study  # two diagnoses of a 40 s recording: ~2 min
def test_sleeve_friction_the_pressures_cannot_see_is_revealed_by_the_encoder():
    """0.5 N of Coulomb friction in the muscle's sleeve (the netlist's muscle has none,
    nor has the effect library): the pressures alone are at their floor (adequate);
    with the encoder the contraction is far above its floor where the motion reverses
    and the verdict is unexplained, the pressures still at theirs."""
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import diagnose_trace

    rec = fig12_record(t_end=40.0, start=12.3, dt=0.05, noise=0.3, noise_mm=0.05, seed=3,
                       friction=0.5)
    params = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "Vtank.V": (250, 50, 600)}
    effects = ["tube@M1.a"]  # the muscle's own candidate (one, to keep the study short)
    build = NetlistBuilder(str(FIG12))
    pressures = diagnose_trace(build, rec, params, signals=["p_tank_kPa", "p_out_kPa"],
                               effects=effects)
    assert pressures.verdict == "adequate", pressures.report()
    both = diagnose_trace(build, rec, params, effects=effects)
    assert both.verdict == "unexplained", both.report()
    table = both.signals
    assert table["contraction_M1"]["ratio_to_floor"] > 3.0, table
    assert table["contraction_M1"]["noise_floor"] == pytest.approx(0.05, rel=0.2)
    for s in ("p_tank", "p_out"):
        assert table[s]["ratio_to_floor"] < 1.5, table
    assert any(w.startswith("contraction_M1:") and " mm " in w for w in both.where), both.where
