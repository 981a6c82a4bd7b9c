"""``tube`` in liquid circuits and with wall roughness (issue 34): Darcy–Weisbach with
Haaland's friction factor, laminar Hagen–Poiseuille, written here independently (SI units),
and FONSim's water case of two accumulators draining through a tube, against scipy.

Haaland (1983): 1/√f = −1.8·log10((ε/D/3.7)^1.11 + 6.9/Re), Darcy f; Δp = f·(L/D)·ρv²/2,
i.e. Δp = f·8L·ṁ²/(π²·D⁵·ρ) for a liquid and p_a² − p_b² = f·16L·R_s·T·ṁ²/(π²·D⁵) for an
isothermal ideal gas.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pneunet import Circuit, ParameterError
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_netlist
from reference_lines import R_AIR, T  # tests/ is on pytest's sys.path

RHO, MU, K = 998.2, 1.002e-3, 2.18e6  # pneunet's water: kg/m³, Pa·s, kPa
AMB = 100.0  # kPa
# air at 20 °C by Sutherland's law with White's constants (μ0, T0, S) = (1.716e-5, 273.15, 110.4)
MU_AIR = 1.716e-5 * (T / 273.15) ** 1.5 * (273.15 + 110.4) / (T + 110.4)


def _haaland(re, rel):
    """Darcy f at Re floored as pneunet documents, Re_h = (Re⁴ + 100⁴)^(1/4) (Haaland's
    formula has no root below Re ≈ 24)."""
    re_h = (re ** 4 + 100.0 ** 4) ** 0.25
    return (-1.8 * math.log10((rel / 3.7) ** 1.11 + 6.9 / re_h)) ** -2


def _turbulent(delta, kappa, d, mu, eps):
    """kg/s solving delta = κ·f(Re)·ṁ² (Haaland), by bisection."""
    return brentq(lambda m: kappa * _haaland(4 * m / (math.pi * d * mu), eps / d) * m * m
                  - delta, 1e-9, 10.0, xtol=1e-15, rtol=1e-13)


def _liquid_flow(dp_pa, length, d, eps):
    """Documented blend of Hagen–Poiseuille and Haaland flows, kg/s (signed)."""
    kappa = 8 * length / (math.pi ** 2 * d ** 5 * RHO)
    lam = abs(dp_pa) * math.pi * d ** 4 * RHO / (128 * MU * length)
    turb = _turbulent(abs(dp_pa), kappa, d, MU, eps)
    return math.copysign((lam ** -4 + turb ** -4) ** -0.25, dp_pa)


def _op_flow(p_a, length_mm, diameter_mm, fluid="water", **kw):
    """Steady flow (mg/s) through a tube from p_a (kPa) to the ambient."""
    c = Circuit("line", ambient=AMB, fluid=fluid)
    c.pressure_source("P1", "a", p_a)
    c.tube("T1", "a", "atm", length=length_mm, diameter=diameter_mm, **kw)
    return c.op(stability=False).flows["T1.s1"]


@pytest.mark.parametrize("eps_mm", [0.0, 0.0015, 0.05])
def test_turbulent_liquid_flow_is_darcy_weisbach_with_haaland(eps_mm):
    length, d, dp = 0.5, 4e-3, 50e3  # m, m, Pa
    mdot = _op_flow(AMB + dp / 1e3, length * 1e3, d * 1e3, roughness=eps_mm)
    expected = _turbulent(dp, 8 * length / (math.pi ** 2 * d ** 5 * RHO), d, MU, eps_mm * 1e-3)
    assert 4 * expected / (math.pi * d * MU) > 1.5e4  # well turbulent
    assert mdot == pytest.approx(expected * 1e6, rel=1e-4)  # the laminar blend: < 1e-4
    assert mdot == pytest.approx(_liquid_flow(dp, length, d, eps_mm * 1e-3) * 1e6, rel=1e-7)


def test_roughness_lowers_the_flow_as_the_moody_chart_says():
    """At ε/D = 0.0125 and Re ≈ 4·10⁴ Haaland's f is 0.0416 against 0.0222 smooth: the flow
    at the same Δp falls by √(0.0222/0.0416) (the Re shift is in the reference)."""
    smooth = _op_flow(AMB + 50.0, 500.0, 4.0, roughness=0.0)
    rough = _op_flow(AMB + 50.0, 500.0, 4.0, roughness=0.05)
    assert rough / smooth == pytest.approx(
        _liquid_flow(50e3, 0.5, 4e-3, 5e-5) / _liquid_flow(50e3, 0.5, 4e-3, 0.0), rel=2e-4)
    assert rough / smooth < 0.8


def test_slow_liquid_flow_is_hagen_poiseuille():
    length, d, dp = 1.0, 1e-3, 400.0  # Re ≈ 20
    mdot = _op_flow(AMB + dp / 1e3, length * 1e3, d * 1e3)
    laminar = dp * math.pi * d ** 4 * RHO / (128 * MU * length)
    assert 4 * laminar / (math.pi * d * MU) < 25
    assert mdot == pytest.approx(laminar * 1e6, rel=3e-3)
    assert mdot == pytest.approx(_liquid_flow(dp, length, d, 0.0) * 1e6, rel=2e-4)


def test_rough_gas_tube_is_isothermal_darcy_weisbach_with_haaland():
    length, d, eps = 2.0, 4e-3, 0.02e-3
    mdot = _op_flow(400.0, length * 1e3, d * 1e3, fluid="gas", roughness="0.02mm")
    kappa = 16 * length * R_AIR * T / (math.pi ** 2 * d ** 5)
    expected = _turbulent((400e3) ** 2 - (AMB * 1e3) ** 2, kappa, d, MU_AIR, eps)
    assert 4 * expected / (math.pi * d * MU_AIR) > 1e4
    assert mdot == pytest.approx(expected * 1e6, rel=1e-4)
    delta = (400e3) ** 2 - (AMB * 1e3) ** 2
    laminar = delta * math.pi * d ** 4 / (256 * MU_AIR * R_AIR * T * length)
    blend = (laminar ** -4 + expected ** -4) ** -0.25  # as documented for tube
    assert mdot == pytest.approx(blend * 1e6, rel=1e-7)


def test_water_drains_two_accumulators_as_the_law_says():
    """FONSim's water test (test_02 of its accumulator tests): a source at 0.2 bar gauge, a
    2 mm × 0.1 m tube, two accumulators k = 10¹⁰ Pa/m³ joined at its end holding 6 mL
    (0.3 bar gauge). It starts at Re ≈ 6,900, crosses the transition and ends laminar.
    pneunet's node pressure against scipy's solve_ivp of C(p)·ṗ = −ṁ(p − p_s), C =
    2ρ(V/K + k) from both accumulators plus the tube's stored liquid ρ·V_tube/(2K)."""
    eps, length, d = 0.0015e-3, 0.1, 2e-3
    c = Circuit("two accumulators", ambient=AMB, fluid="water", rtol=1e-8, atol=1e-8)
    c.pressure_source("P1", "s", "20kPag")
    c.tube("T1", "s", "x", length="0.1m", diameter="2mm", roughness="0.0015mm", segments=1)
    for name in ("A0", "A1"):
        c.accumulator(name, "x", V0="1mL", k=0.1, pref="10kPag", p0="30kPag")
    sol = c.tran(0.6, t_step=0.01)

    k_ml_kpa, v_tube = 0.1, math.pi / 4 * d ** 2 * length * 1e6  # mL/kPa, mL

    def rate(t, y):
        gauge = y[0]  # kPa
        volume = 1.0 + k_ml_kpa * (gauge - 10.0)  # mL, each accumulator
        cap = 2 * RHO * 1e-6 * (volume / K + k_ml_kpa) + RHO * 1e-6 * v_tube / (2 * K)  # kg/kPa
        return [-_liquid_flow((gauge - 20.0) * 1e3, length, d, eps) / cap]

    ref = solve_ivp(rate, (0.0, 0.6), [30.0], rtol=1e-10, atol=1e-10, dense_output=True)
    gauge = sol.pressure("x") - AMB
    re0 = 4 * _liquid_flow(10e3, length, d, eps) / (math.pi * d * MU)
    assert 6000 < re0 < 8000
    assert np.max(np.abs(gauge - ref.sol(sol.t)[0])) < 2e-3  # kPa, of a 10 kPa swing
    assert gauge[-1] == pytest.approx(20.0, abs=0.01)


