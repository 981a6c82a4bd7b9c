"""Which fits compare an oscillating record from its second cycle start.

A start from the record sets the recorded nodes and what they imply; an effect's own
storage that the record does not show (a gas temperature, a tube's inner pressure) is
guessed, so its fit leaves one whole cycle to settle (``unset_storage``); a recorded
node given a volume (a dead volume at ``out``) is not a guess.
"""
import numpy as np
import pytest

from pneunet.common.errors import DataError
from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import fit_trace
from pneunet.truth.circuits.effects import DeadVolume, Tube, VolumeHeatTransfer
from pneunet.truth.circuits.fit import settling_time, unset_storage
from pneunet.truth.circuits.initial_state import StartState
from pneunet.truth.circuits.model import TraceModel

from .standalone import oscillator_record

VALUES = {"Rout": 1.132, "Rvent": 3.0}
RECORDED = {"p_tank_kPa": None, "p_out_kPa": None}


def _unset(*effects):
    model = TraceModel(NetlistBuilder("netlists/oscillator.pn"), effects=effects)
    return unset_storage(model, VALUES, RECORDED)


def test_guessed_storage_is_the_effects_own_unrecorded_storage():
    assert _unset() == []
    assert _unset(DeadVolume("out")) == []  # p_out is recorded
    heat = _unset(VolumeHeatTransfer())
    assert len(heat) == 1 and heat[0].endswith("__T")  # the gas temperature's node
    tube = _unset(Tube("X1", "ctrl"))
    assert len(tube) == 1 and tube[0] not in ("tank", "out")
    assert sorted(_unset(VolumeHeatTransfer(), Tube("X1", "ctrl"))) == sorted(heat + tube)


def test_settling_counts_whole_cycles_from_the_record_s_rising_crossings():
    t = np.arange(0.0, 10.0, 0.01)
    y = 200.0 + 50.0 * np.sin(2 * np.pi * (t - 0.3) / 2.0)  # rises through 200 at 0.3 + 2k
    record = StartState("record")
    assert settling_time(record, t, y) == settling_time(record, t, y, 1)
    assert [round(settling_time(record, t, y, k), 6) for k in (1, 2, 3)] == [0.3, 2.3, 4.3]
    short = t < 6.0  # three rises: a fifth cycle start is the last there is
    assert round(settling_time(record, t[short], y[short], 5), 6) == 4.3
    assert settling_time(StartState("rest"), t, y, 2) == 0.0


def test_an_oscillator_s_effect_fit_waits_a_cycle_a_driven_circuit_s_does_not():
    """The oscillator with heat exchange recorded mid-run is compared from its second
    cycle start; the inverter chain (driven: a cycle is its sources' 4 s period, almost
    half its fit window) with a control-line tube from its first."""
    from pneunet.design.circuits import oscillator
    from pneunet.truth.circuits import fit_trace
    from pneunet.truth.circuits.data import rising_crossings

    from .standalone import oscillator_record
    from .standalone_inverter import inverter_record

    rec = oscillator_record(12.0, noise=0.4, seed=1, heat_tau=0.5)
    rec = rec[rec["time_s"] >= 5.0 - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    fit = fit_trace(oscillator, rec, {"Rout": (1.132, 0.3, 5.0)}, node="tank",
                    effects=(VolumeHeatTransfer(),), max_nfev=2, start_state="record",
                    refined=False)
    starts = rising_crossings(rec["time_s"].to_numpy(), rec["p_tank_kPa"].to_numpy())
    assert fit.extras["compared_from_s"] == starts[1]

    rec = inverter_record(5.4, 12.0, dt=0.02, noise=0.3, seed=1)
    fit = fit_trace(NetlistBuilder("netlists/inverter.pn"), rec, {"Rpull": (20.0, 2.0, 200.0)},
                    node="out1", effects=(Tube("X2.Xv", "ctrl"),), max_nfev=2,
                    start_state="record", refined=False)
    t = rec["time_s"].to_numpy()
    starts = rising_crossings(t - t[0], rec["p_out1_kPa"].to_numpy())  # from the first sample
    assert fit.start_state.driven and fit.extras["compared_from_s"] == starts[0]


def test_a_fit_window_that_ends_before_its_states_settle_is_a_clear_error():
    """A mid-run record whose fit window ends before the tube's guessed inner pressure
    has settled (two cycle starts) compares no sample: a DataError naming the settling
    time, not scipy's "func input vector length" TypeError (a 400 mL oscillator at
    50 Hz, 17 s cycles, crashed its diagnosis so)."""
    rec = oscillator_record(30.0, dt=0.05, noise=0.3, seed=2, V=200.0, Rvent=3.5)
    rec = rec[rec["time_s"] >= 8.0 - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    second = settling_time(StartState(mode="record"), rec["time_s"].to_numpy(),
                           rec["p_tank_kPa"].to_numpy(), 2)
    tube = Tube("X1", "ctrl")
    build = NetlistBuilder("netlists/oscillator.pn")
    params = {"Rvent": (3.8, 0.5, 20.0), **tube.params}
    with pytest.raises(DataError, match=r"0 samples compared .* settle until"):
        fit_trace(build, rec, params, node="tank", effects=(tube,),
                  window=(0.0, second - 0.2), x_start={"Rvent": 3.5}, start_state="record")
