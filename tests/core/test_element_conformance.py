"""Every element family passes the same checks (issue 2, item 5).

For each registered family: a trivial circuit using it is assembled; the
residual has one entry per unknown node; the analytic Jacobian (∂F/∂y + cj ∂F/∂ẏ)
matches central finite differences; the fast flows (no partials, batched over
time) equal the flows returned with partials; the circuit reaches the steady state its
physics dictates; an invalid parameter raises a ParameterError naming the element.
A family added to the registry without an entry here fails the test.
"""
import numpy as np
import pytest

from pneunet import Circuit, ParameterError
from pneunet.engine.assembly import CircuitDAE
from pneunet.physics.elements import known_kinds
from pneunet.physics.waveforms import Step


def _pressure_source():
    c = Circuit("psource", ambient=100.0)
    c.pressure_source("P1", "a", Step(200.0, 300.0, at=1.0))
    c.resistor("R1", "a", "b", R=1.0)
    c.volume("V1", "b", V=50.0, p0=200.0)
    return c, {"b": 300.0}, dict(kind="pressure_source", nodes=("a",), value=-5.0)


def _flow_source():
    c = Circuit("fsource", ambient=100.0)
    c.flow_source("F1", "atm", "b", 50.0)
    c.resistor("R1", "b", "atm", R=2.0)
    c.volume("V1", "b", V=20.0)
    # steady state: 50 = sqrt(p² − 100²)/2
    return c, {"b": np.sqrt(100.0 ** 2 + (50.0 * 2.0) ** 2)}, None


def _resistor():
    c = Circuit("resistor", ambient=100.0)
    c.pressure_source("P1", "a", 400.0)
    c.resistor("R1", "a", "m", R=1.0)
    c.resistor("R2", "m", "atm", R=1.0)
    # equal flows: 400² − m² = m² − 100²
    return c, {"m": np.sqrt((400.0 ** 2 + 100.0 ** 2) / 2)}, dict(kind="resistor",
                                                                   nodes=("a", "b"), R=-1.0)


def _pipe():
    c = Circuit("pipe", ambient=100.0)
    c.pressure_source("P1", "a", 400.0)
    c.pipe("T1", "a", "m", length=500.0, diameter=2.0)
    c.pipe("T2", "m", "atm", length=500.0, diameter=2.0)
    return c, {"m": np.sqrt((400.0 ** 2 + 100.0 ** 2) / 2)}, dict(kind="pipe", nodes=("a", "b"),
                                                                   length=10.0, diameter=0.0)


