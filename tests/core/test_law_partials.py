"""The laws' partial derivatives (the engine's Jacobian is built from them) against central
finite differences of the independent references (tests/reference_valve.py, the
regularised root d/(d² + ε²)^¼ written here), in every flow direction: forward,
backward (eq. 25's a_in on the out port) and through a closing valve (issue 39: the
reverse-flow partials had no test).
"""
import itertools

import numpy as np
import pytest

from pneunet.physics.laws import (Scalar, quadrature_flow, signed_root, valve_conductance,
                                  valve_flow_and_partials)
from pneunet.physics.valve_params import PAPER_VALVES
import reference_valve as ref  # tests/ is on pytest's sys.path

BAND = 10.0  # kPa², the circuits' default flow band


def root(d, band):
    return d / (d * d + band * band) ** 0.25 if band else np.sign(d) * np.sqrt(abs(d))


def valve(p_in, p_out, p_ctrl, params, band):
    """Eq. 19 with eq. 25 (tests/reference_valve.py) with the flow band's root."""
    dp = ref.delta_p(p_in, p_out, p_ctrl, params["ain"], params["aout"])
    if dp <= params["pclose"]:
        return 0.0
    u = (dp - params["pclose"]) / (params["ptrans"] - params["pclose"])
    return root(p_in ** 2 - p_out ** 2, band) / (
        params["Rf"] * np.sqrt(1.0 + u ** (-2.0 * params["e"])))


def central(f, x, h=1e-4):
    x = np.asarray(x, float)
    return np.array([(f(*(x + h * np.eye(len(x))[i])) - f(*(x - h * np.eye(len(x))[i])))
                     / (2 * h) for i in range(len(x))])


#: (p_in, p_out, p_ctrl) kPa, forward then the same pairs backward; open, partly open
POINTS = [(400.0, 200.0, 96.0), (300.0, 150.0, 96.0), (500.0, 300.0, 250.0),
          (450.0, 430.0, 200.0)]
POINTS += [(b, a, c) for a, b, c in POINTS]


@pytest.mark.parametrize("model, band, xp", [  # the scalar path needs a positive band
    (m, b, x) for m, b, x in itertools.product(("axi", "mirror_backward"), (BAND, 0.0),
                                               ("numpy", "scalar")) if b or x == "numpy"])
def test_valve_partials_are_the_laws_derivatives_in_both_directions(model, band, xp):
    params = PAPER_VALVES[model].as_dict()
    for x in POINTS:
        assert valve(*x, params, band) != 0.0, x  # every point open
        mdot, partials = valve_flow_and_partials(
            *x, *params.values(), band=band, xp=Scalar if xp == "scalar" else np)
        assert float(mdot) == pytest.approx(valve(*x, params, band), rel=1e-12), x
        want = central(lambda a, b, c: valve(a, b, c, params, band), x)
        np.testing.assert_allclose(np.array(partials, float), want, rtol=1e-6, atol=1e-9,
                                   err_msg=str(x))


def test_closed_valve_has_no_flow_and_no_partials():
    axi = PAPER_VALVES["axi"].as_dict()
    for x in [(200.0, 400.0, 300.0), (400.0, 200.0, 300.0)]:
        mdot, partials = valve_flow_and_partials(*x, *axi.values())
        assert mdot == 0.0 and np.all(np.array(partials) == 0.0)


@pytest.mark.parametrize("band", [BAND, 0.0])
def test_quadrature_flow_and_signed_root_against_their_formulas(band):
    """ṁ = sr(p_a² − p_b²)/R both ways; sr and its slope (returned unless told not to)."""
    for pa, pb in [(300.0, 200.0), (200.0, 300.0), (150.0, 149.0), (149.0, 150.0)]:
        mdot, d_a, d_b = quadrature_flow(pa, pb, 2.0, band)
        assert float(mdot) == pytest.approx(root(pa * pa - pb * pb, band) / 2.0, rel=1e-12)
        want = central(lambda a, b: root(a * a - b * b, band) / 2.0, (pa, pb), h=1e-5)
        np.testing.assert_allclose([float(d_a), float(d_b)], want, rtol=1e-6)
    for d in (-2000.0, -3.0, 0.5, 40.0):
        value, slope = signed_root(d, band)
        assert float(value) == pytest.approx(root(d, band), rel=1e-12)
        assert float(slope) == pytest.approx(central(lambda v: root(v, band), [d], 1e-6)[0],
                                             rel=1e-6)


def test_default_flow_band_is_the_documented_10_kpa2():
    """docs/netlist.md's .options line and docs/model.md: flow_band = 10 kPa² unless set;
    the laws' default is the circuits' default."""
    from pneunet.engine.options import SimulationOptions

    assert SimulationOptions().flow_band == 10.0
    mdot, _, _ = quadrature_flow(150.0, 149.99, 1.0)
    assert float(mdot) == pytest.approx(root(150.0 ** 2 - 149.99 ** 2, 10.0), rel=1e-12)
    axi = PAPER_VALVES["axi"].as_dict()
    mdot, _ = valve_flow_and_partials(150.0, 149.99, 20.0, *axi.values())  # open: Δp 134.5
    want = valve(150.0, 149.99, 20.0, axi, 10.0)
    assert want > 0 and float(mdot) == pytest.approx(want, rel=1e-12)


def test_valve_conductance_and_its_slope_by_default():
    """Eq. 19's conductance 1/(R_f·√(1 + u^(−2e))) and d/dΔp (returned unless told not to);
    zero, with zero slope, at and below p_close; signed_root exact (band 0) by default."""
    axi = PAPER_VALVES["axi"].as_dict()

    def g(dp):
        u = (dp - axi["pclose"]) / (axi["ptrans"] - axi["pclose"])
        return 0.0 if u <= 0 else 1.0 / (axi["Rf"] * np.sqrt(1.0 + u ** (-2.0 * axi["e"])))

    for dp in (100.0, 130.0, 174.0, 400.0):
        value, slope = valve_conductance(dp, axi["Rf"], axi["pclose"], axi["ptrans"], axi["e"])
        assert float(value) == pytest.approx(g(dp), rel=1e-12)
        assert float(slope) == pytest.approx(central(g, [dp], 1e-5)[0], rel=1e-6)
    value, slope = valve_conductance(90.0, axi["Rf"], axi["pclose"], axi["ptrans"], axi["e"])
    assert float(value) == 0.0 and float(slope) == 0.0
    assert float(signed_root(-4.0)[0]) == -2.0 and float(signed_root(4.0)[1]) == 0.25


def test_no_pressure_difference_no_flow_with_the_exact_root():
    """Identification's exact law (band 0) at p_in = p_out: zero flow, not 0/0; the exact
    root's slope there is infinite (dṁ/dp of √)."""
    from pneunet.physics.laws import valve_flow

    axi = PAPER_VALVES["axi"].as_dict()
    assert valve_flow(300.0, 300.0, 96.0, **axi) == 0.0  # open: Δp = 213 kPa
    assert float(quadrature_flow(150.0, 150.0, 2.0, band=0.0)[0]) == 0.0
    value, slope = signed_root(0.0)
    assert float(value) == 0.0 and float(slope) == np.inf