def test_netlist_liquid_tube_matches_python_and_bad_roughness_is_located():
    text = ("* water line\n.options fluid=water ambient=100kPa\nP1 a 150kPa\n"
            "tube T1 a atm length=0.5m diameter=4mm roughness=0.05mm\n.op\n.end\n")
    deck = parse_netlist(text)
    assert deck.circuit.op(stability=False).flows["T1.s1"] == pytest.approx(
        _op_flow(150.0, 500.0, 4.0, roughness=0.05), rel=1e-9)
    with pytest.raises(NetlistError, match=r"<netlist>:4:.*T1.*roughness=0\.5 mm is over 5% of the bore"):
        parse_netlist(text.replace("0.05mm", "0.5mm"))
    with pytest.raises(ParameterError, match="element T2.*roughness"):
        Circuit("bad", fluid="water").tube("T2", "a", "b", length=500, diameter=4,
                                           roughness=-1)


def test_closed_liquid_line_stores_rho_v_over_k():
    """0.5 mg/s for 1 s into a closed water line of 3.14 mL: the rise is m·K/(ρ·V)."""
    from pneunet.physics.waveforms import Step

    c = Circuit("closed line", ambient=AMB, fluid="water", rtol=1e-7, atol=1e-7)
    c.flow_source("F1", "atm", "a", Step(0.5, 0.0, at=1.0))
    c.tube("T1", "a", "b", length=1000.0, diameter=2.0, segments=5)
    sol = c.tran(3.0, t_step=0.01)
    volume_ml = math.pi / 4 * 2.0 ** 2 * 1000.0 * 1e-3
    rise = 0.5 * K / (RHO * volume_ml)  # kPa: mg·kPa/((mg/mL)·mL)
    assert sol.pressure("b")[-1] - AMB == pytest.approx(rise, rel=1e-4)


