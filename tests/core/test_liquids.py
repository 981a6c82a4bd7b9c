"""Liquid circuits: fills through an orifice and a laminar tube against their closed-form
solutions, written out here from ρ, μ and K of water (issue 14)."""
import math

import numpy as np
import pytest

from pneunet import Circuit, ParameterError
from pneunet.common.errors import PneunetError
from pneunet.netlist import parse_netlist

RHO, MU, K = 998.2, 1.002e-3, 2.18e6  # water at 20 °C: kg/m³, Pa·s, kPa
SUPPLY, AMBIENT, V = 400.0, 100.0, 2000.0  # kPa, kPa, mL


def _fill(add_restriction, t_stop, volume="volume"):
    c = Circuit("liquid fill", ambient=AMBIENT, fluid="water", rtol=1e-8, atol=1e-8)
    c.pressure_source("P1", "s", SUPPLY)
    add_restriction(c)
    if volume == "volume":
        c.volume("V1", "b", V=V)
    else:
        c.accumulator("A1", "b", V0=V, k=0.0002)
    return c.tran(t_stop, t_step=t_stop / 1000)


def _crossing(sol, level):
    """Time at which p_b first reaches ``level`` (linear between output points)."""
    p = sol.pressure("b")
    assert p[0] < level <= p[-1]
    i = int(np.argmax(p >= level))
    return float(np.interp(level, p[i - 1:i + 1], sol.t[i - 1:i + 1]))


def test_orifice_fill_time_matches_the_square_root_law():
    """C·ṗ = a·√(p_s − p), C = ρV/K, a = Cd·A·√(2ρ) (SI): √(p_s − p) falls linearly, so
    the gap closes from u0 to u1 in t = 2C(√u0 − √u1)/a."""
    d, cd = 0.3, 0.61  # mm
    sol = _fill(lambda c: c.orifice("O1", "s", "b", diameter=d, Cd=cd), 0.6)
    c_si = RHO * V * 1e-6 / (K * 1e3)  # kg/Pa
    a_si = cd * math.pi / 4 * (d * 1e-3) ** 2 * math.sqrt(2 * RHO)  # kg/s per √Pa
    for gap in (150.0, 50.0, 5.0):  # kPa below the supply
        t_exact = 2 * c_si * (math.sqrt(300e3) - math.sqrt(gap * 1e3)) / a_si
        assert _crossing(sol, SUPPLY - gap) == pytest.approx(t_exact, rel=2e-4)


def test_laminar_tube_fill_is_exponential_with_wall_compliance():
    """C·ṗ = G·(p_s − p), G = ρπD⁴/(128μL); C = ρ·(V/K + k) grows with the accumulator's
    volume V0 + k(p − p_ref): the exact solution of the separable equation is checked at
    three crossings."""
    length, dia, k = 500.0, 0.4, 0.0002  # mm, mm, mL/kPa
    sol = _fill(lambda c: c.laminar_tube("T1", "s", "b", length=length, diameter=dia), 2.0,
                volume="accumulator")
    g = RHO * math.pi * (dia * 1e-3) ** 4 / (128 * MU * length * 1e-3)  # kg/(s·Pa)
    c0 = RHO * 1e-6 * (V / K + k) / 1e3  # kg/Pa at p = p_ref, SI
    c1 = RHO * 1e-6 * k / K / 1e3 * 1e-3  # dC/dp, kg/Pa²
    for level in (150.0, 250.0, 350.0):
        u0, u = (SUPPLY - AMBIENT) * 1e3, (SUPPLY - level) * 1e3  # Pa
        # ∫ C(p) dp/(G(p_s − p)) with C = c0 + c1·(p − p_ref) = c0 + c1·(u0 − u)
        t_exact = ((c0 + c1 * u0) * math.log(u0 / u) - c1 * (u0 - u)) / g
        assert _crossing(sol, level) == pytest.approx(t_exact, rel=2e-4)
    assert np.max(sol.signals["Re_T1"]) < 2000  # laminar, as the law assumes


def test_fluid_is_stated_once_and_gas_elements_are_refused():
    deck = parse_netlist(".options fluid=water ambient=100kPa\nP1 s 4bar\n"
                         "orifice O1 s b 0.5mm\nlaminar_tube T1 b atm 1m 1mm\nV1 b 10mL\n")
    assert deck.circuit.options.liquid.name == "water"
    with pytest.raises(PneunetError, match="resistor is a gas element; this circuit's fluid"):
        parse_netlist(".options fluid=water\nP1 s 4bar\nR1 s atm 1\n")
    with pytest.raises(ParameterError, match="orifice is a liquid element"):
        Circuit().orifice("O1", "a", "b", diameter=1.0)
    with pytest.raises(ParameterError, match="unknown fluid 'honey'"):
        Circuit(fluid="honey")
    with pytest.raises(ParameterError, match="O2.*Cd=2.5 is outside its valid range"):
        Circuit(fluid="water").orifice("O2", "a", "b", diameter=1.0, Cd=2.5)


def test_liquid_circuit_prints_and_parses_back():
    from pneunet.netlist import print_circuit

    c = Circuit("hydraulic", fluid="hydraulic_oil")
    c.pressure_source("P1", "s", "3bar")
    c.orifice("O1", "s", "b", diameter=0.5, Cd=0.7)
    c.laminar_tube("T1", "b", "atm", length=800.0, diameter=1.0)
    c.accumulator("A1", "b", V0=50.0, k=0.01)
    again = parse_netlist(print_circuit(c)).circuit
    assert again.options == c.options
    assert {n: e.params for n, e in again.elements.items()} == \
        {n: e.params for n, e in c.elements.items()}
