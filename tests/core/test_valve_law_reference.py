"""The valve law (eqs. 19 and 25) against an independent reference, in every flow
direction and for both of the paper's valve models (issue 39).

The reference (tests/reference_valve.py) is the paper's equations written in plain
Python; a few values are worked out by hand below.  Covered: pneunet.physics.laws (exact root
and, on the scalar path, with the circuit's flow band) and the valve element family
(vectorised and per-instance routes), forward flow (p_in > p_out), backward flow
(p_out > p_in: a_in on the out port, eq. 25) and the mirror valve, whose backward
parameters (Table 1) apply when p_out > p_in.
"""
import itertools

import numpy as np
import pytest

from pneunet import Circuit
from pneunet.engine.assembly import CircuitDAE
from pneunet.physics.laws import Scalar, valve_flow, valve_flow_and_partials
from pneunet.physics.valve_params import PAPER_VALVES
import reference_valve as ref  # tests/ is on pytest's sys.path

MODELS = ("axi", "mirror", "mirror_backward")
#: (p1, p2, p_ctrl) kPa: forward, backward (same pairs swapped), partly open, closed
#: (the last: axi closed, Δp 82 kPa; with a_in on p_in the reverse flow would open)
FORWARD = [(400.0, 200.0, 96.0), (596.1, 349.1, 96.0), (500.0, 300.0, 250.0),
           (300.0, 150.0, 180.0), (450.0, 430.0, 200.0), (400.0, 200.0, 300.0),
           (250.0, 120.0, 96.0), (596.0, 96.0, 350.0), (400.0, 200.0, 500.0),
           (450.0, 250.0, 96.0), (550.0, 500.0, 200.0), (500.0, 200.0, 220.0)]
POINTS = FORWARD + [(b, a, c) for a, b, c in FORWARD]


def test_hand_worked_values_of_the_axi_valve():
    """Eq. 25 then eq. 19 by hand, axi valve, 400 ↔ 200 kPa, control 96 kPa:
    Δp = 0.32·400 + 0.71·200 − 96 = 174 kPa in both directions (a_in on the 400 kPa
    port), u = (174 − 96.42)/(155.1 − 96.42) = 1.32209, ṁ = √(400² − 200²)/(0.566·
    √(1 + u^−3.98)) = 530.87 mg/s.  With a_in on p_in regardless (the wrong reverse rule)
    Δp would be 252 kPa and the reverse flow −606 mg/s."""
    axi = PAPER_VALVES["axi"].as_dict()
    assert ref.flow(400.0, 200.0, 96.0, **axi) == pytest.approx(530.87, abs=0.01)
    assert valve_flow(400.0, 200.0, 96.0, **axi) == pytest.approx(530.87, abs=0.01)
    assert valve_flow(200.0, 400.0, 96.0, **axi) == pytest.approx(-530.87, abs=0.01)
    # closed: Δp = 0.32·400 + 0.71·200 − 300 = −30 kPa ≤ p_close
    assert valve_flow(200.0, 400.0, 300.0, **axi) == 0.0


@pytest.mark.parametrize("model", MODELS)
def test_law_equals_the_papers_equations_in_both_directions(model):
    params = PAPER_VALVES[model].as_dict()
    p = np.array(POINTS)
    expected = np.array([ref.flow(*x, **params) for x in POINTS])
    assert (expected > 0).sum() >= 6 and (expected < 0).sum() >= 6 and (expected == 0).any()
    # exact law, vectorised
    np.testing.assert_allclose(valve_flow(p[:, 0], p[:, 1], p[:, 2], **params), expected,
                               rtol=1e-12, atol=1e-12)
    # circuit form: regularised root (band 10 kPa²; |p1² − p2²| ≥ 17,600 here), on floats
    for x, want in zip(POINTS, expected):
        got, _ = valve_flow_and_partials(*x, *params.values(), band=10.0, partials=True,
                                         xp=Scalar)
        assert got == pytest.approx(want, rel=1e-6, abs=1e-9), x


def _mirror_element_circuit(n):
    c = Circuit("mirror valves", ambient=96.0)
    c.pressure_source("P1", "a", 300.0)
    for i in range(n):
        c.valve(f"X{i}", "a", f"b{i}", "a", model="mirror", backward="mirror_backward")
        c.resistor(f"R{i}", f"b{i}", "atm", R=1.0)
    return c


@pytest.mark.parametrize("n", [1, 20], ids=["per-instance", "vectorised"])
def test_mirror_element_uses_backward_parameters_when_p_out_is_higher(n):
    """The element family with Table 1's forward and backward mirror parameters: each
    valve's flow at (p_in, p_out, p_ctrl) is the reference law with the forward set when
    p_in ≥ p_out and the backward set (a_in still on the higher port) otherwise."""
    dae = CircuitDAE(_mirror_element_circuit(n))
    (block,) = [b for b in dae._blocks if b.family.kind == "valve"]
    fwd, bwd = PAPER_VALVES["mirror"].as_dict(), PAPER_VALVES["mirror_backward"].as_dict()
    rows = list(itertools.islice(itertools.cycle(POINTS), max(n, len(POINTS))))
    for start in range(0, len(rows), n):
        p = np.array((rows[start:start + n] * n)[:n])
        got = block.family.flows(0.0, p, np.zeros_like(p))[:, 0]
        want = [ref.flow(*x, **(fwd if x[0] >= x[1] else bwd)) for x in p]
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)