@pytest.mark.parametrize("volume, stored_ml", [(None, 1.0 * math.pi), (0, 0.0), ("5mL", 5.0)])
def test_a_tube_holds_its_bore_its_given_volume_or_none(volume, stored_ml):
    """0.5 mg of air into two 10 mL volumes joined by a 2 mm × 1 m tube: the pressure rise is
    the mass over M·(20 mL + the line's volume)/(R·T) (volume=0: a resistance only)."""
    from pneunet.physics.waveforms import Step

    c = Circuit("two volumes", ambient=AMB, rtol=1e-8, atol=1e-8)
    c.flow_source("F1", "atm", "a", Step(0.5, 0.0, at=1.0))
    c.volume("V1", "a", V=10.0)
    c.tube("T1", "a", "b", length=1000.0, diameter=2.0, volume=volume)
    c.volume("V2", "b", V=10.0)
    assert [e.kind for e in c.elements.values() if e.name.startswith("T1")][0] == \
        ("tube_line" if volume == 0 else "tube")
    sol = c.tran(4.0, t_step=0.01)
    capacitance = 28.965e-3 * (20.0 + stored_ml) * 1e-6 / (8.314462618 * T)  # kg/Pa
    assert sol.pressure("b")[-1] - AMB == pytest.approx(0.5e-6 / capacitance / 1e3, rel=1e-5)
