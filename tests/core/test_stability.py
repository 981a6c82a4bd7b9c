"""``.op()`` says whether the circuit settles at its operating point (issue 16, done-when 4)."""
import numpy as np
import pytest

from pneunet.design.paper_circuits import oscillator


def test_the_papers_oscillator_will_not_settle_at_its_operating_point():
    op = oscillator().op()
    assert op.stability.stable is False
    assert op.stability.slowest.real > 0.1  # 1/s: the deviation grows within seconds
    assert "UNSTABLE" in str(op) and "will not settle" in str(op)
    assert repr(op.stability) == ("<Stability UNSTABLE: modes 1, slowest eigenvalue +1.19 1/s; "
                                  ".describe(), .eigenvalues, .slowest>")


def test_growth_rate_equals_the_linearised_papers_equations():
    """The unstable mode from the paper's equations written here (tests/reference_valve):
    tank ODE C·ṗ = √(o² − p²)/R_out − √(p² − 96²)/R_vent with the valve output o
    algebraic (valve flow = R_out flow), C = M·V/(R·T) = 2.3769 mg/kPa for 200 mL at
    293.15 K; λ = (f_p − f_o·g_p/g_o)/C at the operating point (central differences)."""
    import math

    from scipy.optimize import fsolve

    from pneunet.physics.valve_params import PAPER_VALVES
    from reference_valve import flow  # tests/ is on pytest's sys.path

    axi = PAPER_VALVES["axi"].as_dict()
    r_out, r_vent = 2 * axi["Rf"], 3.0
    cap = 28.965e-3 * 200e-6 / (8.314 * 293.15) * 1e9  # mg/kPa

    def g(o, p):  # valve flow − R_out flow into the tank, mg/s
        return flow(496.0, o, p, **axi) - math.sqrt(o * o - p * p) / r_out

    def f(o, p):  # the tank's net inflow, mg/s
        return math.sqrt(o * o - p * p) / r_out - math.sqrt(p * p - 96.0 ** 2) / r_vent

    o, p = fsolve(lambda z: [g(*z), f(*z)], [196.0, 186.0], xtol=1e-13)
    h = 1e-6
    d = {k: ((fn(o + h, p) - fn(o - h, p)) / (2 * h), (fn(o, p + h) - fn(o, p - h)) / (2 * h))
         for k, fn in (("g", g), ("f", f))}
    growth = (d["f"][1] - d["f"][0] * d["g"][1] / d["g"][0]) / cap
    assert growth == pytest.approx(1.1947, abs=1e-3)  # 1/s
    op = oscillator().op()
    assert op.pressures["tank"] == pytest.approx(p, abs=0.01)
    assert op.pressures["out"] == pytest.approx(o, abs=0.01)
    assert op.stability.slowest.real == pytest.approx(growth, rel=1e-3)


def test_with_r_out_zero_it_settles_at_the_rate_the_transient_decays():
    circuit = oscillator(0.0)
    op = circuit.op()
    assert op.stability.stable is True and "stable" in str(op)
    assert all(v.real < 0 for v in op.stability.eigenvalues)
    # the late transient approaches the operating point as exp(λ t)
    sol = circuit.tran(12.0, t_step=0.05)
    gap = np.abs(sol.pressure("tank") - op.pressures["tank"])
    late = (sol.t > 6) & (gap > 1e-3)
    rate = np.polyfit(sol.t[late], np.log(gap[late]), 1)[0]
    assert abs(rate - op.stability.slowest.real) < 0.05 * abs(rate)
