"""Recordings of a circuit with a McKibben muscle that start mid-run (issue 40): the
muscle's own states (contraction, velocity) at the first sample are where its force
balances its load at the recorded pressure, or where the encoder puts them; cycle starts
of a noisy record are one per cycle.  The reference muscle and the recordings come from
tests/traces/standalone_muscle.py (no pneunet code)."""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from pneunet import Circuit
from pneunet.truth.circuits.initial_state import element_states

from .standalone_muscle import MUSCLE, fig12_record, muscle_force

ROOT = Path(__file__).resolve().parents[2]
FIG12 = ROOT / "netlists" / "fig12_mckibben.pn"
AMBIENT = 96.0
PARAMS = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "Vtank.V": (250, 50, 600)}
TRUTH = {"Rout": 1.132, "Rvent": 3.0, "Vtank.V": 200.0}


def _tank_and_muscle(p_tank):
    c = Circuit("rig", ambient=AMBIENT)
    c.volume("Vtank", "tank", 200.0, p0=p_tank)
    c.resistor("Rvent", "tank", "atm", R=3.0)
    c.add("mckibben", "M1", ("tank",), L0=MUSCLE["L0"], D0=MUSCLE["D0"],
          theta0=MUSCLE["theta0"], mass=MUSCLE["mass"], damping=MUSCLE["damping"])
    return c


@pytest.mark.parametrize("p_tank", [180.0, 250.0, 320.0])
def test_a_muscle_starts_where_its_pull_balances_its_load(p_tank):
    x_ref = brentq(lambda x: muscle_force(p_tank - AMBIENT, x) - MUSCLE["mass"] * 9.81,
                   0.0, 200.0)
    states = element_states(_tank_and_muscle(p_tank), 0.0)
    assert states["M1.x"] - AMBIENT == pytest.approx(x_ref, abs=1e-3)
    assert states["M1.v"] == pytest.approx(AMBIENT, abs=1e-9)  # at rest


def test_a_recorded_contraction_sets_the_muscle_and_its_velocity_stays_at_rest():
    states = element_states(_tank_and_muscle(250.0), 0.0, {"contraction_M1": 150.0})
    assert states["M1.x"] - AMBIENT == pytest.approx(150.0, abs=1e-6)
    assert states["M1.v"] == pytest.approx(AMBIENT, abs=1e-9)


def test_a_circuit_without_element_states_has_none():
    c = Circuit("tank", ambient=AMBIENT)
    c.volume("V1", "a", 10.0, p0=200.0)
    c.resistor("R1", "a", "atm", R=3.0)
    assert element_states(c, 0.0) == {}


def test_noise_on_the_falling_edge_of_a_midrun_record_adds_no_cycle_start():
    """The rig recorded from 15.4 s with 0.5 kPa of noise at 20 Hz: its tank pressure
    falls slowly through the mid level (1 kPa per sample), where noise made a second
    'cycle start' 4.4 s after the first and the fit compared the wrong cycles (45 kPa
    rms).  Now: one start per cycle, each within 0.03 s of the noise-free record's."""
    from pneunet.truth.circuits.align import Alignment

    clean = fig12_record(t_end=30.0, start=15.4, dt=0.05, noise=0.0, noise_mm=0.0)
    t, p = clean["time_s"].to_numpy(), clean["p_tank_kPa"].to_numpy()
    noisy = p + 0.5 * np.random.default_rng(11).standard_normal(p.size)
    exact = Alignment.of(t, p, "p_tank")
    found = Alignment.of(t, noisy, "p_tank")
    assert len(exact.starts) == 3 and np.all(np.diff(exact.starts) > 9.0)
    np.testing.assert_allclose(found.starts, exact.starts, atol=0.03)


@pytest.mark.study  # two stand-alone recordings and their fits: ~60 s
@pytest.mark.parametrize("start, dt, noise, noise_mm, damping", [
    (15.4, 0.05, 0.5, 0.1, 20.0),     # the case that failed: 45 kPa rms, period 6.8 s
    (6.4, 0.025, 0.3, 0.05, 3000.0),  # a slow muscle (τ ≈ 6 s): its start state matters
])
def test_a_midrun_rig_recording_fits_to_its_noise_and_covers_the_truth(
        tmp_path, start, dt, noise, noise_mm, damping):
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits.fit import fit_trace

    netlist = tmp_path / "rig.pn"
    netlist.write_text(FIG12.read_text().replace("damping=20N*s/m", f"damping={damping}N*s/m"))
    rec = fig12_record(t_end=30.0, start=start, dt=dt, noise=noise, noise_mm=noise_mm,
                       seed=11, muscle={"damping": damping})
    fit = fit_trace(NetlistBuilder(str(netlist)), rec, PARAMS)
    assert fit.start_state.mode == "record" and "contraction_M1" in fit.start_state.signals
    assert fit.rmse["p_tank"] == pytest.approx(noise, rel=0.15)
    assert fit.rmse["contraction_M1"] == pytest.approx(noise_mm, rel=0.15)
    for k, truth in TRUTH.items():
        lo, hi = fit.ci[k]
        assert hi / lo < 1.02
        if damping == 20.0:  # within 3 standard errors
            assert abs(math.log(fit.values[k] / truth)) < 3 * fit.stderr_log[k], (k, lo, hi)
        else:  # the slow muscle's contraction differs from the stand-alone one's by 0.02 mm
            # rms at the truth (0.4 of its noise, resolved by 1,200 samples): 3–4 se off,
            # within 0.5 % of the truth (from x = 0 the fit was at 163× its noise)
            assert fit.values[k] == pytest.approx(truth, rel=5e-3), (k, lo, hi)
    assert math.isfinite(fit.period_error) and abs(fit.period_error) < 0.05
