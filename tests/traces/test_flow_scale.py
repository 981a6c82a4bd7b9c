"""A circuit of quadrature lines and isothermal volumes recorded by its pressures alone
cannot tell its resistances from its volumes: every R ×k with every V ÷k leaves every
pressure as it was (dp/dt = √(p_a² − p_b²)/(R·C)).  Two tanks charged and vented through
two lines by a supply step, all four fitted: the forward-difference Jacobian's weakest
direction held only the simulator's error over the step (its singular value 3e-4 of the
largest, above the round-off threshold), and the fit reported R₁ 1.97 [1.23, 3.15] and
V₁ 12.8 [7.97, 20.4] mL for a true 0.5 and 50 mL.  Now the Jacobian from the other side
shows that direction to be noise: the four intervals are unbounded, with a note that
says to fix one.  With the volumes given, the lines' intervals cover the truth.

The recording comes from the equations below (scipy's Radau), not from pneunet."""
import numpy as np
import pandas as pd
import pytest
from scipy.integrate import solve_ivp

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import fit_trace

NETLIST = """* two tanks charged and vented through quadrature lines by a supply step
.options ambient=96kPa
.param R1=0.5 R2=2 V1=50 V2=100
PS supply PWL(0 96kPa 2 96kPa 2.02 296kPa 12 296kPa 12.02 96kPa)
R1 supply t1 {R1}
Vone t1 {V1}mL
R2 t1 t2 {R2}
Vtwo t2 {V2}mL
.tran 10ms 24s
"""
TRUTH = {"R1": 0.5, "R2": 2.0, "V1": 50.0, "V2": 100.0}


def record(start=1.1, seconds=18.0, dt=0.02, noise=0.3, seed=0):
    """p_t1, p_t2 from ``start`` s on the supply's clock, the logger's clock from 0."""
    def C(V):  # isothermal capacitance of air at 293.15 K, mg/kPa
        return 28.965 * V / (8.314462618 * 293.15)

    def line(a, b, R):  # quadrature law, 1 kPa² band
        d = a * a - b * b
        return d / (d * d + 1.0) ** 0.25 / R

    def supply(t):
        return float(np.interp(t, [0, 2, 2.02, 12, 12.02], [96, 96, 296, 296, 96]))

    def rhs(t, y):
        q1, q2 = line(supply(t), y[0], TRUTH["R1"]), line(y[0], y[1], TRUTH["R2"])
        return [(q1 - q2) / C(TRUTH["V1"]), q2 / C(TRUTH["V2"])]

    t = start + dt * np.arange(int(round(seconds / dt)))
    sol = solve_ivp(rhs, (0.0, t[-1]), [96.0, 96.0], method="Radau", t_eval=t, rtol=1e-9,
                    atol=1e-9, max_step=0.01)
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"time_s": t - start,
                         "p_t1_kPa": sol.y[0] + noise * rng.standard_normal(t.size),
                         "p_t2_kPa": sol.y[1] + noise * rng.standard_normal(t.size)})


@pytest.fixture(scope="module")
def tanks(tmp_path_factory):
    path = tmp_path_factory.mktemp("tanks") / "tanks.pn"
    path.write_text(NETLIST)
    return NetlistBuilder(str(path)), record()


def test_resistances_and_volumes_fitted_together_are_undetermined(tanks):
    build, rec = tanks
    fit = fit_trace(build, rec, {"R1": (0.7, 0.05, 5.0), "R2": (1.5, 0.1, 20.0),
                                 "V1": (40.0, 5.0, 500.0), "V2": (130.0, 5.0, 500.0)},
                    node="t2")
    for name in TRUTH:
        assert fit.ci[name] == (0.0, np.inf), name
    (direction,) = fit.extras["intervals"]["undetermined"]
    assert sorted(direction["parameters"]) == sorted(TRUTH)
    assert "fix one of them" in fit.extras["intervals"]["note"]
    assert fit.success or "fix one of the parameters" in fit.unconverged()
    assert fit.rmse["p_t1"] < 0.33 and fit.rmse["p_t2"] < 0.33  # the fit itself is good


def test_with_the_volumes_given_the_lines_are_determined(tanks):
    build, rec = tanks
    fit = fit_trace(build, rec, {"R1": (0.7, 0.05, 5.0), "R2": (1.5, 0.1, 20.0)},
                    fixed={"V1": 50.0, "V2": 100.0}, node="t2")
    assert "undetermined" not in fit.extras["intervals"]
    for name in ("R1", "R2"):
        lo, hi = fit.ci[name]
        assert lo < TRUTH[name] < hi and hi / lo < 1.2, (name, fit.ci[name])
