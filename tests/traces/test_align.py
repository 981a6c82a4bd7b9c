"""Cycle alignment of a simulated oscillation to a noisy recording: each recorded cycle
compared with the simulated cycle of the same number, shifted so the whole cycle matches
(issue 31: a crossing time read from four noisy samples was off by milliseconds, which
after the steep rise following the valve's opening stood in the residual of the whole
cycle as 0.5–0.9 kPa and pulled R_vent and V 2–6 standard errors off the truth).

The recording and the "simulation" are the same stand-alone oscillator curve
(tests/traces/standalone.py), so the right model times are the recorded times."""
import numpy as np

from pneunet.truth.circuits.align import Alignment

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
