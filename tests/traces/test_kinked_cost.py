"""An oscillator's fit on a cost that is kinked at a difference step's scale (its cycles
aligned, its valve's jumps timed by folds): the intervals come from secants where the
differences on the two sides disagree, not from a check that calls every direction
noise.

The recording comes from tests/traces/standalone.py (scipy's Radau, not pneunet): a
150 mL oscillator with R_vent 4.2 and a hidden 4 mL dead volume at ``out``, the logger
started 17.7 s after switch-on, 25 Hz, 0.35 kPa.  Fitted with ``dead_volume@out`` from
its truth, the two Jacobians disagreed along the weakest direction more than J moved
(116 against 71) and every interval was unbounded, "move together without changing the
fit"; a secant along it moves 73."""
import numpy as np

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import fit_trace
from pneunet.truth.circuits.effects import candidates_for

from .standalone import oscillator_record

TRUTH = {"Rout": 1.132, "Rvent": 4.2, "Vtank.V": 150.0, "V_dead@out": 4.0}


def test_an_oscillator_fitted_from_its_truth_has_intervals_that_cover_it():
    start = 17.7
    rec = oscillator_record(start + 40.0, dt=0.04, noise=0.35, seed=21, V=150.0, Rvent=4.2,
                            V_out=4.0)
    rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    build = NetlistBuilder("netlists/oscillator.pn")
    (dead,) = [e for e in candidates_for(build({})) if e.name == "dead_volume@out"]
    params = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0),
              "Vtank.V": (250.0, 50.0, 600.0), **dead.params}
    fit = fit_trace(build, rec, params, node="tank", effects=(dead,), x_start=TRUTH,
                    max_nfev=60)
    assert fit.error() < 1.05 * 0.35
    assert "undetermined" not in fit.extras["intervals"], fit.extras["intervals"]["note"]
    assert "measured by secants" in fit.extras["intervals"]["secant_note"]
    for name, true in TRUTH.items():
        lo, hi = fit.ci[name]
        assert lo < true < hi and np.log(hi / lo) < 0.05, (name, fit.ci[name])