def _volume():
    c = Circuit("volume", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.volume("V1", "b", V=30.0, n=1.4, p0=150.0)
    return c, {"b": 250.0}, dict(kind="volume", nodes=("b",), V=10.0, n=1.6)


def _actuator():
    c = Circuit("actuator", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.actuator("A1", "b", length=100.0, diameter=20.0)
    return c, {"b": 250.0}, dict(kind="actuator", nodes=("b",), V=-3.0)


def _thermal_volume():
    c = Circuit("thermal", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.add("thermal_volume", "VT1", ("b", "bT"), V=30.0, tau=0.5, p0=150.0)  # constant hA
    c.resistor("R2", "a", "d", R=1.5)
    c.add("thermal_volume", "VT2", ("d", "dT"), V=20.0, tau=2.0, scaling=1.0)  # constant τ
    # at rest: source pressure, and the gas at wall temperature (θ = p_ref)
    return c, {"b": 250.0, "bT": 150.0, "d": 250.0, "dT": 100.0}, dict(
        kind="thermal_volume", nodes=("b", "bT"), V=10.0, tau=-1.0)


def _thermal_chamber():
    c = Circuit("chamber", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "x1", R=1.0)
    c.add("thermal_inlet", "I1", ("x1", "g", "gT"))
    c.add("thermal_inlet", "I2", ("x2", "g", "gT"))
    c.add("thermal_chamber", "VC", ("g", "gT"), V=30.0, tau=0.5)
    c.resistor("R2", "x2", "atm", R=1.0)
    # at rest: equal flows in and out, and the gas at wall temperature (θ = p_ref)
    g = np.sqrt((250.0 ** 2 + 100.0 ** 2) / 2)
    return c, {"g": g, "x1": g, "gT": 100.0}, dict(kind="thermal_inlet",
                                                   nodes=("x", "g", "gT"), r=0.0)


def _valve():
    c = Circuit("valve", ambient=96.0)
    c.pressure_source("P1", "a", 500.0)
    c.pressure_source("PC", "ctrl", 96.0)
    c.valve("X1", "a", "b", "ctrl", model="axi")
    c.resistor("R1", "b", "atm", R=2.0)
    return c, None, dict(kind="valve", nodes=("a", "b", "c"), model="no_such_valve")


def _check_valve():
    c = Circuit("check valve", ambient=100.0)
    c.pressure_source("P1", "a", 400.0)
    c.check_valve("D1", "a", "b", R=1.0, pcrack=10.0, width=5.0)  # fills until it reseats
    c.volume("V1", "b", V=30.0)
    c.check_valve("D2", "c", "a", R=1.0, pcrack=20.0, width=100.0, Rleak=10.0)  # leaks back
    c.volume("V2", "c", V=30.0)
    return c, {"b": 390.0, "c": 400.0}, dict(kind="check_valve", nodes=("a", "b"), R=1.0,
                                            Rleak=0.5)


def _hysteretic_check_valve():
    c = Circuit("hysteretic check valve", ambient=100.0)
    c.pressure_source("P1", "a", 400.0)
    c.hysteretic_check_valve("D1", "a", "b", "s1", R=1.0, pcrack=20.0, preseat=5.0,
                             width=100.0, Rleak=40.0, tau=0.01)
    c.volume("V1", "b", V=10.0)
    c.resistor("R2", "b", "atm", R=1.0)
    # opens and stays open: equal flows through the valve (open, R=1 ‖ leak) and R2
    g = 1.0 + 1 / 40.0
    b = np.sqrt((g ** 2 * 400.0 ** 2 + 100.0 ** 2) / (g ** 2 + 1.0))
    return c, {"b": b, "s1": 200.0}, dict(kind="hysteretic_check_valve", nodes=("a", "b", "s"),
                                          R=1.0, pcrack=5.0, preseat=10.0)


def _accumulator():
    c = Circuit("accumulator", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.accumulator("A1", "b", V0=20.0, k=0.1, p0=150.0)
    return c, {"b": 250.0}, dict(kind="accumulator", nodes=("b",), V0=10.0, k=-0.1)


def _pv_volume():
    c = Circuit("pv_volume", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.pv_volume("A1", "b", table=([100.0, 180.0, 230.0, 300.0], [20.0, 24.0, 31.0, 33.0]))
    return c, {"b": 250.0}, dict(kind="pv_volume", nodes=("b",), table=([100, 200], [20, 10]))


def _pv_volume_state():
    c = Circuit("pv_volume_state", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    # pressure not monotone: volume as state (a balloon), two rising branches through 250 kPa
    c.pv_volume("A1", "b", table=([100.0, 260.0, 200.0, 240.0, 300.0], [1.0, 5.0, 15.0, 25.0,
                                                                        35.0]))
    c.resistor("R2", "a", "d", R=1.0)
    c.pv_volume("A2", "d", table=([110.0, 260.0, 200.0, 300.0], [1.0, 5.0, 15.0, 35.0]),
                V0=25.0)
    return c, {"b": 250.0, "d": 250.0}, None


def _orifice():
    c = Circuit("orifice", ambient=100.0, fluid="water")
    c.pressure_source("P1", "a", 400.0)
    c.orifice("O1", "a", "m", diameter=0.5)
    c.orifice("O2", "m", "atm", diameter=0.5, Cd=0.61)
    c.volume("V1", "m", V=10.0)
    # equal orifices: equal pressure drops
    return c, {"m": 250.0}, dict(kind="orifice", nodes=("a", "b"), diameter=-1.0)


def _laminar_tube():
    c = Circuit("laminar tube", ambient=100.0, fluid="water")
    c.pressure_source("P1", "a", 400.0)
    c.laminar_tube("T1", "a", "m", length=1000.0, diameter=0.5)
    c.laminar_tube("T2", "m", "atm", length=3000.0, diameter=0.5)
    c.accumulator("A1", "m", V0=5.0, k=0.001)
    # conductances 3:1, the drops 1:3
    return c, {"m": 325.0}, dict(kind="laminar_tube", nodes=("a", "b"), length=0.0,
                                 diameter=1.0)


def _tube():
    c = Circuit("tube", ambient=100.0)
    c.pressure_source("P1", "a", 400.0)
    c.tube("T1", "a", "m", length=500.0, diameter=2.0, segments=3, f=0.008)
    c.tube("T2", "m", "atm", length=500.0, diameter=2.0, segments=3, f=0.008)
    c.tube("T3", "a", "d", length=2000.0, diameter=1.0, segments=2)  # laminar/Blasius, dead end
    c.tube("T4", "a", "e", length=900.0, diameter=3.0, roughness=0.01)  # Haaland, dead end
    c.tube("T5", "e", "g", length=900.0, diameter=3.0, volume=0)  # tube_line, to a volume
    c.volume("V5", "g", V=5.0)
    # equal halves in quadrature (eq. 5); the dead ends at the source pressure
    return c, {"m": np.sqrt((400.0 ** 2 + 100.0 ** 2) / 2), "d": 400.0, "T3.1": 400.0,
               "e": 400.0, "g": 400.0}, dict(kind="tube", nodes=("a", "b"), length=10.0, diameter=2.0,
                                 segments=1.5)


def _liquid_check_valve():
    c = Circuit("liquid check valve", ambient=100.0, fluid="water")
    c.pressure_source("P1", "a", 400.0)
    c.check_valve("D1", "a", "m", R=0.01, pcrack=5.0, width=300.0, Rleak=0.1)  # opening
    c.accumulator("A1", "m", V0=5.0, k=0.01)
    c.hysteretic_check_valve("D2", "a", "d", "z", R=0.01, pcrack=5.0, preseat=2.0)
    c.volume("V2", "d", V=5.0)
    c.pv_volume("A3", "m", table=([100.0, 450.0, 350.0, 500.0], [1.0, 5.0, 10.0, 20.0]))
    # no outlet: both fill to the supply pressure (the leak passes the last pcrack)
    return c, {"m": 400.0}, None


def _liquid_tube():
    c = Circuit("liquid tube", ambient=100.0, fluid="water")
    c.pressure_source("P1", "a", 400.0)
    c.tube("T1", "a", "m", length=300.0, diameter=1.0, roughness=0.02, segments=2)
    c.tube("T2", "m", "atm", length=300.0, diameter=1.0, roughness=0.02, segments=2)
    c.tube("T3", "a", "d", length=500.0, diameter=2.0, f=0.01)  # eq. 6's f, dead end
    # equal tubes: equal drops; the dead end at the source pressure
    return c, {"m": 250.0, "d": 400.0}, None


def _mckibben():
    c = Circuit("mckibben", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.add("mckibben", "M1", ("b",), L0=150.0, D0=10.0, theta0=25.0, spring=400.0)  # static
    c.resistor("R2", "a", "d", R=1.0)
    c.add("mckibben", "M2", ("d",), L0=100.0, b=110.0, n=1.5, k_end=1.2, mass=0.2,
          damping=30.0)                                                        # inertial
    c.resistor("R3", "a", "e", R=1.0)
    c.add("mckibben", "M3", ("e",), L0=100.0, D0=10.0, theta0=20.0, damping=20.0,
          preload=5.0)                                                         # damped
    return c, {"b": 250.0, "d": 250.0, "e": 250.0}, dict(kind="mckibben", nodes=("b",),
                                                         L0=100.0, D0=10.0, theta0=60.0)


CASES = {"pressure_source": _pressure_source, "flow_source": _flow_source,
         "resistor": _resistor, "pipe": _pipe, "volume": _volume, "actuator": _actuator,
         "valve": _valve, "thermal_volume": _thermal_volume,
         "thermal_chamber": _thermal_chamber, "thermal_inlet": _thermal_chamber,
         "check_valve": _check_valve, "accumulator": _accumulator, "pv_volume": _pv_volume,
         "orifice": _orifice, "laminar_tube": _laminar_tube,
         "hysteretic_check_valve": _hysteretic_check_valve, "tube": _tube,
         "tube_liquid": _liquid_tube, "check_valve_liquid": _liquid_check_valve,
         "pv_volume_state": _pv_volume_state, "tube_line": _tube,
         "mckibben": _mckibben, "mckibben_static": _mckibben, "mckibben_damped": _mckibben,
         "mckibben_inertial": _mckibben}


def test_every_registered_family_has_a_conformance_case():
    assert set(known_kinds()) <= set(CASES), set(known_kinds()) - set(CASES)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_residual_shape_and_jacobian_match_finite_differences(kind):
    circuit, _, _ = CASES[kind]()
    dae = CircuitDAE(circuit)
    rng = np.random.default_rng(1)
    y = rng.uniform(150.0, 350.0, dae.n)
    ydot = rng.normal(0.0, 50.0, dae.n)
    t, cj = 0.13, 7.0
    res, data = dae.evaluate(t, y, ydot, cj)
    assert res.shape == (dae.n,)
    analytic = dae.csc(data).toarray()
    numeric = np.zeros((dae.n, dae.n))
    h = 1e-4
    for j in range(dae.n):
        e = np.zeros(dae.n)
        e[j] = h
        numeric[:, j] = (dae.evaluate(t, y + e, ydot)[0] - dae.evaluate(t, y - e, ydot)[0]) / (2 * h)
        numeric[:, j] += cj * (dae.evaluate(t, y, ydot + e)[0]
                               - dae.evaluate(t, y, ydot - e)[0]) / (2 * h)
    np.testing.assert_allclose(analytic, numeric, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_fast_flows_equal_outflows_at_one_time_and_over_a_history(kind):
    """``flows`` (no partials; also batched over time) gives exactly ``outflows``' flows."""
    circuit, _, _ = CASES[kind]()
    dae = CircuitDAE(circuit)
    rng = np.random.default_rng(2)
    times = np.array([0.5, 1.2, 3.0])
    states = rng.uniform(150.0, 350.0, (times.size, dae.n))
    history = dae.full_pressures(times, states)
    for block in dae._blocks:
        fam, ports = block.family, block.port_node
        rates = rng.normal(0.0, 50.0, (times.size,) + ports.shape)
        batched = fam.flows(times, history[:, ports], rates)
        for k, t in enumerate(times):
            expected = fam.outflows(t, history[k][ports], rates[k])[0]
            np.testing.assert_allclose(fam.flows(t, history[k][ports], rates[k]), expected,
                                       rtol=1e-13, atol=1e-12)
            np.testing.assert_allclose(batched[k], expected, rtol=1e-13, atol=1e-12)
            np.testing.assert_allclose(history[k], dae.full_pressures(t, states[k]), rtol=0)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_trivial_circuit_reaches_its_steady_state(kind):
    circuit, expected, _ = CASES[kind]()
    if expected is None:  # valve: steady state from the paper's law written in the test
        from scipy.optimize import brentq

        from pneunet.physics.valve_params import PAPER_VALVES
        from reference_valve import flow  # tests/ is on pytest's sys.path

        axi = PAPER_VALVES["axi"].as_dict()
        # valve 500 kPa → b equals resistor b → atm: √(b² − 96²)/2
        b = brentq(lambda b: flow(500.0, b, 96.0, **axi) - np.sqrt(b * b - 96.0 ** 2) / 2.0,
                   96.0 + 1e-9, 500.0, xtol=1e-12)
        op = circuit.op()
        assert op.pressures["b"] == pytest.approx(b, rel=1e-6)
        assert op.flows["X1"] == pytest.approx(flow(500.0, b, 96.0, **axi), rel=1e-6)
        assert op.flows["X1"] == pytest.approx(op.flows["R1"], rel=1e-6)
        return
    sol = circuit.tran(20.0)
    for node, pressure in expected.items():
        assert sol.pressure(node)[-1] == pytest.approx(pressure, rel=1e-3)


@pytest.mark.parametrize("kind", sorted(k for k in CASES if CASES[k]()[2]))
def test_invalid_parameter_names_the_element(kind):
    _, _, bad = CASES[kind]()
    bad = dict(bad)
    from pneunet.physics.elements import family

    c = Circuit(fluid="gas" if "gas" in family(bad["kind"]).fluids else "water")
    with pytest.raises(ParameterError) as err:
        c.add(bad.pop("kind"), "BAD1", bad.pop("nodes"), **bad)
    assert "BAD1" in str(err.value) or "no_such_valve" in str(err.value)
