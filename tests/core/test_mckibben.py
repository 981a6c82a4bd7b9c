"""The McKibben actuator with its load (issue 12).

References are written here independently of the element: the Chou–Hannaford muscle
from its braid (b = L0/cos θ0, n = b·sin θ0/(π·D0); V = L·(b² − L²)/(4πn²),
F = p_g·(3L² − b²)/(4πn²)), the Tondu–Lopez force π·r0²·p_g·[a(1 − kε)² − c], force
balances solved with scipy's brentq, and the gas law for the stored mass.
"""
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from pneunet import Circuit, ParameterError
from pneunet.physics.elements.mckibben import LoadWarning
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_netlist, print_circuit
from pneunet.netlist.runner import run_deck

AMBIENT = 100.0
G = 9.81
RHO1 = 28.965 / (8.314462618 * 293.15)  # mg/(kPa·mL): air at 20 °C, per kPa
L0, D0, THETA0 = 200.0, 12.0, 25.0  # mm, mm, degrees


def _braid(l0=L0, d0=D0, theta0=THETA0):
    th = np.radians(theta0)
    b = l0 / np.cos(th)
    return b, b * np.sin(th) / (np.pi * d0)


def _ch_volume(length, b, n):
    """Chou–Hannaford volume, mL."""
    return length * (b * b - length * length) / (4 * np.pi * n * n) * 1e-3


def _ch_force(p_gauge, length, b, n):
    """Chou–Hannaford tension, N (kPa·mm² = 1e-3 N)."""
    return p_gauge * (3 * length * length - b * b) / (4 * np.pi * n * n) * 1e-3


def _circuit(p_supply, R=1.0, **muscle):
    c = Circuit("muscle", ambient=AMBIENT)
    c.pressure_source("P1", "s", p_supply)
    c.resistor("R1", "s", "a", R=R)
    c.add("mckibben", "M1", ("a",), **{"L0": L0, "D0": D0, "theta0": THETA0, **muscle})
    return c


def _static_length(p_gauge, load, spring_n_mm=0.0, b=None, n=None):
    b, n = (b, n) if b is not None else _braid()
    return brentq(lambda L: _ch_force(p_gauge, L, b, n) - load - spring_n_mm * (L0 - L),
                  b / np.sqrt(3) + 1e-9, L0)


def test_static_contraction_and_volume_follow_chou_hannaford():
    """No mass, no damping: the force balance is algebraic; op() finds it."""
    op = _circuit(250.0, preload=20.0, spring=300.0).op(stability=False)
    sol = _circuit(250.0, preload=20.0, spring=300.0).tran(2.0)
    length = _static_length(150.0, 20.0, 0.3)
    b, n = _braid()
    assert L0 - length > 10.0  # a real contraction, away from both stops
    assert sol["contraction_M1"][-1] == pytest.approx(L0 - length, rel=1e-6)
    assert sol["volume_M1"][-1] == pytest.approx(_ch_volume(length, b, n), rel=1e-6)
    assert sol["force_M1"][-1] == pytest.approx(20.0 + 0.3 * (L0 - length), rel=1e-6)
    assert op.pressures == {"s": 250.0, "a": pytest.approx(250.0)}  # no contraction as kPa


def test_mass_and_damping_settle_to_the_static_contraction():
    sol = _circuit(250.0, mass=2.0, damping=50.0).tran(3.0)
    length = _static_length(150.0, 2.0 * G)
    x = sol["contraction_M1"]
    assert x.max() > x[-1] + 0.01  # it moved (overshoot or approach) before settling
    assert x[-1] == pytest.approx(L0 - length, rel=1e-5)
    assert sol["force_M1"][-1] == pytest.approx(2.0 * G, rel=1e-4)


