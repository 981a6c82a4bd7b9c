"""Screening a candidate effect: a grid point at which the circuit cannot be simulated
costs one simulation and ranks last, instead of three simulations that each run until
their time budget (a 4 kPa·s/mg supply tube of 0.03 mL makes the valve buzz: 19,000
fold jumps in 20 s)."""
import math

import numpy as np
import pytest

from pneunet.design.circuits import oscillator
from pneunet.engine.circuit import Circuit
from pneunet.common.errors import SolverError
from pneunet.truth.circuits import synthetic_trace
from pneunet.truth.circuits.screen import ScreenTask
from pneunet.truth.circuits.effects import candidates_for

BASE = {"Rout": 1.132, "Rvent": 3.0, "V": 50.0}
NAMES = list(BASE)


def _task(point):
    rec = synthetic_trace(oscillator, BASE, 6.0, dt=0.05, noise=0.3, seed=1, signals=("p_tank",))
    t = rec["time_s"].to_numpy()
    meas = {"p_tank": rec["p_tank_kPa"].to_numpy()}
    data = (t, ["p_tank"], meas, {"p_tank": np.ones(t.size, bool)}, {"p_tank": 1.0}, None)
    eff = next(e for e in candidates_for(oscillator(BASE)) if e.name == "polytropic_volume")
    x = np.log(list(BASE.values()))
    jac = np.ones((t.size, len(NAMES)))
    bounds = (x - 2.0, x + 2.0)
    return ScreenTask(eff, point, NAMES, x, jac, bounds, ((oscillator, {}), {"typical_s": 0.05}),
                       data)


def test_a_point_that_cannot_be_simulated_costs_one_simulation(monkeypatch):
    tran = Circuit.tran

    def refuse_stiff_tanks(circuit, *args, **kwargs):
        if circuit.elements["V1"].params.get("n", 1.0) > 1.2:
            raise SolverError("stand-in for a simulation past its budget", time=0.0)
        return tran(circuit, *args, **kwargs)

    monkeypatch.setattr(Circuit, "tran", refuse_stiff_tanks)
    bad = _task({"n": 1.3})()
    assert bad["rss"] == math.inf and bad["simulations"] == 1
    good = _task({"n": 1.1})()
    assert math.isfinite(good["rss"]) and good["simulations"] >= 2


def test_a_kept_candidates_start_is_moved_by_one_damped_gauss_newton_step():
    """The step that starts a kept candidate's full fit, from base values 2 % off with
    the residual's own Jacobian there: the least-squares step, scaled so that no
    parameter moves more than SCREEN_STEP in ln value, one simulation, a lower
    residual; with the Jacobian's sign flipped the step goes uphill and is not taken."""
    from pneunet.truth.circuits.model import TraceModel, TraceResidual
    from pneunet.truth.circuits.screen import SCREEN_STEP

    task = _task({"n": 1.0})  # the isothermal tank: the record's own model
    fun = TraceResidual(TraceModel(oscillator), NAMES + ["n"], *task.data)
    x_off = np.log(list(BASE.values())) + np.array([0.02, -0.02, 0.02])
    r = fun(np.append(x_off, 0.0))
    h = 1e-4
    jac = np.column_stack([(fun(np.append(x_off + h * e, 0.0)) - r) / h for e in np.eye(3)])
    task.jac = jac
    values, calls = task.step((x_off, r))
    step = np.linalg.solve(jac.T @ jac, -jac.T @ r)
    step *= min(1.0, SCREEN_STEP / np.max(np.abs(step)))
    moved = np.log([values[k] for k in NAMES])
    assert calls == 1 and values["n"] == 1.0
    np.testing.assert_allclose(moved, x_off + step, rtol=0, atol=1e-9)
    r1 = fun(np.append(moved, 0.0))
    assert r1 @ r1 < 0.5 * (r @ r)
    task.jac = -jac
    values, calls = task.step((x_off, r))
    assert calls == 1
    np.testing.assert_allclose(np.log([values[k] for k in NAMES]), x_off, rtol=0, atol=1e-12)


