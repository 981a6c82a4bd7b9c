import numpy as np

from pneunet.engine.oscillation import analyze_oscillation, classify


def test_sustained_square_like_wave():
    t = np.linspace(0, 20, 4001)
    y = 250 + 60 * np.sign(np.sin(2 * np.pi * t / 2.5)) + 0.0 * t
    o = analyze_oscillation(t, y)
    assert o.kind == "limit_cycle"
    assert abs(o.period_s - 2.5) < 1e-2
    assert abs(o.duty_cycle - 0.5) < 0.02
    assert o.p_min == 190 and o.p_max == 310


def test_decaying_and_equilibrium():
    t = np.linspace(0, 40, 8001)
    o = analyze_oscillation(t, 200 + 50 * np.exp(-t / 15) * np.sin(2 * np.pi * t / 2))
    assert o.kind == "decaying" and not o.oscillating
    assert classify(t, 150 + 0 * t) == "equilibrium"


def test_oscillator_period_matches_the_verified_cycle(paper_cycle):
    """Period and extremes against the paper's equations integrated by scipy
    (tests/reference_oscillator.py: 5.9399 s, 183.46–319.78 kPa)."""
    from reference_oscillator import limit_cycle  # tests/ is on pytest's sys.path

    period, p_min, p_max = limit_cycle()
    o = paper_cycle.oscillation
    assert o.kind == "limit_cycle" and o.converged
    assert abs(o.period_s - period) < 2e-3
    assert abs(o.p_min - p_min) < 0.05 and abs(o.p_max - p_max) < 0.05
    # it stopped as soon as the cycle converged instead of running a fixed long time
    assert paper_cycle.t_simulated <= 45
    assert 0 < o.rise_fraction < o.duty_cycle < 1


def test_oscillator_period_reports_an_equilibrium():
    from pneunet.design.circuits import oscillator
    from pneunet.engine.oscillation import oscillator_period

    res = oscillator_period(oscillator({"Rout": 0}), "tank")
    assert res.oscillation.kind == "equilibrium"
    assert abs(res.oscillation.final - 167.484) < 0.01


def test_crossings_with_a_band_count_one_rise_per_cycle_on_a_noisy_record():
    """Noise riding on a slope near the level: without hysteresis it adds rises on the
    falling edges; with a band of 4 σ only the true cycle starts remain, each within a
    sample of the noise-free crossing (t = 10 k s for this sine)."""
    from pneunet.engine.oscillation import rising_crossings

    t = np.linspace(0.0, 41.0, 4101)
    noise = 0.05 * np.random.default_rng(7).standard_normal(t.size)
    y = np.sin(2 * np.pi * t / 10.0) + noise
    assert len(rising_crossings(t, y, 0.0)) > 4  # the falling edges' noise counts too
    rises = rising_crossings(t, y, 0.0, band=0.2)
    np.testing.assert_allclose(rises, [10.0, 20.0, 30.0, 40.0], atol=0.05)
    # a falling ramp with noise around the level: no rise at all
    ramp = 1.0 - 0.05 * t + noise
    assert len(rising_crossings(t, ramp, 0.0, band=0.2)) == 0
