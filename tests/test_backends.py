"""Both IDA bindings (scikit-sundae, scikits.odes) give the same oscillator.

The scikits.odes backend is optional (``.ci/install-odes.sh``); its tests skip
when it is not importable.
"""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.design.paper_circuits import oscillator
from pneunet.engine.simulate import transient
from pneunet.engine.solvers import available_backends

needs_odes = pytest.mark.skipif("odes" not in available_backends(),
                                reason="scikits.odes not installed (.ci/install-odes.sh)")


def period(t, p, t_from=3.0):
    """Mean interval between rising crossings of the mid level after ``t_from``."""
    late = t > t_from
    mid = 0.5 * (p[late].min() + p[late].max())
    i = np.flatnonzero((p[:-1] < mid) & (p[1:] >= mid) & late[:-1])
    crossings = t[i] + (mid - p[i]) / (p[i + 1] - p[i]) * (t[i + 1] - t[i])
    assert len(crossings) >= 2, "fewer than two cycles"
    return float(np.mean(np.diff(crossings)))


@pytest.fixture(scope="module")
def sundae_period():
    s = transient(oscillator(), 16.0, backend="sksundae")
    return period(s.t, s.pressure("tank"))


def test_sksundae_period_is_the_reference(sundae_period):
    """Against the paper's equations integrated by scipy (tests/reference_oscillator.py:
    5.9399 s; pneunet 5.9404 at its default tolerances, 5.9400 at rtol 1e-9)."""
    from reference_oscillator import limit_cycle  # tests/ is on pytest's sys.path

    assert sundae_period == pytest.approx(limit_cycle()[0], abs=1.5e-3)


@needs_odes
@pytest.mark.parametrize("t_step", [None, 0.01])
def test_odes_gives_the_same_period(sundae_period, t_step):
    s = transient(oscillator(), 16.0, backend="odes", t_step=t_step)
    assert s.stats["backend"] == "odes"
    assert len(s.jumps) >= 4  # folds detected through the odes root function
    assert period(s.t, s.pressure("tank")) == pytest.approx(sundae_period, rel=1e-3)


@needs_odes
def test_odes_with_dead_volumes_matches():
    # every node differential: no fold events, plain IDA stepping
    a = transient(oscillator(dead_volume=0.05), 16.0, backend="sksundae")
    b = transient(oscillator(dead_volume=0.05), 16.0, backend="odes")
    assert period(b.t, b.pressure("tank")) == pytest.approx(period(a.t, a.pressure("tank")),
                                                            rel=1e-3)


@needs_odes
def test_odes_stops_exactly_on_breakpoints():
    from pneunet.physics.waveforms import Pulse

    c = Circuit("pulse")
    c.pressure_source("P", "src", Pulse(101.325, 300.0, delay=0.3, rise=0.1, width=0.7))
    c.resistor("R", "src", "tank", R=1.0)
    c.volume("V", "tank", V="50mL")
    s = transient(c, 2.0, backend="odes")
    for corner in (0.3, 0.4, 1.1):
        assert np.min(np.abs(s.t - corner)) < 1e-12, corner  # not 1e-7 (float32 tstop)
    ref = transient(c, 2.0, backend="sksundae")
    assert s.pressure("tank")[-1] == pytest.approx(ref.pressure("tank")[-1], rel=1e-4)


def test_unknown_backend_is_a_clear_error():
    from pneunet.common.errors import SolverError

    with pytest.raises(SolverError, match="not installed"):
        transient(oscillator(), 1.0, backend="nonexistent")
