"""A driven recording whose sources change once (netlists/amplifier_once.pn: the actuator
inflated at 5 s and deflated at 10 s), on the logger's own clock: the netlist time of its
first sample is found from the change the record shows (pneunet.truth.circuits.clock).

Before, sources without a period kept the file's clock: a logger started 3.3 s after
switch-on with its clock from 0 put the inflation 3.3 s early, and the fit ended with both
parameters at their bounds, 121 kPa rms against a 0.3 kPa noise, and no notice."""
import numpy as np
import pandas as pd
import pytest

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import fit_trace
from pneunet.truth.circuits.clock import source_changes
from tests.traces.standalone_driven import amplifier_record
from tests.traces.test_start_state import AMPLIFIER

ONCE = "netlists/amplifier_once.pn"
PARAMS = {"Rtube.R": (0.2, 0.02, 2.0), "Amck.V": (25.0, 5.0, 200.0)}
TRUTH = {"Rtube.R": 0.24, "Amck.V": 30.0}
DT = 0.02


def record(start, seconds=12.0, clock=0.0, seed=2):
    """``seconds`` of p_muscle at 50 Hz, 0.3 kPa noise, from ``start`` s on the sources'
    clock (before 0: the actuator at rest), the time column from ``clock``."""
    rec = amplifier_record(max(start, 0.0), seconds, dt=DT, noise=0.3, seed=seed, once=True,
                           signals=("muscle",), R_line=TRUTH["Rtube.R"], V=TRUTH["Amck.V"])
    if start < 0:
        n = int(round(-start / DT))
        rest = 120.0 + 0.3 * np.random.default_rng(seed + 1).standard_normal(n)
        rec = pd.concat([pd.DataFrame({"time_s": start + DT * np.arange(n),
                                       "p_muscle_kPa": rest}), rec], ignore_index=True)
    rec = rec.iloc[:int(round(seconds / DT))].copy()
    rec["time_s"] = clock + DT * np.arange(len(rec))
    return rec


def test_the_times_at_which_one_shot_sources_change():
    assert source_changes(NetlistBuilder(ONCE)({})) == pytest.approx((5.0, 10.01))
    assert source_changes(NetlistBuilder(AMPLIFIER)({})) is None  # periodic pulses
    assert source_changes(NetlistBuilder("netlists/oscillator.pn")({})) is None  # constant


@pytest.mark.parametrize("start, clock", [(-3.0, 0.0), (1.0, 0.0), (7.0, 0.0), (3.3, 1.7e9)])
def test_a_one_shot_record_on_the_loggers_clock_is_placed_by_its_change(start, clock):
    """Started before switch-on, before the inflation, during it (the actuator off its
    rest state), and with a Unix-time column: the first sample's netlist time within a
    tenth of a sample, the line's values covered, the fit at the noise."""
    fit = fit_trace(NetlistBuilder(ONCE), record(start, clock=clock), PARAMS, node="muscle")
    state = fit.start_state
    assert "estimated from the record" in state.clock and state.driven
    assert state.first_time == pytest.approx(start, abs=0.1 * DT)
    assert state.settle >= 0.0  # before switch-on: no history to run (was −3 s)
    lo, hi = state.clock_ci
    assert lo <= start <= hi
    for k, v in TRUTH.items():
        assert fit.ci[k][0] <= v <= fit.ci[k][1], (k, fit.ci[k])
    assert fit.error() < 0.33  # the noise is 0.3 kPa


def test_a_one_shot_record_on_the_sources_clock_keeps_its_time_stamps():
    fit = fit_trace(NetlistBuilder(ONCE), record(3.3, clock=3.3), PARAMS, node="muscle")
    assert fit.start_state.clock == "" and fit.start_state.first_time == pytest.approx(3.3)
    assert fit.error() < 0.33


def test_a_record_after_the_last_change_is_not_driven_and_fits_no_clock():
    """Started at 11 s, after the deflation's switch: the record holds the relaxation only.
    It is placed after the last change, where the sources no longer vary, and its clock is
    not fitted (nothing in the record fixes it)."""
    fit = fit_trace(NetlistBuilder(ONCE), record(11.0, seconds=8.0), PARAMS, node="muscle")
    state = fit.start_state
    assert "after the sources' last change" in state.clock
    assert not state.driven and state.first_time > 10.01 and state.clock_ci == ()
    assert fit.error() < 0.33
