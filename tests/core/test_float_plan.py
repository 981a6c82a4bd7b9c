"""A small circuit is evaluated on Python floats (:mod:`pneunet.engine.float_plan`): its
residual, its Jacobian's data and the fold indicator's algebraic block must be those of
the vectorised path to the bit (the same operations on the same values, summed in the
same order), so that a transient does not depend on which path ran."""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.engine.assembly import CircuitDAE
from pneunet.physics.valve_params import PAPER_VALVES, ValveParams

BACKWARD = ValveParams(Rf=0.9, pclose=60.0, ptrans=150.0, e=1.8, ain=0.7, aout=0.4)


def _oscillator():
    c = Circuit("oscillator", ambient=96.0)
    c.pressure_source("PH", "supply", 496.0)
    c.valve("X1", "supply", "out", "tank", PAPER_VALVES["axi"])
    c.resistor("Rout", "out", "tank", 1.132)
    c.volume("V1", "tank", 200.0)
    c.resistor("Rvent", "tank", "atm", 3.0)
    return c


def _mixed(n=1.3):
    """Two valves (one with backward parameters), a pipe, resistors, a volume (polytropic
    with exponent ``n``) and an isothermal actuator: every float path, both flow
    directions, and nodes fed by three families (their sum's order matters to the last
    bit)."""
    c = Circuit("mixed", ambient=96.0)
    c.pressure_source("PH", "high", 289.0)
    c.pressure_source("PC", "c", 300.0)
    c.valve("Xin", "high", "act", "c", PAPER_VALVES["axi"], backward=BACKWARD)
    c.valve("Xout", "act", "mid", "muscle", PAPER_VALVES["axi"])
    c.pipe("P1", "mid", "atm", 500.0, 2.0)
    c.resistor("Rm", "mid", "atm", 2.0)
    c.resistor("Rt", "act", "muscle", 0.2)
    c.actuator("A1", "muscle", V=30.0, p0=120.0)
    c.volume("V2", "act", 5.0, n=n)
    return c


def _thermal():
    """The oscillator's tank as a thermal chamber fed through two inlets (Simscape's
    constant hA) and an actuator as a thermal volume of constant τ behind a resistor:
    every thermal float path, flows into and out of the chamber, both heat scalings."""
    c = _oscillator()
    del c.elements["V1"]
    c.add("thermal_chamber", "V1", ("tank", "theta"), V=200.0, tau=0.3)
    for line, port in (("Rout", 1), ("Rvent", 0)):
        spec = c.elements[line]
        nodes = list(spec.nodes)
        nodes[port] = f"tank__{line}"
        spec.nodes = tuple(nodes)
        c.add("thermal_inlet", f"I_{line}", (nodes[port], "tank", "theta"))
    c.resistor("Ra", "out", "muscle", 0.5)
    c.add("thermal_volume", "A1", ("muscle", "theta_a"), V=30.0, tau=0.05, scaling=1.0,
          p0=120.0)
    return c


def _vectorised(circuit):
    """The same circuit's DAE evaluated by the vectorised path only."""
    dae = CircuitDAE(circuit)
    dae._floats = None
    return dae


def _mixed_isothermal():
    return _mixed(n=1.0)


@pytest.mark.parametrize("build, ulps", [(_oscillator, 0), (_mixed_isothermal, 0),
                                         (_thermal, 0), (_mixed, 4)])
def test_floats_equal_the_vectorised_path_to_the_bit(build, ulps):
    """Bit for bit, except where a polytropic volume raises its pressure ratio to a power:
    numpy's power on an array runs SIMD code on some processors (AVX-512) that differs
    from the C library's in the last place, so there the two agree within a few units
    of the largest term."""
    def same(a, b):
        if not ulps:
            np.testing.assert_array_equal(a, b)
        else:
            np.testing.assert_allclose(a, b, rtol=0, atol=ulps * np.spacing(np.max(np.abs(b))))

    floats, arrays = CircuitDAE(build()), _vectorised(build())
    assert floats._floats is not None  # the float path is the one under test
    block_f, block_a = floats.algebraic_block(), arrays.algebraic_block()
    assert block_f.floats is not None and block_f.size >= 1
    block_a.floats = None
    rng = np.random.default_rng(7)
    for k in range(200):
        # around zero flow, flow reversal and closed valves; rates of both signs
        y = rng.uniform(96.0, 500.0, floats.n)
        if k % 4 == 0:
            y[:] = y[0]
        yp = rng.normal(0.0, 50.0, floats.n)
        t, cj = float(k), rng.uniform(0.0, 1e3)
        for a, b in zip(floats.evaluate(t, y, yp, cj), arrays.evaluate(t, y, yp, cj)):
            same(a, b)
        same(floats.evaluate(t, y, yp)[0], arrays.evaluate(t, y, yp)[0])
        for residual in (True, False):
            for a, b in zip(block_f.evaluate(t, y, residual), block_a.evaluate(t, y, residual)):
                if a is not None:
                    same(a, b)


def test_a_family_without_a_float_path_keeps_the_circuit_vectorised():
    c = _oscillator()
    c.check_valve("CV", "tank", "atm", 5.0)
    assert CircuitDAE(c)._floats is None


