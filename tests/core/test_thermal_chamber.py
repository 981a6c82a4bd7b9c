"""The thermal chamber against the gas energy balance written out by hand.

A 50 mL vessel between a 400 kPa supply (through R1) and the atmosphere (through R2)
fills and vents at once: gas enters at wall temperature and leaves at its own, and the
wall takes heat back with the constant conductance hA = m_ref·c_v/τ.  The reference
below integrates mass and temperature with scipy (no pneunet code): the one-port
``thermal_volume``, which sees only the net flow, cannot reproduce it, the chamber with
one ``thermal_inlet`` per line must.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pneunet import Circuit

M_AIR, R_GAS = 28.965, 8.314462618  # g/mol, J/(mol K)
GAMMA, T_WALL, P_AMB, BAND = 1.4, 293.15, 100.0, 10.0
V, TAU, R1, R2, P_SUPPLY = 50.0, 0.3, 1.0, 2.0, 400.0


def _root(d):
    return d / (d * d + BAND * BAND) ** 0.25


def reference(times):
    """(p kPa, T K) of the vessel: m·dT/dt = γ·T_w·q_in − γ·T·q_out − T·(q_in − q_out)
    + m_ref/τ·(T_w − T), p = m·R·T/(M·V)."""
    c = M_AIR * V / (R_GAS * T_WALL)  # mg/kPa at T_w
    m_ref = c * P_AMB

    def rhs(t, y):
        m, temp = y
        p = m / c * temp / T_WALL
        q_in = _root(P_SUPPLY ** 2 - p ** 2) / R1
        q_out = _root(p ** 2 - P_AMB ** 2) / R2
        dm = q_in - q_out
        h_in = T_WALL if q_in >= 0 else temp
        dT = (GAMMA * h_in * q_in - GAMMA * temp * q_out - temp * dm
              + m_ref / TAU * (T_WALL - temp)) / m
        return [dm, dT]

    sol = solve_ivp(rhs, (0, times[-1]), [m_ref, T_WALL], t_eval=times, method="Radau",
                    rtol=1e-10, atol=1e-10)
    m, temp = sol.y
    return m / c * temp / T_WALL, temp


def _vessel(kind):
    c = Circuit("vessel", ambient=P_AMB)
    c.pressure_source("P1", "s", P_SUPPLY)
    if kind == "chamber":
        c.resistor("R1", "s", "x1", R=R1)
        c.resistor("R2", "x2", "atm", R=R2)
        c.add("thermal_inlet", "I1", ("x1", "v", "vT"))
        c.add("thermal_inlet", "I2", ("x2", "v", "vT"))
        c.add("thermal_chamber", "VC", ("v", "vT"), V=V, tau=TAU)
    else:
        c.resistor("R1", "s", "v", R=R1)
        c.resistor("R2", "v", "atm", R=R2)
        c.add("thermal_volume", "VC", ("v", "vT"), V=V, tau=TAU)
    c.options = c.options.replace(rtol=1e-8, atol=1e-8)
    return c


def test_chamber_with_two_lines_follows_the_energy_balance():
    times = np.linspace(0.0, 1.5, 151)
    p_ref, temp_ref = reference(times)
    sol = _vessel("chamber").tran(1.5, t_step=0.01)
    p = np.interp(times, sol.t, sol.pressure("v"))
    temp = np.interp(times, sol.t, sol["T_VC"])
    assert temp_ref.max() > T_WALL + 20  # the compression heating is large
    np.testing.assert_allclose(p, p_ref, rtol=2e-4)
    np.testing.assert_allclose(temp, temp_ref, rtol=2e-4)
    # the link drops a negligible pressure
    assert np.max(np.abs(sol.pressure("x1") - sol.pressure("v"))) < 0.01


def test_one_port_volume_misses_the_outflow_enthalpy_the_chamber_carries():
    times = np.linspace(0.0, 1.5, 151)
    _, temp_ref = reference(times)
    sol = _vessel("volume").tran(1.5, t_step=0.01)
    temp = np.interp(times, sol.t, sol["T_VC"])
    assert np.max(np.abs(temp - temp_ref)) > 5.0  # K: net flow is not enough here


def test_chamber_with_one_line_equals_the_one_port_volume():
    c1 = Circuit("one line", ambient=P_AMB)
    c1.pressure_source("P1", "s", P_SUPPLY)
    c1.resistor("R1", "s", "x", R=R1)
    c1.add("thermal_inlet", "I1", ("x", "v", "vT"), p0=150.0)
    c1.add("thermal_chamber", "VC", ("v", "vT"), V=V, tau=TAU, p0=150.0)
    c2 = Circuit("one port", ambient=P_AMB)
    c2.pressure_source("P1", "s", P_SUPPLY)
    c2.resistor("R1", "s", "v", R=R1)
    c2.add("thermal_volume", "VC", ("v", "vT"), V=V, tau=TAU, p0=150.0)
    a, b = c1.tran(1.0, t_step=0.01), c2.tran(1.0, t_step=0.01)
    np.testing.assert_allclose(a["T_VC"], b["T_VC"], rtol=1e-4)
    assert a.pressure("v")[0] == pytest.approx(150.0)
