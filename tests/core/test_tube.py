"""The tube element (issue 12): a gas line's resistance and volume in N lumped segments.

References are written here independently: Hagen–Poiseuille for isothermal gas,
Blasius and eq. 6 (Weymouth) friction, the gas law for the stored mass, the
linear diffusion of a small pressure step into a closed line, and a finite-volume
line (many cells, scipy's solve_ivp) filling a volume from the paper's supply.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.sparse import diags

from pneunet import Circuit, ParameterError
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_netlist, print_circuit
from pneunet.physics.waveforms import Step
from reference_lines import MU, R_AIR, T, line_flow  # tests/ is on pytest's sys.path


def _steady_flow(p_a, length, diameter, **kw):
    """Operating-point flow (mg/s) through a tube from p_a (kPa) to ambient 100 kPa."""
    c = Circuit("tube", ambient=100.0)
    c.pressure_source("P1", "a", p_a)
    c.tube("T1", "a", "atm", length=length, diameter=diameter, **kw)
    flows = c.op(stability=False).flows
    return flows["T1.s1"], flows


def _reynolds(mdot_mg_s, diameter_mm):
    return 4 * mdot_mg_s * 1e-6 / (np.pi * diameter_mm * 1e-3 * MU)


def test_laminar_flow_is_hagen_poiseuille_for_isothermal_gas():
    mdot, flows = _steady_flow(101.0, length=5000.0, diameter=1.0)
    d, l = 1e-3, 5.0
    expected = np.pi * d ** 4 * ((101e3) ** 2 - (100e3) ** 2) / (256 * MU * R_AIR * T * l) * 1e6
    assert _reynolds(mdot, 1.0) < 50
    assert mdot == pytest.approx(expected, rel=2e-3)
    # steady: the same flow through every segment
    assert np.allclose(list(flows.values())[1:], mdot, rtol=1e-9)


def test_turbulent_flow_follows_blasius():
    mdot, _ = _steady_flow(400.0, length=2000.0, diameter=4.0)
    d, l = 4e-3, 2.0

    def excess(m_kg_s):
        f = 0.0791 * (4 * m_kg_s / (np.pi * d * MU)) ** -0.25
        return 64 * f * l * R_AIR * T * m_kg_s ** 2 / (np.pi ** 2 * d ** 5) - (400e3 ** 2 - 100e3 ** 2)

    expected = brentq(excess, 1e-7, 1.0) * 1e6
    assert _reynolds(mdot, 4.0) > 1e4
    assert mdot == pytest.approx(expected, rel=2e-3)


def _blasius_flow(delta_pa2, length, diameter):
    """Turbulent flow (kg/s) with Fanning f = 0.0791·Re^(−1/4): Δ = 64·f·R_s·T·L·ṁ²/(π²·D⁵)."""
    k = 64 * R_AIR * T * length / (np.pi ** 2 * diameter ** 5)
    return brentq(lambda m: k * 0.0791 * (4 * m / (np.pi * diameter * MU)) ** -0.25 * m * m
                  - delta_pa2, 1e-12, 10.0)


@pytest.mark.parametrize("p_a", [100.05, 100.2, 100.5, 130.0, 250.0, 600.0])
def test_each_law_holds_in_its_reynolds_range(p_a):
    """Within 1 % of Hagen–Poiseuille below Re = 200, of Blasius above Re = 3,500."""
    d, l = 2e-3, 1.0
    mdot, _ = _steady_flow(p_a, length=l * 1e3, diameter=d * 1e3)
    delta = (p_a * 1e3) ** 2 - 100e3 ** 2
    re = _reynolds(mdot, d * 1e3)
    laminar = np.pi * d ** 4 * delta / (256 * MU * R_AIR * T * l) * 1e6
    if re < 200:
        assert mdot == pytest.approx(laminar, rel=0.01), re
    elif re > 3500:
        assert mdot == pytest.approx(_blasius_flow(delta, l, d) * 1e6, rel=0.01), re
    else:  # transition: below both laws
        assert mdot < min(laminar, _blasius_flow(delta, l, d) * 1e6), re


def test_explicit_friction_factor_is_eq6():
    mdot, _ = _steady_flow(400.0, length=2000.0, diameter=4.0, f=0.006, segments=3)
    d, l = 4e-3, 2.0
    r_si = 8 * np.sqrt(0.006 * l * R_AIR * T / (np.pi ** 2 * d ** 5))
    expected = np.sqrt(400e3 ** 2 - 100e3 ** 2) / r_si * 1e6
    assert mdot == pytest.approx(expected, rel=1e-3)


def test_total_gas_volume_is_the_line_volume():
    # 0.5 mg/s for 1 s into a closed line: the pressure rise is the mass over C = M·V/(R·T)
    # rtol 1e-7: at the default 1e-5 IDA's error over the fill is ~1e-3 of the rise
    c = Circuit("closed line", ambient=100.0, rtol=1e-7, atol=1e-7)
    c.flow_source("F1", "atm", "a", Step(0.5, 0.0, at=1.0))
    c.tube("T1", "a", "b", length=1000.0, diameter=2.0, segments=7)
    sol = c.tran(5.0, t_step=0.01)
    volume = np.pi / 4 * 2e-3 ** 2 * 1.0  # m³
    rise = 0.5e-6 * R_AIR * T / volume / 1e3  # kPa
    assert sol.pressure("b")[-1] - 100.0 == pytest.approx(rise, rel=1e-4)
    assert sol.pressure("a")[-1] == pytest.approx(sol.pressure("b")[-1], abs=1e-6)


def test_small_step_into_a_closed_line_diffuses_as_the_analytic_limit():
    # 0.5 kPa onto a 5 m × 1 mm line, closed at b: ∂p/∂t = κ ∂²p/∂x², κ = p·D²/(32·μ)
    length, diameter, step = 5.0, 1e-3, 0.5
    c = Circuit("diffusion", ambient=100.0)
    c.pressure_source("P1", "a", Step(100.0, 100.0 + step, at=0.0))
    c.tube("T1", "a", "b", length=length * 1e3, diameter=diameter * 1e3, segments=20)
    sol = c.tran(3.0, t_step=1e-3)
    kappa = 100.25e3 * diameter ** 2 / (32 * MU)
    n = np.arange(200)
    lam = (2 * n + 1) ** 2 * np.pi ** 2 * kappa / (4 * length ** 2)

    def closed_end(t):
        return 1 - 4 / np.pi * np.sum((-1.0) ** n / (2 * n + 1) * np.exp(-lam * t))

    rise = (sol.pressure("b") - 100.0) / step
    for level in (0.5, 0.9):
        t_sim = np.interp(level, rise, sol.t)
        t_ref = brentq(lambda t: closed_end(t) - level, 1e-4, 10.0)
        assert t_sim == pytest.approx(t_ref, rel=5e-3), level


def test_default_segments_and_names():
    c = Circuit("names", ambient=100.0)
    c.tube("T1", "a", "b", length=3000.0, diameter=2.0)  # 3000/(100·2) = 15
    assert [e for e in c.elements] == [f"T1.s{k}" for k in range(1, 16)]
    assert c.nodes == ["a", *(f"T1.{k}" for k in range(1, 15)), "b"]
    c.tube("T2", "a", "b", length=10.0, diameter=2.0)  # at least 4
    c.tube("T3", "a", "b", length=1e5, diameter=1.0)   # at most 20
    assert sum(e.startswith("T2.") for e in c.elements) == 4
    assert sum(e.startswith("T3.") for e in c.elements) == 20


@pytest.mark.parametrize("params, message", [
    ("length=0 diameter=2mm", "length"), ("length=1m diameter=-1mm", "diameter"),
    ("length=1m diameter=2mm segments=2.5", "segments"),
    ("length=1m diameter=2mm segments=0", "segments"), ("length=1m diameter=2mm f=2", "f="),
])
def test_bad_parameters_name_the_element_and_line(params, message):
    text = f"* bad tube\nP1 a 300kPa\ntube T9 a atm {params}\n.tran 1s\n.end\n"
    with pytest.raises(NetlistError) as err:
        parse_netlist(text)
    assert "T9" in str(err.value) and "<netlist>:3:" in str(err.value)
    assert message in str(err.value)
    kw = dict(item.split("=") for item in params.split())
    with pytest.raises(ParameterError, match="element T9"):
        Circuit("bad").tube("T9", "a", "b", **kw)


def test_netlist_tube_matches_the_python_api():
    deck = parse_netlist("* line\nP1 a 300kPa\ntube T1 a atm length=2m diameter=4mm "
                         "segments=3\n.op\n.end\n")
    assert [e for e in deck.circuit.elements if e.startswith("T1")] == ["T1.s1", "T1.s2", "T1.s3"]
    assert deck.circuit.elements["T1.s2"].params["length"] == pytest.approx(2000.0 / 3)


def test_printed_segments_parse_back_to_the_same_line():
    c = Circuit("line", ambient=100.0)
    c.pressure_source("P1", "a", 300.0)
    c.tube("T1", "a", "atm", length=2000.0, diameter=1.0, segments=3)
    again = parse_netlist(print_circuit(c)).circuit
    assert list(again.elements) == list(c.elements)
    assert again.op(stability=False).flows["T1.s3"] == pytest.approx(
        c.op(stability=False).flows["T1.s3"], rel=1e-9)


# -- fill time through a long line against a finite-volume line ----------------------------
AMB, SUPPLY = 96.0, 496.0  # kPa, the paper's vent and supply pressures


def _fv_fill_time(length, d, volume, level, cells=400):
    """Time (s) for a volume (m³) at the end of a line, all at AMB, to reach ``level`` (kPa)
    once the supply steps to SUPPLY: ``cells`` cells of gas (isothermal, mass per cell
    A·dx·p/(R_s·T)), the volume a last cell with no outflow."""
    dx = length / cells
    caps = np.r_[np.full(cells, np.pi / 4 * d ** 2 * dx), volume] / (R_AIR * T)  # kg/Pa
    lengths = np.r_[dx / 2, np.full(cells - 1, dx), dx / 2]  # supply→cell 1 … cell n→volume

    def rate(t, p):
        inflow = line_flow(np.r_[SUPPLY * 1e3, p[:-1]], p, lengths, d)
        return (inflow - np.r_[inflow[1:], 0.0]) / caps

    def reached(t, p):
        return p[-1] - level * 1e3
    reached.terminal = True
    out = solve_ivp(rate, (0.0, 60.0), np.full(cells + 1, AMB * 1e3), method="BDF",
                    jac_sparsity=diags([1.0, 1.0, 1.0], [-1, 0, 1], shape=(cells + 1,) * 2),
                    rtol=1e-8, atol=1e-3, events=reached)
    return out.t_events[0][0]


@pytest.mark.parametrize("volume_ml", [120.0, 1.0])
def test_fill_time_through_a_long_line_matches_a_finite_volume_line(volume_ml):
    """2 m of 2 mm tubing (default segments: 10) fills a volume from the paper's supply
    (96 → 496 kPa at t = 0); "filled" is 90 % of the supply's gauge pressure (456 kPa).
    120 mL: the line's resistance sets the time; 1 mL: its own volume (6.3 mL) does."""
    level = AMB + 0.9 * (SUPPLY - AMB)
    c = Circuit("fill", ambient=AMB, rtol=1e-7, atol=1e-7)
    c.pressure_source("P1", "s", Step(AMB, SUPPLY, at=0.0))
    c.tube("T1", "s", "tank", length="2m", diameter="2mm")
    c.volume("V1", "tank", V=volume_ml)
    sol = c.tran(2.0, t_step=1e-4)
    t_fill = np.interp(level, sol.pressure("tank"), sol.t)
    t_ref = _fv_fill_time(2.0, 2e-3, volume_ml * 1e-6, level)
    assert t_fill == pytest.approx(t_ref, rel=0.03)