def test_end_effect_correction_is_tondu_lopez():
    """F = π·r0²·p_g·[a(1 − kε)² − c], a = 3/tan²θ0, c = 1/sin²θ0 against m·g."""
    k = 1.3
    th = np.radians(THETA0)
    a, c = 3 / np.tan(th) ** 2, 1 / np.sin(th) ** 2
    area = np.pi * (D0 / 2) ** 2 * 1e-3  # N per kPa
    eps = brentq(lambda e: area * 150.0 * (a * (1 - k * e) ** 2 - c) - 10.0, 0.0,
                 (1 - np.sqrt(c / a)) / k)
    sol = _circuit(250.0, preload=10.0, k_end=k).tran(2.0)
    assert sol["contraction_M1"][-1] == pytest.approx(eps * L0, rel=1e-6)


def test_a_muscle_stores_more_air_than_a_tank_of_its_relaxed_volume():
    """Filled from ambient through a resistor, the muscle takes ρ·(p·V(x) − p0·V(0)):
    its volume grows as it contracts (V(x) > π/4·D0²·L0)."""
    sol = _circuit(300.0, R=2.0, mass=0.5, damping=20.0).tran(2.0, t_step=1e-3)
    delivered = np.trapezoid(sol.flow("R1"), sol.t)
    b, n = _braid()
    x, p = sol["contraction_M1"][-1], sol.pressure("a")[-1]
    relaxed = np.pi / 4 * D0 ** 2 * L0 * 1e-3
    assert _ch_volume(L0, b, n) == pytest.approx(relaxed, rel=1e-12)
    stored = RHO1 * (p * _ch_volume(L0 - x, b, n) - AMBIENT * relaxed)
    assert delivered == pytest.approx(stored, rel=2e-3)
    assert stored > 1.1 * RHO1 * (p - AMBIENT) * relaxed


def test_thread_length_and_turns_give_the_same_muscle():
    b, n = _braid()
    by_thread = _circuit(250.0, D0=None, theta0=None, b=b, n=n, preload=20.0).tran(1.0)
    by_angle = _circuit(250.0, preload=20.0).tran(1.0)
    assert by_thread["contraction_M1"][-1] == pytest.approx(by_angle["contraction_M1"][-1],
                                                            rel=1e-9)


@pytest.mark.parametrize("params, words", [
    (dict(theta0=60.0), ["theta0=60", "54.7"]),
    (dict(theta0=-5.0), ["theta0=-5"]),
    (dict(L0=0.0), ["L0=0"]),
    (dict(D0=-2.0), ["D0=-2"]),
    (dict(mass=-1.0), ["mass=-1"]),
    (dict(spring=-5.0), ["spring=-5"]),
    (dict(damping=-0.1), ["damping=-0.1"]),
    (dict(b=150.0, n=3.0), ["D0 and theta0, or as b and n"]),
    (dict(), ["slack", "mass"]),
])
def test_bad_input_names_the_element_and_the_parameter(params, words):
    with pytest.raises(ParameterError) as err:
        _circuit(250.0, **params)
    text = str(err.value)
    assert "M1" in text and all(w in text for w in words), text


def test_bad_thread_and_netlist_line():
    with pytest.raises(ParameterError, match=r"b=190 mm"):
        _circuit(250.0, D0=None, theta0=None, b=190.0, n=3.0)
    deck = "* m\nPH s 3bar\nR1 s a 2\nmckibben M1 a L0=20cm D0=1cm theta0=55deg mass=200g\n"
    with pytest.raises((ParameterError, NetlistError)) as err:
        parse_netlist(deck)
    assert ":4" in str(err.value) and "M1" in str(err.value) and "54.7" in str(err.value)


def test_a_load_it_cannot_lift_is_a_result_with_a_warning():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LoadWarning)
        sol = _circuit(110.0, mass=20.0, damping=50.0).tran(1.0)  # 10 kPag, 196 N
        x = sol["contraction_M1"]
    assert np.all(np.isfinite(x)) and np.all(x <= 0.0) and x.min() > -2.0
    messages = [str(w.message) for w in caught if "cannot lift" in str(w.message)]
    assert len(messages) == 1 and "M1" in messages[0] and "196 N" in messages[0]


