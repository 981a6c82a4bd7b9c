"""The DAE assembly (pneunet/engine/assembly.py) against the circuit's equations written out
by hand: F_i = Σ of the flows leaving node i, quadrature resistors √(p_a² − p_b²)/R (with
the flow band), volumes C·ṗ with C = M·V/(R_gas·T), a flow source's constant flow; its
Jacobian against central differences of that hand-written residual; the mass matrix, the
consistent rates, the dead volume, the initial state, the sources' flows, the algebraic
block and the merged breakpoints."""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.engine.assembly import AlgebraicBlock, CircuitDAE, distinct_times
from pneunet.physics.gas import AIR, GAS_CONSTANT
from pneunet.physics.waveforms import Step

AMB, BAND, T_K = 96.0, 10.0, 293.15
R1, R2, R3, R4 = 1.0, 2.0, 1.5, 0.7
V1, V2, FLOW = 20.0, 35.0, 50.0


def _circuit(**options):
    """s (source, 200 → 300 kPa at t = 1 s) –R1– a (V1, F1 draws 50 mg/s from a to atm)
    –R2– b (no volume) –R3– atm; a –R4– c (V2, .ic 180 kPa)."""
    c = Circuit("mixed", ambient=AMB, flow_band=BAND, temperature=T_K, **options)
    c.pressure_source("P1", "s", Step(200.0, 300.0, at=1.0))
    c.resistor("R1", "s", "a", R=R1)
    c.volume("V1", "a", V=V1, p0=150.0)
    c.flow_source("F1", "a", "atm", FLOW)
    c.resistor("R2", "a", "b", R=R2)
    c.resistor("R3", "b", "atm", R=R3)
    c.resistor("R4", "a", "c", R=R4)
    c.volume("V2", "c", V=V2, p0=120.0)
    c.set_initial("c", 180.0)
    return c


def _q(pa, pb, r):
    """Quadrature flow a → b with the band: d/(d² + ε²)^¼ / R, d = pa² − pb²."""
    d = pa * pa - pb * pb
    return d / (d * d + BAND * BAND) ** 0.25 / r


def _cap(v):
    return AIR.molar_mass_g_mol * 1e3 * v / (GAS_CONSTANT * 1e3 * T_K)


def _source(t):
    return 200.0 if t < 1.0 else 300.0


def _reference(t, p, pdot, dead=0.0):
    """F at nodes a, b, c (dict of pressures and rates by node name), mg/s."""
    s = _source(t)
    return {"a": _q(p["a"], s, R1) + _cap(V1) * pdot["a"] + FLOW + _q(p["a"], p["b"], R2)
            + _q(p["a"], p["c"], R4),
            "b": _q(p["b"], p["a"], R2) + _q(p["b"], AMB, R3) + _cap(dead) * pdot["b"],
            "c": _q(p["c"], p["a"], R4) + _cap(V2) * pdot["c"]}


