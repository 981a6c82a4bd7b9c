"""Families with few instances evaluate their laws on Python floats (``laws.Scalar``);
with many, on numpy arrays.  Both routes give the same flows and partials, across flow
reversal, a closed valve and a valve with its own backward parameters."""
import numpy as np
import pytest

from pneunet.physics import elements
from pneunet.physics.elements.base import FEW_INSTANCES, ElementSpec, FamilyContext
from pneunet.engine.options import SimulationOptions
from pneunet.physics.valve_params import ValveParams

BACKWARD = ValveParams(Rf=0.9, pclose=60.0, ptrans=150.0, e=1.8, ain=0.7, aout=0.4)


def _spec(kind, i):
    if kind == "valve":
        params = {"model": "axi", "backward": BACKWARD if i % 2 else False}
    else:
        params = {"R": 0.5 + 0.1 * i}
    return ElementSpec(kind, f"E{i}", ("a", "b", "c")[:3 if kind == "valve" else 2], params)


def _family(kind, specs):
    cls = elements.family(kind)
    for s in specs:
        cls.check_spec(s)
    return cls(specs, FamilyContext(SimulationOptions()))


@pytest.mark.parametrize("kind", ["valve", "resistor"])
def test_few_instances_equal_many(kind):
    rng = np.random.default_rng(3)
    n_ports = 3 if kind == "valve" else 2
    # pressures around flow reversal, zero flow and the valve's closing point
    p = rng.uniform(96.0, 500.0, size=(40, n_ports))
    p[::5, 1] = p[::5, 0]                       # zero flow
    p[1::5, :2] = p[1::5, 1::-1]                # reversed
    many = _family(kind, [_spec(kind, i % 4) for i in range(40)])
    assert many.n > FEW_INSTANCES
    q_many, dq_many, _ = many.outflows(0.0, p, None)
    for i in range(0, 40, 4):
        few = _family(kind, [_spec(kind, k) for k in range(4)])
        q, dq, _ = few.outflows(0.0, p[i:i + 4], None)
        np.testing.assert_allclose(q, q_many[i:i + 4], rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(dq, dq_many[i:i + 4], rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(few.flows(0.0, p[i:i + 4], None), q, rtol=1e-13, atol=1e-13)
    # some valves closed, some open: the test covers both branches of the law
    if kind == "valve":
        assert (q_many[:, 0] == 0).any() and (np.abs(q_many[:, 0]) > 1).any()