def test_netlist_signals_and_round_trip():
    deck = parse_netlist("* m\n.options ambient=100kPa\nPH s 250kPa\nR1 s a 1\n"
                         "mckibben M1 a L0=200mm D0=12mm theta0=25deg mass=1kg damping=50\n"
                         ".tran 1s\n.meas tran x FIND contraction(M1) AT=1s\n"
                         ".meas tran t WHEN contraction(M1)=1cm RISE=1\n"
                         ".save p(a) contraction(M1) force(M1) volume(M1)\n")
    text = print_circuit(deck.circuit)
    assert print_circuit(parse_netlist(text).circuit) == text
    run = run_deck(deck)
    sol = run.results[0][1]
    assert run.measures["x"] == pytest.approx(sol["contraction_M1"][-1])
    assert np.interp(run.measures["t"], sol.t, sol["contraction_M1"]) == pytest.approx(10.0)
    assert {"contraction_M1", "force_M1", "volume_M1"} <= set(sol.signals)
    assert not any(k.startswith("p_M1") for k in sol.signals)
    assert sol.units["contraction_M1"] == "mm" and sol.units["force_M1"] == "N"


def test_fig12_netlist_oscillates_between_the_turning_points(tmp_path):
    """The paper's Fig. 12: the tank pressure cycles between the stationary-branch
    turning points of the valve + R_out subsystem, and the muscle contracts with it."""
    from pathlib import Path

    from pneunet.physics.oscillator_branches import spec_from_circuit, stationary_branches
    from pneunet.design.muscle import muscle_cycle, plot_muscle_run
    from pneunet.netlist import parse_file

    deck = parse_file(Path(__file__).resolve().parents[2] / "netlists" / "fig12_mckibben.pn")
    sol = deck.circuit.tran(50.0)
    branches = stationary_branches(spec_from_circuit(deck.circuit))
    cycle = muscle_cycle(sol, "M1", "tank")
    p, x = cycle.pressure, cycle.contraction
    assert p.kind == "limit_cycle" and p.cycles >= 3
    assert p.p_min == pytest.approx(branches.p_c_min, abs=0.5)
    assert p.p_max == pytest.approx(branches.p_c_max, abs=0.5)
    assert x.kind == "limit_cycle" and x.period_s == pytest.approx(p.period_s, rel=0.01)
    assert cycle.amplitude_mm > 1.0
    # more pressure, more contraction: the two move together
    after = sol.t >= 10.0
    assert np.corrcoef(sol.pressure("tank")[after], sol["contraction_M1"][after])[0, 1] > 0.9
    assert plot_muscle_run(sol, "M1", ("tank", "out"), tmp_path / "f.png").stat().st_size > 10_000


def test_quasi_static_muscle_in_the_oscillator_matches_the_hanging_mass():
    """Without mass and damping (the weight as a preload) the force balance is algebraic
    and is carried across the valve's folds: the same cycle as the 200 g mass."""
    from pathlib import Path

    from pneunet.design.muscle import muscle_cycle
    from pneunet.netlist import parse_netlist

    text = (Path(__file__).resolve().parents[2] / "netlists" / "fig12_mckibben.pn").read_text()
    static = text.replace("mass=200g damping=20N*s/m", "preload={0.2*9.81}N")
    assert "preload" in static
    deck = parse_netlist(static)
    assert deck.circuit.elements["M1"].kind == "mckibben_static"
    quasi = muscle_cycle(deck.circuit.tran(50.0), "M1", "tank")
    hanging = muscle_cycle(parse_netlist(text).circuit.tran(50.0), "M1", "tank")
    assert quasi.pressure.period_s == pytest.approx(hanging.pressure.period_s, rel=2e-3)
    assert quasi.contraction.p_min == pytest.approx(hanging.contraction.p_min, abs=0.05)
    assert quasi.contraction.p_max == pytest.approx(hanging.contraction.p_max, abs=0.05)


def test_a_transient_may_start_from_the_operating_point():
    """start='op' takes the muscle's state (no pressure) from the steady state too."""
    sol = _circuit(250.0, mass=1.0, damping=50.0).tran(0.5, start="op")
    x = sol["contraction_M1"]
    assert x[0] == pytest.approx(L0 - _static_length(150.0, G), rel=1e-6)
    assert np.ptp(x) < 1e-6
