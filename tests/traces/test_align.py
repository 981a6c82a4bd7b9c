"""Cycle alignment of a simulated oscillation to a noisy recording: each recorded cycle
compared with the simulated cycle of the same number, shifted so the whole cycle matches
(issue 31: a crossing time read from four noisy samples was off by milliseconds, which
after the steep rise following the valve's opening stood in the residual of the whole
cycle as 0.5–0.9 kPa and pulled R_vent and V 2–6 standard errors off the truth).

The recording and the "simulation" are the same stand-alone oscillator curve
(tests/traces/standalone.py), so the right model times are the recorded times."""
import math

import numpy as np
import pytest

from pneunet.truth.circuits.align import Alignment, thinning

from .standalone import oscillator_record


def test_a_noisy_record_is_aligned_to_the_same_curve_within_a_fraction_of_a_ms():
    fine = oscillator_record(30.0, dt=0.01, noise=0.0, V=140.0, Rvent=3.7)
    t_fine, y_fine = fine["time_s"].to_numpy(), fine["p_tank_kPa"].to_numpy()
    times, clean = t_fine[::5], y_fine[::5]  # the logger at 20 Hz
    noisy = clean + 0.25 * np.random.default_rng(26).standard_normal(times.size)
    align = Alignment.of(times, noisy, "p_tank")
    assert len(align.starts) >= 4
    model = align.model_times(times, t_fine, y_fine)
    after = times >= align.starts[0]  # the cycles (before: compared at their own times)
    assert np.max(np.abs(model - times)[after]) < 8e-4, np.max(np.abs(model - times)[after])
    np.testing.assert_array_equal(model[~after], times[~after])
    # the residual left is the noise: the sample-by-sample rms at the aligned times
    rms = np.sqrt(np.mean((np.interp(model, t_fine, y_fine) - noisy)[after] ** 2))
    assert rms < 0.27


@pytest.mark.parametrize("dt", [0.1, 0.05, 0.03, 0.02, 0.01])
def test_a_record_sampled_finer_than_a_difference_step_resolves_is_thinned(dt):
    """One sample in k, k the fewest spacings a 0.5 % change of the period moves the end of
    a cycle by: the period from the clean curve's own rising crossings."""
    clean = oscillator_record(40.0, dt=dt, noise=0.0, V=200.0, Rvent=3.5, V_out=3.0)
    t, y = clean["time_s"].to_numpy(), clean["p_tank_kPa"].to_numpy()
    level = 0.5 * (y[t > 20].min() + y[t > 20].max())
    up = np.flatnonzero((y[:-1] < level) & (y[1:] >= level))
    period = float(np.median(np.diff(t[up])))
    noisy = y + 0.3 * np.random.default_rng(4).standard_normal(t.size)
    assert thinning(t, noisy, 0.005) == math.ceil(0.005 * period / dt)
    assert thinning(t, 200.0 - 100.0 * np.exp(-t / 3.0), 0.005) == 1  # no oscillation


def test_a_plain_fit_of_a_finely_sampled_oscillation_can_be_thinned_too():
    """``fit_trace(thin=True)`` fits what a diagnosis would: one sample in k (here 50 Hz,
    8.8 s cycles: k = 3), says so, and its intervals cover the truth."""
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import fit_trace

    rec = oscillator_record(36.0, dt=0.02, noise=0.3, seed=5, V=240.0, Rvent=3.5)
    k = thinning(rec["time_s"].to_numpy(), rec["p_tank_kPa"].to_numpy(), 0.005)
    assert k == 3
    fit = fit_trace(NetlistBuilder("netlists/oscillator.pn"), rec,
                    {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0),
                     "Vtank.V": (250.0, 50.0, 600.0)}, node="tank", thin=True)
    assert fit.extras["fitted_every_nth_sample"] == k
    np.testing.assert_allclose(np.diff(fit.residuals["time_s"]), k * 0.02, rtol=1e-9)
    assert fit.report().startswith(f"fitted on one sample in {k}")
    assert "one sample in 3 (16.7 of 50 Hz)" in fit.extras["intervals"]["note"]
    for name, true in (("Rout", 1.132), ("Rvent", 3.5), ("Vtank.V", 240.0)):
        lo, hi = fit.ci[name]
        assert lo <= true <= hi, (name, fit.values[name], fit.ci[name])