def test_one_node_relaxation_and_indicator_on_floats_equal_the_array_path(monkeypatch):
    """The fold indicator and branch-jump relaxation of a one-node algebraic block run on
    floats (FoldMonitor._relax_one); at the oscillator's own jumps and at random states
    (landings and failures) they give the array path's results to the bit."""
    from pneunet.engine.solvers import folds

    pushed = []
    relax_one = folds.FoldMonitor._relax_one
    monkeypatch.setattr(folds.FoldMonitor, "_relax_one",
                        lambda self, t, y: pushed.append((t, y.copy())) or relax_one(self, t, y))
    sol = _oscillator().tran(8.0)
    assert len(sol.jumps) >= 2 and len(pushed) >= len(sol.jumps)
    dae = CircuitDAE(_oscillator())
    monitor = folds.FoldMonitor(dae, dae.options.fold_threshold)
    assert monitor._one is not None
    rng = np.random.default_rng(5)
    states = pushed + [(1.0, rng.uniform([96.0, 96.0], [496.0, 496.0])) for _ in range(150)]
    outcomes = set()
    for steps in (folds.RELAX_STEPS, 6):  # 6: most relaxations give up (None)
        monkeypatch.setattr(folds, "RELAX_STEPS", steps)
        for t, y in states:
            one, ref = relax_one(monitor, t, y), monitor._relax(t, y)
            outcomes.add(one is None)
            if one is None or ref is None:
                assert one is None and ref is None
            else:
                np.testing.assert_array_equal(one, ref)
    assert outcomes == {True, False}  # landings and failures both compared
    for t, y in states:
        kappa = monitor.indicator(t, y)
        monitor._one = None
        assert kappa == monitor.indicator(t, y)
        monitor._one = dae.algebraic_block().floats


def _divider(low, r):
    """b between a 300 kPa source and ``low`` through two resistors R: one algebraic node."""
    c = Circuit("divider", ambient=96.0)
    c.pressure_source("PH", "high", 300.0)
    c.pressure_source("PL", "low", low)
    c.resistor("R1", "high", "b", r)
    c.resistor("R2", "b", "low", r)
    return c


def _closed():
    """b between two valves held closed: zero residual, every partial zero."""
    c = Circuit("closed", ambient=96.0)
    c.pressure_source("P1", "s", 200.0)
    c.pressure_source("PC", "k", 600.0)
    c.valve("X1", "s", "b", "k", PAPER_VALVES["axi"])
    c.valve("X2", "b", "atm", "k", PAPER_VALVES["axi"])
    return c


@pytest.mark.parametrize("build, starts, lands", [
    (lambda: _divider(300.0, 2.0), [300.0], False),        # at equilibrium: zero residual
    (_closed, [150.0], False),                             # zero residual, scale at its floor
    (lambda: _divider(96.0, 50.0), [120.0, 200.0, 290.0], True)],  # slope below 1
    ids=["equilibrium", "closed", "weak"])
def test_one_node_relaxation_on_floats_at_states_a_transient_does_not_visit(build, starts,
                                                                           lands):
    """The float relaxation equals the array path also where the residual is exactly zero
    (no step goes along the flow, nothing is divided by zero) and on a node whose slope
    J_aa is below 1 mg/(s·kPa) (the landing's stability test is J_aa > 0, not > 1)."""
    from pneunet.engine.solvers import folds

    dae = CircuitDAE(build())
    monitor = folds.FoldMonitor(dae, dae.options.fold_threshold)
    assert dae.n == 1 and monitor._one is not None
    for b in starts:
        y = np.array([b])
        one, ref = monitor._relax_one(1.0, y), monitor._relax(1.0, y)
        assert (one is not None) == (ref is not None) == lands
        if lands:
            np.testing.assert_array_equal(one, ref)
            _, (jac,), _ = monitor._one.lists(1.0, one)
            assert 0.0 < jac < 1.0


def test_the_indicator_of_a_few_algebraic_nodes_on_floats_is_lapacks():
    """A tank with heat exchange has an algebraic node per line into it besides the valve
    output: the fold indicator factorises that small block on Python floats, with the
    pivots LAPACK's dgetrf chooses; at random states (near and at folds too, equal
    pressures) it is the array path's within a few units in the last place."""
    from pneunet.engine.solvers import folds

    dae = CircuitDAE(_thermal())
    monitor = folds.FoldMonitor(dae, dae.options.fold_threshold)
    assert monitor._few is not None and 1 < monitor._block.size <= folds.FEW_ON_FLOATS
    arrays = folds.FoldMonitor(dae, dae.options.fold_threshold)
    arrays._few = None
    rng = np.random.default_rng(11)
    values = []
    for k in range(300):
        y = rng.uniform(96.0, 500.0, dae.n)
        if k % 5 == 0:
            y[:] = y[0]
        a, b = monitor.indicator(float(k), y), arrays.indicator(float(k), y)
        assert a == pytest.approx(b, rel=1e-13, abs=1e-300)
        values.append(b)
    assert min(values) < 0.05 < max(values)  # states near a fold and far from one


@pytest.mark.parametrize("n", [2, 3, 4])
def test_pivots_on_lists_are_lapacks(n):
    """The small LU behind that indicator against LAPACK's dgetrf (partial pivoting) on
    random matrices with rows of very different scales."""
    from scipy.linalg.lapack import dgetrf

    from pneunet.engine.solvers.folds import _pivots_on_lists

    rng = np.random.default_rng(n)
    for _ in range(200):
        a = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
        ours = np.array(_pivots_on_lists(a.tolist()))
        np.testing.assert_allclose(ours, np.diag(dgetrf(a)[0]), rtol=1e-12,
                                   atol=1e-12 * np.abs(a).max())
