"""Check valve: cracking pressure, opening range, reseating and closed leakage against the
law written out independently here (issue 14)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from pneunet import Circuit, ParameterError
from pneunet.common.errors import PneunetError
from pneunet.netlist import parse_netlist
from pneunet.physics.waveforms import PiecewiseLinear

AMBIENT, R, PCRACK, WIDTH, RLEAK, R_LOAD = 100.0, 0.5, 30.0, 8.0, 400.0, 0.5


def reference_flow(p_a, p_b):
    """ṁ a→b (mg/s): open fraction 3s² − 2s³ of s = (Δp − pcrack)/width, quadrature law."""
    s = min(max((p_a - p_b - PCRACK) / WIDTH, 0.0), 1.0)
    opening = s * s * (3 - 2 * s)
    d = p_a * p_a - p_b * p_b
    return (opening / R + 1 / RLEAK) * math.copysign(math.sqrt(abs(d)), d)


def reference_outlet(p_a):
    """Outlet pressure where the valve's flow equals the load resistor's (to atmosphere)."""
    return brentq(lambda p_b: reference_flow(p_a, p_b) - math.sqrt(p_b ** 2 - AMBIENT ** 2)
                  / R_LOAD, AMBIENT, p_a, xtol=1e-12)


def _circuit(source):
    c = Circuit("check valve", ambient=AMBIENT, flow_band=1e-6)
    c.pressure_source("P1", "a", source)
    c.check_valve("D1", "a", "b", R=R, pcrack=PCRACK, width=WIDTH, Rleak=RLEAK)
    c.resistor("RL", "b", "atm", R=R_LOAD)
    return c


def test_steady_flow_follows_the_law_through_cracking_and_full_opening():
    supply = np.linspace(AMBIENT + 1.0, AMBIENT + 200.0, 60)
    drops, flows = [], []
    for p_a in supply:
        op = _circuit(float(p_a)).op()
        p_b = reference_outlet(p_a)
        assert op.pressures["b"] == pytest.approx(p_b, abs=1e-6)
        assert op.flows["D1"] == pytest.approx(reference_flow(p_a, p_b), rel=1e-6)
        drops.append(p_a - op.pressures["b"])
        flows.append(op.flows["D1"])
    drops, flows = np.array(drops), np.array(flows)
    closed, wide_open = drops < PCRACK, drops > PCRACK + WIDTH
    assert closed.sum() > 5 and wide_open.sum() > 5
    # closed: the leak alone; fully open: the open resistance alone (plus the leak)
    leak = np.sqrt(supply ** 2 - (supply - drops) ** 2) / RLEAK
    np.testing.assert_allclose(flows[closed], leak[closed], rtol=1e-6)
    np.testing.assert_allclose(flows[wide_open], leak[wide_open] * (1 + RLEAK / R), rtol=1e-6)
    # cracking: the flow leaves the leak line at Δp = pcrack
    cracked = drops[flows > 1.001 * leak]
    assert PCRACK < cracked.min() < PCRACK + 0.2 * WIDTH


def test_reseats_at_the_cracking_pressure_and_leaks_back_when_reversed():
    """A volume charged through the valve: it fills until the valve reseats at Δp = pcrack;
    once the supply falls below it, only the leak flows back."""
    c = Circuit("check valve fill", ambient=AMBIENT)
    c.pressure_source("P1", "a", PiecewiseLinear((0.0, 0.1, 2.0, 2.1), (AMBIENT, 250.0, 250.0,
                                                                      AMBIENT)))
    c.check_valve("D1", "a", "b", R=R, pcrack=PCRACK, width=WIDTH, Rleak=RLEAK)
    c.volume("VB", "b", V=200.0)
    sol = c.tran(3.0, t_step=0.01)
    p_a, p_b, flow = sol.pressure("a"), sol.pressure("b"), sol.flow("D1")
    held = (sol.t > 1.5) & (sol.t < 2.0)  # reseated, the leak slowly tops the volume up
    np.testing.assert_allclose(p_a[held] - p_b[held], PCRACK, atol=0.5)
    back = sol.t > 2.2  # supply below the charged volume: back-flow through the leak
    assert np.all(flow[back] < 0)
    np.testing.assert_allclose(flow[back], -np.sqrt(p_b[back] ** 2 - p_a[back] ** 2) / RLEAK,
                               rtol=1e-3)
    expected = [reference_flow(x, y) for x, y in zip(p_a, p_b)]
    np.testing.assert_allclose(flow, expected, rtol=1e-3, atol=1e-3)


def test_netlist_letter_and_kind_and_bad_parameters():
    text = ("P1 a 150kPa\nD1 a b 0.5 pcrack=30kPa width=8kPa Rleak=400\n"
            "check_valve D2 a c R=0.5 pcrack=0.3bar\nRL b atm 2\nR2 c atm 2\n")
    circuit = parse_netlist(text).circuit
    assert circuit.elements["D1"].kind == circuit.elements["D2"].kind == "check_valve"
    assert circuit.elements["D2"].params["pcrack"] == pytest.approx(30.0)
    assert circuit.elements["D2"].params["Rleak"] == np.inf
    with pytest.raises(PneunetError, match=r"D1: pcrack=-5 kPa is outside its valid range") as err:
        parse_netlist(text.replace("pcrack=30kPa", "pcrack=-5kPa"))
    assert ":2:" in str(err.value)
    with pytest.raises(ParameterError, match="Rleak=0.1 .* must exceed .* R=0.5") as err:
        Circuit().check_valve("D9", "a", "b", R=0.5, Rleak=0.1)
    assert "D9" in str(err.value)


def test_hysteretic_valve_cracks_and_reseats_at_its_two_pressures():
    """Δp imposed by two sources ramps 0 → 50 → 0 kPa: the valve opens at pcrack = 30 on
    the way up, stays open through the band down to preseat = 10, and is closed (leak only)
    in the same band on the way up."""
    width, tau, preseat = 1.0, 1e-3, 10.0
    c = Circuit("hysteresis", ambient=AMBIENT, flow_band=1e-6)
    c.pressure_source("P1", "a", PiecewiseLinear((0.0, 2.0, 4.0), (AMBIENT, AMBIENT + 50.0,
                                                                    AMBIENT)))
    c.pressure_source("P2", "b", AMBIENT)
    c.hysteretic_check_valve("D1", "a", "b", "d1_state", R=R, pcrack=PCRACK, preseat=preseat,
                             width=width, Rleak=RLEAK, tau=tau)
    sol = c.tran(4.0, t_step=0.002)
    drop, x, t = sol.pressure("a") - AMBIENT, sol.signals["opening_D1"], sol.t
    opens = drop[np.argmax(x > 0.5)]
    closes = drop[t > 2.0][np.argmax(x[t > 2.0] < 0.5)]
    # crossing x = 1/2 takes about τ·ln 2 after the drive switches on within `width`
    assert PCRACK < opens < PCRACK + width + 0.1
    assert preseat - width - 0.1 < closes < preseat
    band = (drop > preseat + 2 * width) & (drop < PCRACK - 2 * width)
    rising, falling = band & (t < 2.0), band & (t > 2.0)
    np.testing.assert_allclose(x[rising], 0.0, atol=1e-9)
    np.testing.assert_allclose(x[falling], 1.0, atol=1e-6)
    root = np.sqrt(sol.pressure("a") ** 2 - AMBIENT ** 2)
    np.testing.assert_allclose(sol.flow("D1"), (x / R + 1 / RLEAK) * root, rtol=1e-3,
                               atol=1e-3)
    with pytest.raises(ParameterError, match="preseat=40 kPa must be below pcrack=30"):
        c.hysteretic_check_valve("D2", "a", "b", "s2", R=R, pcrack=30.0, preseat=40.0)