def _point(dae, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(120.0, 320.0, dae.n), rng.normal(0.0, 40.0, dae.n)


def _by_name(dae, v):
    return {n: v[dae.node_index(n)] for n in dae.node_names}


def _vector(dae, d):
    return np.array([d[n] for n in dae.node_names])


@pytest.mark.parametrize("t", [0.4, 2.5])
def test_residual_is_the_sum_of_the_flows_leaving_each_node(t):
    dae = CircuitDAE(_circuit())
    assert sorted(dae.node_names) == ["a", "b", "c"] and sorted(dae.fixed_names) == ["atm", "s"]
    y, ydot = _point(dae)
    ref = _vector(dae, _reference(t, _by_name(dae, y), _by_name(dae, ydot)))
    np.testing.assert_allclose(dae.evaluate(t, y, ydot)[0], ref, rtol=1e-12)
    res, data = dae.evaluate(t, y, ydot, cj=5.0)
    np.testing.assert_allclose(res, ref, rtol=1e-12)
    assert data.shape == (dae.nnz,)


@pytest.mark.parametrize("t, cj", [(0.4, 0.0), (2.5, 7.0)])
def test_jacobian_is_the_hand_written_residuals_derivative(t, cj):
    """∂F/∂y + cj·∂F/∂ẏ, as CSC data, dense array and scipy matrix, against central
    differences of the reference residual; the pattern holds exactly the pairs an element
    joins (b and c share no element) and every diagonal."""
    dae = CircuitDAE(_circuit())
    y, ydot = _point(dae, seed=4)
    numeric = np.zeros((dae.n, dae.n))
    h = 1e-5
    for j in range(dae.n):
        e = np.zeros(dae.n)
        e[j] = h

        def f(y_, yd_):
            return _vector(dae, _reference(t, _by_name(dae, y_), _by_name(dae, yd_)))
        numeric[:, j] = (f(y + e, ydot) - f(y - e, ydot)) / (2 * h) \
            + cj * (f(y, ydot + e) - f(y, ydot - e)) / (2 * h)
    data = dae.evaluate(t, y, ydot, cj)[1]
    np.testing.assert_allclose(dae.dense(data), numeric, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(dae.jacobian(t, y, ydot, cj).toarray(), numeric, rtol=1e-6,
                               atol=1e-9)
    if cj == 0.0:  # the default: ∂F/∂y alone
        np.testing.assert_allclose(dae.jacobian(t, y, ydot).toarray(), numeric, rtol=1e-6,
                                   atol=1e-9)
    out = np.full((dae.n, dae.n), 9.0)
    assert dae.dense(data, out) is out and np.array_equal(out, dae.dense(data))
    b, c = dae.node_index("b"), dae.node_index("c")
    pattern = dae.sparsity().toarray()
    expected = np.ones((dae.n, dae.n))
    expected[b, c] = expected[c, b] = 0.0
    np.testing.assert_array_equal(pattern, expected)
    rows, cols = dae.entries()
    assert dae.nnz == len(rows) == 7
    np.testing.assert_array_equal(dae.dense(data)[rows, cols], data)


def test_mass_matrix_capacitance_and_consistent_rates():
    dae = CircuitDAE(_circuit())
    y, _ = _point(dae, seed=5)
    a, b, c = (dae.node_index(n) for n in "abc")
    cap = np.zeros(dae.n)
    cap[a], cap[c] = _cap(V1), _cap(V2)
    np.testing.assert_allclose(dae.capacitance(1.5, y), cap, rtol=1e-12)
    np.testing.assert_allclose(dae.mass_matrix(1.5, y).toarray(), np.diag(cap), rtol=1e-12,
                               atol=1e-15)
    np.testing.assert_array_equal(dae.differential, [n != "b" for n in dae.node_names])
    np.testing.assert_array_equal(dae.algebraic_idx, [b])
    f0 = _reference(1.5, _by_name(dae, y), dict.fromkeys("abc", 0.0))
    ydot = dae.derivative(1.5, y)
    assert ydot[a] == pytest.approx(-f0["a"] / _cap(V1), rel=1e-12)
    assert ydot[c] == pytest.approx(-f0["c"] / _cap(V2), rel=1e-12)
    assert ydot[b] == 0.0


def test_a_dead_volume_goes_to_every_node_without_storage():
    dae = CircuitDAE(_circuit(dead_volume=0.5))
    assert dae.differential.all()
    y, ydot = _point(dae, seed=6)
    ref = _reference(0.3, _by_name(dae, y), _by_name(dae, ydot), dead=0.5)
    np.testing.assert_allclose(dae.evaluate(0.3, y, ydot)[0], _vector(dae, ref), rtol=1e-12)
    assert dae.capacitance(0.3, y)[dae.node_index("b")] == pytest.approx(_cap(0.5), rel=1e-12)
    assert dae.capacitance(0.3, y)[dae.node_index("a")] == pytest.approx(_cap(V1), rel=1e-12)


def test_initial_state_takes_ic_then_p0_then_ambient():
    dae = CircuitDAE(_circuit())
    start = _by_name(dae, dae.initial_state(0.0))
    assert start == {"a": 150.0, "b": AMB, "c": 180.0}


def test_full_pressures_and_the_sources_flows_over_a_history():
    dae = CircuitDAE(_circuit())
    times = np.array([0.2, 0.9, 1.1, 3.0])
    states = np.random.default_rng(7).uniform(120.0, 320.0, (times.size, dae.n))
    full = dae.full_pressures(times, states)
    s, atm = dae.node_index("s"), dae.node_index("atm")
    np.testing.assert_array_equal(full[:, s], [200.0, 200.0, 300.0, 300.0])
    np.testing.assert_array_equal(full[:, atm], AMB)
    np.testing.assert_array_equal(full[:, :dae.n], states)
    assert dae.pinned_sources() == {"P1": "s"}
    a = states[:, dae.node_index("a")]
    np.testing.assert_allclose(dae.source_flows(times, full)["P1"],
                               _q(full[:, s], a, R1), rtol=1e-12)


def test_algebraic_block_is_the_algebraic_rows_of_the_full_system():
    """F_b and ∂F_b/∂p_b at ẏ = 0, dense and sparse, and the row scale |∂q/∂p_b| summed
    over the elements at b."""
    dae = CircuitDAE(_circuit())
    y, _ = _point(dae, seed=8)
    b = dae.node_index("b")
    p = _by_name(dae, y)
    full = dae.dense(dae.evaluate(2.0, y, np.zeros(dae.n), cj=0.0)[1])
    f_b = _reference(2.0, p, dict.fromkeys("abc", 0.0))["b"]
    h = 1e-5
    slopes = [(_q(p["b"] + h, o, r) - _q(p["b"] - h, o, r)) / (2 * h)
              for o, r in ((p["a"], R2), (AMB, R3))]
    for limit in (40, 1, 0):
        block = AlgebraicBlock(dae, dense_limit=limit)
        res, jac, scale = block.evaluate(2.0, y)
        assert isinstance(jac, np.ndarray) == (limit > 0)  # dense up to the limit, else CSC
        jac = jac if isinstance(jac, np.ndarray) else jac.toarray()
        assert res == pytest.approx([f_b], rel=1e-12)
        assert jac.shape == (1, 1) and jac[0, 0] == pytest.approx(full[b, b], rel=1e-12)
        assert jac[0, 0] == pytest.approx(sum(slopes), rel=1e-6)
        assert scale == pytest.approx([sum(abs(s) for s in slopes)], rel=1e-6)


def test_algebraic_block_with_one_fixed_node_and_other_families_first():
    """Only atm is fixed (a flow source drives a); the volume and the flow source, added
    first, have no port at the algebraic node b."""
    c = Circuit("one fixed node", ambient=AMB, flow_band=BAND)
    c.volume("V1", "a", V=V1)
    c.flow_source("F1", "atm", "a", FLOW)
    c.resistor("R2", "a", "b", R=R2)
    c.resistor("R3", "b", "atm", R=R3)
    dae = CircuitDAE(c)
    assert dae.fixed_names == ["atm"] and dae.n == 2
    p = {"a": 260.0, "b": 170.0}
    res, jac, _ = AlgebraicBlock(dae).evaluate(0.0, _vector(dae, p))
    assert res == pytest.approx([_q(170.0, 260.0, R2) + _q(170.0, AMB, R3)], rel=1e-12)
    assert jac.shape == (1, 1)


def test_a_row_without_any_slope_is_scaled_by_the_floor():
    """b between two valves held closed: every partial of its equation is zero; its scale
    is the 1e-300 floor, never 0 (the fold indicator divides by it)."""
    from pneunet.physics.valve_params import PAPER_VALVES

    c = Circuit("closed", ambient=AMB)
    c.pressure_source("P1", "s", 200.0)
    c.pressure_source("PC", "k", 600.0)
    c.valve("X1", "s", "b", "k", PAPER_VALVES["axi"])
    c.valve("X2", "b", "atm", "k", PAPER_VALVES["axi"])
    on_floats, on_arrays = AlgebraicBlock(CircuitDAE(c)), AlgebraicBlock(CircuitDAE(c))
    on_arrays.floats = None
    assert on_floats.floats is not None  # two valves: on floats; both routes floor it
    for block in (on_floats, on_arrays):
        res, jac, scale = block.evaluate(0.0, np.array([150.0]))
        assert res.tolist() == [0.0] and jac.tolist() == [[0.0]] and scale.tolist() == [1e-300]


def test_the_pattern_of_a_chain_is_tridiagonal():
    c = Circuit("chain", ambient=AMB)
    c.pressure_source("P1", "n0", 300.0)
    for k in range(5):
        c.resistor(f"R{k}", f"n{k}", f"n{k + 1}", R=1.0)
        c.volume(f"V{k}", f"n{k + 1}", V=1.0)
    c.resistor("R9", "n5", "atm", R=1.0)
    dae = CircuitDAE(c)
    order = [dae.node_index(f"n{k}") for k in range(1, 6)]
    pattern = dae.sparsity().toarray()[np.ix_(order, order)]
    np.testing.assert_array_equal(pattern, np.eye(5) + np.eye(5, k=1) + np.eye(5, k=-1))


def test_an_algebraic_block_without_algebraic_nodes_is_empty():
    block = AlgebraicBlock(CircuitDAE(_circuit(dead_volume=0.5)))
    res, jac, scale = block.evaluate(0.0, np.full(3, 150.0))
    assert block.size == 0 and res.size == 0 and jac.shape == (0, 0) and scale.size == 0


def test_breakpoints_equal_up_to_rounding_are_one():
    """Merged when 1e-12 relative apart (of the time, at least 1 s) or closer."""
    np.testing.assert_array_equal(distinct_times([np.array([16 + 0.01, 3.0]),
                                                  np.array([2 * 8 + 0.01])]), [3.0, 16.01])
    np.testing.assert_array_equal(distinct_times([np.array([1.0, 1.0 + 1e-9])]),
                                  [1.0, 1.0 + 1e-9])
    np.testing.assert_array_equal(distinct_times([np.array([0.3]), np.array([0.1 * 3])]), [0.3])
    np.testing.assert_array_equal(distinct_times([np.array([1000.0, 1000.0 + 1e-10])]),
                                  [1000.0])
    np.testing.assert_array_equal(distinct_times([np.array([1000.0, 1000.0 + 1e-8])]),
                                  [1000.0, 1000.0 + 1e-8])
    np.testing.assert_array_equal(distinct_times([np.array([3.0, 1000.0, 1000.0 + 1e-10])]),
                                  [3.0, 1000.0])
    np.testing.assert_array_equal(distinct_times([np.array([1.5, 1.5 + 1.8e-12])]),
                                  [1.5, 1.5 + 1.8e-12])  # 1.5e-12 apart at most
    np.testing.assert_array_equal(distinct_times([np.array([1e-3, 1e-3 + 1e-14])]), [1e-3])
    assert distinct_times([]).size == 0
    dae = CircuitDAE(_circuit())
    np.testing.assert_array_equal(dae.jumps(0.0, 5.0), [1.0])


def test_each_source_delivers_the_flow_of_its_own_node():
    """At zero rates of change: volumes on the source nodes store nothing here (and their p0
    and an .ic there do not set a source's pressure); a family with no port at a source (the
    flow source at m, added before the resistors) is passed over, not the end of the sum."""
    c = Circuit("two sources", ambient=AMB, flow_band=BAND)
    c.pressure_source("PA", "s1", 300.0)
    c.pressure_source("PB", "s2", Step(150.0, 250.0, at=1.0))
    c.volume("Vm", "m", V=V1, p0=170.0)
    c.volume("Vs1", "s1", V=V2, p0=400.0)
    c.volume("Vs2", "s2", V=V2, p0=400.0)
    c.flow_source("Fm", "m", "atm", 10.0)
    c.set_initial("s1", 410.0)
    c.set_initial("s2", 420.0)
    c.resistor("R1", "s1", "m", R=R1)
    c.resistor("R2", "s2", "m", R=R2)
    c.resistor("R3", "m", "atm", R=R3)
    dae = CircuitDAE(c)
    times = np.array([0.5, 2.0])
    full = dae.full_pressures(times, np.array([[180.0], [220.0]]))
    flows = dae.source_flows(times, full)
    m = np.array([180.0, 220.0])
    np.testing.assert_allclose(flows["PA"], _q(300.0, m, R1), rtol=1e-12)
    np.testing.assert_allclose(flows["PB"], _q(np.array([150.0, 250.0]), m, R2), rtol=1e-12)
    assert dae.node_names == ["m"] and dae.fixed_names[:2] == ["s1", "s2"]
    assert dae.initial_state(0.0).tolist() == [170.0]


def test_consistent_rates_solve_a_coupled_mass_matrix():
    """A thermal volume's storage couples its pressure and temperature nodes (off-diagonal
    ∂F/∂ẏ): the rates derivative() returns make the differential residuals zero (at a state
    where the residual is linear in ẏ: the gas flows out, at the wall temperature)."""
    c = Circuit("thermal", ambient=AMB)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=1.0)
    c.add("thermal_volume", "VT1", ("b", "bT"), V=30.0, tau=0.5, p0=150.0)
    dae = CircuitDAE(c)
    y = np.array([260.0, 150.0])
    mass = dae.mass_matrix(0.0, y).toarray()
    assert abs(mass[0, 1]) + abs(mass[1, 0]) > 0
    ydot = dae.derivative(0.0, y)
    assert np.abs(ydot).min() > 1.0
    np.testing.assert_allclose(dae.evaluate(0.0, y, ydot)[0], 0.0, atol=1e-9)


@pytest.mark.parametrize("p, theta", [(180.0, 120.0), (260.0, 200.0), (140.0, 200.0),
                                      (260.0, 130.0)])
def test_consistent_rates_of_a_thermal_volume_whichever_way_its_gas_flows(p, theta):
    """derivative() against the thermal volume's equations solved by hand (docstring of
    physics/elements/thermal.py): the resistor's inflow q fixes s = γ·q·T_up/T_w (T_up = T_w
    entering, T leaving), then ṗ = (s + H)/C and θ̇ from the mass balance.  At ẏ = 0 the
    branch of s is that of −H; at (180, 120) (gas below p_ref, filling) and (260, 200)
    (above, emptying) it is not the solution's: one linear solve left −34.7 mg/s."""
    pref, tau, gamma, scaling, v = 150.0, 0.5, 1.4, 1.0, 30.0
    c = Circuit("thermal", ambient=AMB, flow_band=BAND, temperature=T_K)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R1", "a", "b", R=R1)
    c.add("thermal_volume", "VT1", ("b", "bT"), V=v, tau=tau, p0=pref, gamma=gamma,
          scaling=scaling)
    dae = CircuitDAE(c)
    assert dae.node_names == ["b", "bT"]
    cap, q = _cap(v), _q(250.0, p, R1)
    heat = cap * (p / theta) ** scaling * (pref - theta) / tau
    s = gamma * q * (1.0 if q >= 0 else theta / pref)
    pdot = (s + heat) / cap
    thetadot = (pdot - q * theta / (cap * pref)) * theta / p
    y = np.array([p, theta])
    ydot = dae.derivative(0.0, y)
    np.testing.assert_allclose(ydot, [pdot, thetadot], rtol=1e-9)
    np.testing.assert_allclose(dae.evaluate(0.0, y, ydot)[0], 0.0, atol=1e-9)


def test_a_circuit_is_validated_unless_told_not_to():
    from pneunet import TopologyError

    c = _circuit()
    c.resistor("R9", "x", "y", R=1.0)  # x, y: no path to a pressure
    with pytest.raises(TopologyError):
        CircuitDAE(c)
    assert CircuitDAE(c, validate=False).n == 5


def test_an_initial_pressure_on_a_source_node_is_left_to_the_source():
    c = _circuit()
    c.set_initial("s", 250.0)
    assert _by_name(dae := CircuitDAE(c), dae.initial_state(0.0))["a"] == 150.0


def test_element_signals_are_read_only_and_name_no_dead_volume():
    dae = CircuitDAE(_circuit(dead_volume=0.5))
    times = np.array([0.5, 2.0])
    states = np.random.default_rng(9).uniform(120.0, 320.0, (2, dae.n))
    full = dae.full_pressures(times, states)
    groups = dae.element_signal_groups(times, states, lambda: full)
    names = [n for names, _, _ in groups for n in names]
    assert "mdot_R1" in names and not any("_dead_" in n for n in names)
    computed = {k: v for _, _, compute in groups for k, v in compute().items()}
    assert set(computed) == set(names)
    a, s = states[:, dae.node_index("a")], full[:, dae.node_index("s")]
    np.testing.assert_allclose(computed["mdot_R1"], _q(s, a, R1), rtol=1e-12)
    for block in dae._blocks:
        for unit, values in dae.element_signals(block, times, full).values():
            assert values.shape == (2,) and not values.flags.writeable


def test_a_storage_element_with_two_nodes_starts_each_at_its_own_pressure():
    """pv_volume with the volume as state: its node at P(V0) = 200 kPa (a table point), its
    state node at ambient + V0 = 115."""
    c = Circuit("pv", ambient=100.0)
    c.pressure_source("P1", "a", 250.0)
    c.resistor("R2", "a", "d", R=1.0)
    c.pv_volume("A2", "d", table=([110.0, 260.0, 200.0, 300.0], [1.0, 5.0, 15.0, 35.0]),
                V0=15.0)
    dae = CircuitDAE(c)
    assert _by_name(dae, dae.initial_state(0.0)) == {"d": 200.0, "A2.V": 115.0}


def test_instance_corners_name_each_timed_element_once_per_window():
    dae = CircuitDAE(_circuit())
    corners = dae.instance_corners(0.0, 5.0)
    assert sorted(corners) == ["F1", "P1"]  # the sources' waveforms (F1's is constant)
    np.testing.assert_array_equal(corners["P1"][0], [1.0])
    np.testing.assert_array_equal(corners["P1"][1], [1.0])
    assert corners["F1"][0].size == corners["F1"][1].size == 0
    assert dae.instance_corners(0.0, 5.0) is corners  # kept for the window
    assert dae.instance_corners(2.0, 5.0)["P1"][0].size == 0
