"""A small circuit is evaluated on Python floats (:mod:`pneunet.engine.float_plan`): its
residual, its Jacobian's data and the fold indicator's algebraic block must be those of
the vectorised path to the bit (the same operations on the same values, summed in the
same order), so that a transient does not depend on which path ran."""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.engine.assembly import CircuitDAE
from pneunet.physics.valve_params import PAPER_VALVES, ValveParams

BACKWARD = ValveParams(Rf=0.9, pclose=60.0, ptrans=150.0, e=1.8, ain=0.7, aout=0.4)


def _oscillator():
    c = Circuit("oscillator", ambient=96.0)
    c.pressure_source("PH", "supply", 496.0)
    c.valve("X1", "supply", "out", "tank", PAPER_VALVES["axi"])
    c.resistor("Rout", "out", "tank", 1.132)
    c.volume("V1", "tank", 200.0)
    c.resistor("Rvent", "tank", "atm", 3.0)
    return c


def _mixed():
    """Two valves (one with backward parameters), a pipe, resistors, a polytropic volume
    and an isothermal actuator: every float path, both flow directions, and nodes fed by
    three families (their sum's order matters to the last bit)."""
    c = Circuit("mixed", ambient=96.0)
    c.pressure_source("PH", "high", 289.0)
    c.pressure_source("PC", "c", 300.0)
    c.valve("Xin", "high", "act", "c", PAPER_VALVES["axi"], backward=BACKWARD)
    c.valve("Xout", "act", "mid", "muscle", PAPER_VALVES["axi"])
    c.pipe("P1", "mid", "atm", 500.0, 2.0)
    c.resistor("Rm", "mid", "atm", 2.0)
    c.resistor("Rt", "act", "muscle", 0.2)
    c.actuator("A1", "muscle", V=30.0, p0=120.0)
    c.volume("V2", "act", 5.0, n=1.3)
    return c


def _vectorised(circuit):
    """The same circuit's DAE evaluated by the vectorised path only."""
    dae = CircuitDAE(circuit)
    dae._floats = None
    return dae


@pytest.mark.parametrize("build", [_oscillator, _mixed])
def test_floats_equal_the_vectorised_path_to_the_bit(build):
    floats, arrays = CircuitDAE(build()), _vectorised(build())
    assert floats._floats is not None  # the float path is the one under test
    block_f, block_a = floats.algebraic_block(), arrays.algebraic_block()
    assert block_f._floats is not None and block_f.size >= 1
    block_a._floats = None
    rng = np.random.default_rng(7)
    for k in range(200):
        # around zero flow, flow reversal and closed valves; rates of both signs
        y = rng.uniform(96.0, 500.0, floats.n)
        if k % 4 == 0:
            y[:] = y[0]
        yp = rng.normal(0.0, 50.0, floats.n)
        t, cj = float(k), rng.uniform(0.0, 1e3)
        for a, b in zip(floats.evaluate(t, y, yp, cj), arrays.evaluate(t, y, yp, cj)):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(floats.evaluate(t, y, yp)[0],
                                      arrays.evaluate(t, y, yp)[0])
        for residual in (True, False):
            for a, b in zip(block_f.evaluate(t, y, residual), block_a.evaluate(t, y, residual)):
                np.testing.assert_array_equal(a, b)


def test_a_family_without_a_float_path_keeps_the_circuit_vectorised():
    c = _oscillator()
    c.check_valve("CV", "tank", "atm", 5.0)
    assert CircuitDAE(c)._floats is None
