"""Check valves and K-factor restrictions in liquid circuits (issue 34, item 4), against
their laws written here: the check valve's smoothstep opening u = 3s² − 2s³,
s = (Δp − pcrack)/width, times the linear liquid law ṁ = (u/R + 1/Rleak)·Δp; FONSim's
FlowRestrictor Δp = 8·K·ṁ²/(π²·ρ·D⁴) (K·ρv²/2)."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pneunet import Circuit
from pneunet.netlist import parse_netlist
from pneunet.physics.waveforms import PiecewiseLinear

RHO, MU, K = 998.2, 1.002e-3, 2.18e6  # pneunet's water
AMB = 100.0


def _u(dp, pcrack, width):
    s = min(max((dp - pcrack) / width, 0.0), 1.0)
    return s * s * (3 - 2 * s)


def _valve(dp, r=0.05, pcrack=10.0, width=4.0, r_leak=math.inf):
    return (_u(dp, pcrack, width) / r + 1 / r_leak) * dp  # mg/s


@pytest.mark.parametrize("p_s", [105.0, 112.0, 150.0])
def test_liquid_check_valve_follows_its_law_closed_opening_and_open(p_s):
    """Supply → check valve → node m → laminar line (G mg/(s·kPa)) → ambient: the node
    balances the valve's flow against the line's, solved here by bisection."""
    c = Circuit("liquid check", ambient=AMB, fluid="water")
    c.pressure_source("P1", "s", p_s)
    c.check_valve("D1", "s", "m", R=0.05, pcrack="10kPa", width="4kPa", Rleak=500.0)
    c.laminar_tube("T1", "m", "atm", length=1000.0, diameter=1.0)
    g = RHO * math.pi * 1.0 ** 4 / (128 * MU * 1000.0)  # mg/(s·kPa), D and L in mm
    m = brentq(lambda x: _valve(p_s - x, r_leak=500.0) - g * (x - AMB), AMB, p_s, xtol=1e-12)
    op = c.op(stability=False)
    assert op.pressures["m"] == pytest.approx(m, abs=1e-6)
    assert op.flows["D1"] == pytest.approx(g * (m - AMB), rel=1e-6)


def test_liquid_check_valve_fills_an_accumulator_and_holds_it():
    """A supply ramps up to 300 kPa and back to ambient; the valve fills an accumulator
    and then holds its pressure (no leak). Against solve_ivp of C·ṗ = ṁ_valve(p_s − p)."""
    times, levels = [0.0, 0.2, 0.6, 0.8, 1.5], [AMB, 300.0, 300.0, AMB, AMB]
    c = Circuit("hold", ambient=AMB, fluid="water", rtol=1e-8, atol=1e-8)
    c.pressure_source("P1", "s", PiecewiseLinear(times, levels))
    c.check_valve("D1", "s", "x", R=0.002, pcrack="10kPa", width="4kPa")  # τ = RC ≈ 0.2 s
    c.accumulator("A1", "x", V0=10.0, k=0.1)
    sol = c.tran(1.5, t_step=0.01)
    cap = lambda p: RHO * ((10.0 + 0.1 * (p - AMB)) / K + 0.1)  # mg/kPa (ρ in mg/mL)

    def rate(t, y):
        return [_valve(np.interp(t, times, levels) - y[0], r=0.002) / cap(y[0])]

    ref = solve_ivp(rate, (0.0, 1.5), [AMB], rtol=1e-10, atol=1e-10, max_step=0.005,
                    dense_output=True)
    p = sol.pressure("x")
    assert np.max(np.abs(p - ref.sol(sol.t)[0])) < 0.02  # kPa, of a 190 kPa rise
    assert p[-1] > 280.0 and p[-1] == pytest.approx(p[sol.t.searchsorted(0.9)], abs=1e-6)


def test_orifice_k_factor_is_fonsims_flow_restrictor():
    deck = parse_netlist(".options fluid=water ambient=100kPa\nP1 a 150kPa\n"
                         "orifice O1 a atm diameter=2mm K=0.6\n.op\n")
    mdot = deck.circuit.op(stability=False).flows["O1"] * 1e-6  # kg/s
    d, dp = 2e-3, 50e3
    assert 8 * 0.6 * mdot ** 2 / (math.pi ** 2 * RHO * d ** 4) == pytest.approx(dp, rel=1e-6)
    from pneunet.common.errors import NetlistError
    with pytest.raises(NetlistError, match=r"<netlist>:3:.*Cd or its K, not both"):
        parse_netlist(".options fluid=water\nP1 a 150kPa\n"
                      "orifice O1 a atm diameter=2mm K=0.6 Cd=0.7\n")
