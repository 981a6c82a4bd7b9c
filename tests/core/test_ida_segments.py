"""A final segment run by scikit-sundae's ``solve`` has exactly the rows of the step loop.

The sksundae backend integrates a restarted segment that nothing continues from in one
``solve`` call (:meth:`pneunet.engine.solvers.sundae.SundaeIntegrator.segment`); the
generic loop calls ``step`` once per internal step.  Both drive the same IDA one-step
loop, so times and states must agree to the bit: ending at the stop, at a fold (root)
and at a failure.
"""
import numpy as np
import pytest

from pneunet.design.paper_circuits import oscillator
from pneunet.engine.simulate import transient
from pneunet.engine.solvers import sundae
from pneunet.engine.solvers.base import FAILED, TSTOP, Integrator


class _BlowUp:
    """ẏ = y² from y(0) = 1: y = 1/(1 − t), no solution at t = 1 (IDA fails before)."""

    n = 1
    algebraic_idx = np.empty(0, int)

    def evaluate(self, t, y, yp, cj=None):
        return yp - y * y, None if cj is None else np.array([cj - 2.0 * y[0]])

    def dense(self, data, out):
        out[0, 0] = data[0]


def _both(t_end):
    """The segment from y(0) = 1 to ``t_end``: (step loop, one solve call)."""
    out = []
    for final in (False, True):
        integrator = sundae.SundaeIntegrator(_BlowUp(), rtol=1e-6, atol=1e-6)
        with np.errstate(all="ignore"):
            out.append(integrator.segment(0.0, np.ones(1), np.ones(1), t_end, final=final))
    return out


def _same(a, b):
    assert (a.status, a.message) == (b.status, b.message)
    assert a.t.size > 10
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.yp, b.yp)


def test_a_segment_to_its_stop():
    loop, solved = _both(0.5)
    _same(loop, solved)
    assert solved.status == TSTOP and solved.t[-1] == 0.5 and solved.t[0] > 0.0
    assert solved.y[:, 0] == pytest.approx(1.0 / (1.0 - solved.t), rel=1e-4)


def test_a_failed_segment_keeps_the_steps_before_the_failure():
    loop, solved = _both(2.0)
    _same(loop, solved)
    assert solved.status == FAILED and 0.99 < solved.t[-1] < 1.0
    assert np.all(np.diff(solved.t) > 0)  # steps too small to move t are not rows


def _pulse_rc():
    """A tank filled through a resistor by a pressure pulse: IDA restarts at its step up
    (0.3 s) and continues across the corners of its ramp down (1.0, 1.1 s), so only the
    segment up to the step may be a ``solve`` call."""
    from pneunet import Circuit
    from pneunet.physics.waveforms import Pulse

    c = Circuit("pulse")
    c.pressure_source("P", "src", Pulse(101.325, 300.0, delay=0.3, width=0.7, fall=0.1))
    c.resistor("R", "src", "tank", R=1.0)
    c.volume("V", "tank", V="50mL")
    return c


@pytest.mark.parametrize("build, nodes, solves", [
    (oscillator, ("out", "tank"), lambda s: len(s.jumps) + 1),  # every segment restarts
    (_pulse_rc, ("tank",), lambda s: 1)])
def test_transients_are_unchanged(monkeypatch, build, nodes, solves):
    calls = []
    solve = sundae.ida.IDA.solve
    monkeypatch.setattr(sundae.ida.IDA, "solve",
                        lambda self, *a: calls.append(1) or solve(self, *a))
    fast = transient(build(), 7.0)
    assert len(calls) == solves(fast)
    monkeypatch.setattr(sundae.SundaeIntegrator, "segment", Integrator.segment)
    loop = transient(build(), 7.0)
    assert fast.jumps == loop.jumps
    np.testing.assert_array_equal(fast.t, loop.t)
    for node in nodes:
        np.testing.assert_array_equal(fast.pressure(node), loop.pressure(node))