def test_a_point_its_cycle_does_not_recentre_takes_gauss_newton_steps(monkeypatch):
    """A driven circuit has no cycle to re-centre the base parameters on: the point takes
    up to SCREEN_GN damped Gauss–Newton steps with the base fit's Jacobian (one
    simulation each, kept while they lower the residual) before its merit is taken; a
    point its cycle did re-centre takes none."""
    from pneunet.truth.circuits.model import TraceModel, TraceResidual
    from pneunet.truth.circuits.screen import SCREEN_GN

    task = _task({"n": 1.0})
    fun = TraceResidual(TraceModel(oscillator), NAMES + ["n"], *task.data)
    x_off = np.log(list(BASE.values())) + np.array([0.03, -0.03, 0.03])
    r0 = fun(np.append(x_off, 0.0))
    h = 1e-4
    task.jac = np.column_stack([(fun(np.append(x_off + h * e, 0.0)) - r0) / h
                                for e in np.eye(3)])
    task.x_base = x_off
    monkeypatch.setattr(ScreenTask, "_recentred", lambda self, model, names, theta:
                        (self.x_base, False))
    out = task()
    assert out["simulations"] == 1 + SCREEN_GN
    moved = np.log([out["x"][k] for k in NAMES])
    truth = np.log(list(BASE.values()))
    assert np.max(np.abs(moved - truth)) < 0.6 * np.max(np.abs(x_off - truth))  # towards it
    assert out["at"][1] @ out["at"][1] < 0.1 * (r0 @ r0)
    monkeypatch.setattr(ScreenTask, "_recentred", lambda self, model, names, theta:
                        (self.x_base, True))
    out = task()
    assert out["simulations"] == 1
    np.testing.assert_allclose(np.log([out["x"][k] for k in NAMES]), x_off, atol=1e-12)


def test_the_screen_zooms_in_on_a_valley_narrower_than_its_grid(monkeypatch):
    """A dead volume's grid is five points a factor 8.3 apart (1 mL, 8.3 mL, …); a
    stand-in merit with a narrow valley at 3.36 mL, steeper towards larger volumes (as
    the oscillator's at 50 Hz): the grid alone picks 1 mL, the zoom (spacing halved three
    rounds, two points a round) ends within a factor 1.2 of the valley (its last round's
    points are a factor 1.3 apart), every point
    inside the range, each one simulation counted."""
    from pneunet.truth.circuits import screen
    from pneunet.truth.circuits.effects import DeadVolume

    def merit(task):
        u = math.log(task.point["V_dead@out"] / 3.36)
        return {"x": dict(task.point), "rss": 500.0 + 3000.0 * u * u * (4.0 if u > 0 else 1.0),
                "simulations": 1}

    monkeypatch.setattr(ScreenTask, "__call__", merit)
    eff = DeadVolume("out")
    args = (["Rvent"], np.zeros(1), np.ones((3, 1)), {"Rvent": (3.0, 0.5, 20.0)}, None, None,
            None)
    row = screen.screen_candidates([eff], *args)[0]
    assert row["x"]["V_dead@out"] == pytest.approx(1.0)
    screen.zoom_rows([row], None)
    assert abs(math.log(row["x"]["V_dead@out"] / 3.36)) < math.log(1.2)
    assert row["task"].point == row["x"]
    assert row["simulations"] == 5 + 3 * 2
    # at the edge of its range a parameter's zoom stays inside it
    lo, hi = eff.params["V_dead@out"][1:]
    pts = screen.zoom_points(eff, {"V_dead@out": hi}, {"V_dead@out": 0.3})
    assert [p["V_dead@out"] for p in pts] == [pytest.approx(hi * math.exp(-0.3))]


def test_a_second_start_is_the_anchored_screens_grid_point_not_zoomed(monkeypatch):
    """The second start is another kind of start than the first: the screen anchored at
    the user's guesses, at its best grid point, not zoomed in on (the inverter chain's
    control-line tube reaches the floor only from there).  Stand-in merit as above."""
    from types import SimpleNamespace

    from pneunet.truth.circuits.candidate_fits import CandidateFits
    from pneunet.truth.circuits.effects import DeadVolume

    def merit(task):
        u = math.log(task.point["V_dead@out"] / 3.36)
        return {"x": dict(task.point), "rss": 500.0 + 3000.0 * u * u, "simulations": 1}

    monkeypatch.setattr(ScreenTask, "__call__", merit)
    eff = DeadVolume("out")
    params = {"Rvent": (3.0, 0.5, 20.0)}
    fitting = CandidateFits(None, None, params, None, None, None, None,
                            SimpleNamespace(values={"Rvent": 3.2}), None, {}, "trace", None,
                            0.3, 1.5)
    fitting.screen_setup = (["Rvent"], np.ones((3, 1)), None, None)
    start = fitting.second_start({"effect": eff, "x": {"V_dead@out": 1.0}})
    assert start["V_dead@out"] in [p["V_dead@out"] for p in eff.grid()]
    assert fitting.screen_simulations == len(eff.grid())
