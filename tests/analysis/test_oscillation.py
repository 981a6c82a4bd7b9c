import numpy as np

from pneunet.analysis.oscillation import analyze_oscillation, classify


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
    from pneunet.analysis.circuits import oscillator
    from pneunet.analysis.oscillation import oscillator_period

    res = oscillator_period(oscillator({"Rout": 0}), "tank")
    assert res.oscillation.kind == "equilibrium"
    assert abs(res.oscillation.final - 167.484) < 0.01
