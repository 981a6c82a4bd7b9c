"""Recordings logged on a grid (whole kPa, an ADC's steps): the noise floor includes the
rounding, so a quiet record of a right model is not called unexplained.

Rounding to a step q adds an error uniform on ±q/2 (standard deviation q/√12) that
second differences do not see where the signal is flat: every sample rounds the same
way.  A driven circuit's plateaus are flat for seconds.
"""
import math

import numpy as np
import pytest

from pneunet.truth.core.noise import record_sigma, resolution, rounding_sigma


@pytest.mark.parametrize("step, offset", [(1.0, 0.0), (0.1, 0.0), (0.17, 0.05), (2.5, 96.0)])
def test_the_step_of_a_rounded_signal_is_found(step, offset):
    y = 120 + 50 * np.sin(np.linspace(0, 10, 3000))
    logged = np.round((y - offset) / step) * step + offset
    assert resolution(logged) == pytest.approx(step, rel=1e-9)
    assert rounding_sigma(logged) == pytest.approx(step / math.sqrt(12), rel=1e-9)


def test_values_on_no_grid_have_no_step():
    rng = np.random.default_rng(0)
    y = 120 + 50 * np.sin(np.linspace(0, 10, 3000)) + 0.3 * rng.standard_normal(3000)
    assert resolution(y) == 0.0
    assert resolution([120.0, 120.0, 120.0]) == 0.0  # a constant: no grid to see
    assert resolution([1.0, np.nan, 2.0, 3.3, 4.0]) == 0.0  # gaps 1, 1.3, 0.7: no grid
    # 0.1·3 and 0.3 differ in their last bits: one value, the grid is 0.1
    assert resolution([0.1 * 3, 0.3, 0.4, 0.2, 0.7]) == pytest.approx(0.1)


def test_a_flat_rounded_record_has_at_least_its_rounding_as_noise():
    y = np.round(np.concatenate([np.full(500, 120.3), np.linspace(120.3, 180.6, 200),
                                 np.full(500, 180.6)]))
    assert record_sigma(y) == pytest.approx(1 / math.sqrt(12))


@pytest.fixture(scope="module")
def quiet_driven_record_in_whole_kpa():
    from tests.traces.standalone_driven import amplifier_record

    rec = amplifier_record(7.3, 30.0, dt=0.01, noise=0.1, seed=4, R_line=0.24, V=30.0)
    for c in rec.columns:
        if c != "time_s":
            rec[c] = np.round(rec[c])
    return rec


def test_a_right_model_of_a_record_in_whole_kpa_is_adequate(quiet_driven_record_in_whole_kpa):
    """The flow amplifier logged in whole kPa with 0.1 kPa of sensor noise (stand-alone
    recording): its floor is the rounding, 1/√12 kPa (it was 5e-12 kPa and the verdict
    unexplained), and the line's values are covered."""
    from pathlib import Path

    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import diagnose_trace

    netlist = Path(__file__).resolve().parents[2] / "netlists" / "amplifier.pn"
    d = diagnose_trace(NetlistBuilder(str(netlist)), quiet_driven_record_in_whole_kpa,
                       {"Rtube.R": (0.2, 0.02, 2.0), "Amck.V": (25.0, 5.0, 200.0)},
                       node="muscle")
    assert d.verdict == "adequate"
    assert d.noise_floor == pytest.approx(1 / math.sqrt(12), rel=0.05)
    assert d.noise["resolution"] == {"p_act": pytest.approx(1.0), "p_muscle": pytest.approx(1.0)}
    assert "steps of 1 kPa" in d.noise["method"]
    lo, hi = d.final.ci["Rtube.R"]
    assert lo <= 0.24 <= hi
    lo, hi = d.final.ci["Amck.V"]
    assert lo <= 30.0 <= hi
