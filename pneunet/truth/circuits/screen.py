"""Screening candidate effects cheaply before fitting any fully: each effect at the
points of its parameter grid, the fitted model's parameters re-centred on the recorded
cycle, its residual projected off that fit's Jacobian (two simulations per point, points
in parallel).  Used by
:func:`~pneunet.truth.circuits.diagnosis.diagnose_trace` on the base model, and again on top of
the best single effect when it alone does not reach the noise floor."""
from __future__ import annotations

import math

import numpy as np

from ...common.errors import PneunetError
from ..core.lsq import evaluate_many
from .clock import SHIFT
from .model import TraceModel, TraceResidual
from .start import initial_values


class ScreenTask:
    """One screening point (picklable, runs in a worker): the effect at one point of its
    grid, the base parameters re-centred on the recorded cycle (one simulation).  Its
    merit is the fit-window residual there (one more), projected off the columns of the
    base fit's Jacobian J, ‖(I − J·J⁺)·r‖²: what no small move of the base parameters
    can remove (cycle alignment keeps the residual close to linear in them).  A
    Gauss–Newton step in them before the projection (a third simulation) changed no
    study case's two best (benchmarks/README.md, the screen); it is taken only at the
    best point of a candidate that is fitted fully (:meth:`step`), whose fit it starts
    closer to the right valley."""

    def __init__(self, effect, point, names, x_base, jac, bounds, model_args, data,
                 on_top=()):
        """``x_base``: the fit's ln values of ``names``, and where ``data`` has a clock
        step (a fit of the logger's clock) its shift last (0: the fit's clock), the
        columns of ``jac`` and the ``bounds`` alike."""
        self.effect, self.point, self.names, self.x_base = effect, point, names, x_base
        self.on_top = tuple(on_top)  # effects already in the model (params among names)
        self.jac, self.bounds, self.model_args, self.data = jac, bounds, model_args, data

    def _x(self, xb, theta):
        """The residual's x: the base ln values, the effect's, the clock's shift last."""
        n = len(self.names)
        return np.concatenate([xb[:n], theta, xb[n:]])

    def __call__(self):
        eff = self.effect
        names = self.names + list(eff.params)
        theta = np.log([self.point[k] for k in eff.params])
        model = TraceModel(*self.model_args[0], effects=(*self.on_top, eff),
                           budget=SCREEN_BUDGET, **self.model_args[1])
        fun = TraceResidual(model, names, *self.data)
        xb, moved = self._recentred(model, names, theta)
        if model.failures:  # a point the circuit cannot be simulated at: no more time on it
            return self._failed(model)
        r = fun(self._x(xb, theta))
        if model.failures:
            return self._failed(model)
        for _ in range(0 if moved else SCREEN_GN):
            xb, r, better = self._damped_step(fun, model, xb, r, theta, SCREEN_GN_STEP)
            if not better:
                break
        left = r - self.jac @ np.linalg.lstsq(self.jac, r, rcond=None)[0]
        return {"x": self._values(xb), "rss": float(left @ left), "simulations": model.calls,
                "at": (xb, r)}

    def at_point(self, point: dict) -> "ScreenTask":
        """The same screening task at another ``point`` of the effect's parameters."""
        return ScreenTask(self.effect, point, self.names, self.x_base, self.jac, self.bounds,
                          self.model_args, self.data, self.on_top)

    def step(self, at):
        """The start values after one damped Gauss–Newton step in the base parameters
        from ``at`` = (their ln values, the residual there) with the base fit's
        Jacobian, at most :data:`SCREEN_STEP` in ln value (one simulation; kept where
        it lowers the residual).  Returns (values, simulations)."""
        xb, r = at
        theta = np.log([self.point[k] for k in self.effect.params])
        model = TraceModel(*self.model_args[0], effects=(*self.on_top, self.effect),
                           budget=SCREEN_BUDGET, **self.model_args[1])
        fun = TraceResidual(model, self.names + list(self.effect.params), *self.data)
        xb, _, _ = self._damped_step(fun, model, xb, r, theta, SCREEN_STEP)
        return self._values(xb), model.calls

    def _damped_step(self, fun, model, xb, r, theta, cap):
        """One Gauss–Newton step in the base parameters from ``xb`` (residual ``r``) with
        the base fit's Jacobian, at most ``cap`` in ln value (one simulation): (xb, r,
        True) at the new point where it lowers the residual, else the old and False."""
        step = np.linalg.lstsq(self.jac, -r, rcond=None)[0]
        n = len(self.names)  # the ln values capped at ``cap``, a clock's shift (samples) at
        step *= min(1.0, cap / max(np.max(np.abs(step[:n]), initial=0.0), 1e-300),
                    SCREEN_CLOCK_STEP / max(np.max(np.abs(step[n:]), initial=0.0), 1e-300))
        trial = np.clip(xb + step, *self.bounds)
        r1 = fun(self._x(trial, theta))
        if model.failures or r1 @ r1 >= r @ r:
            return xb, r, False
        return trial, r1, True

    def _values(self, xb):
        """Start values: the base parameters', the point's, a clock's shift (:data:`SHIFT`)."""
        n = len(self.names)
        values = dict(zip(self.names, np.exp(xb[:n])))
        values.update(self.point)
        if len(xb) > n:
            values[SHIFT] = float(xb[n])
        return values


    def _failed(self, model):
        return {"x": self._values(self.x_base), "rss": math.inf, "simulations": model.calls}

    def _recentred(self, model, names, theta):
        """The base parameters moved so the simulated cycle's turning points, rise
        fraction and period match the recording (:func:`~pneunet.truth.circuits.start.
        initial_values`, an oscillator it recognises; else unchanged): an effect that
        changes the period much is judged after the period is matched."""
        times, sigs, meas = self.data[0], self.data[1], self.data[2]
        node = next((s for s in sigs if s.startswith("p_")), None)
        if node is None or len(self.x_base) > len(self.names):  # no cycle: a driven circuit
            return self.x_base, False
        x = np.concatenate([self.x_base, theta])
        lb = np.concatenate([self.bounds[0], theta])
        ub = np.concatenate([self.bounds[1], theta])
        try:
            x, info = initial_values(model, names, x, lb, ub, times, meas[node], node[2:],
                                     iterations=1)
        except PneunetError:
            return self.x_base, False
        if info.get("method") == "none":
            return self.x_base, False
        return x[:len(self.x_base)], True


#: the screen's second and third best are fitted fully when their merits (fit-window
#: residual sums of squares) are within this factor of the best's (rms within 1.5×, the
#: verdict's tolerance); the second best is, whatever its merit, when none of those
#: reaches the floor (a control-line tube's screen merit is 1.5× a dead volume's in rms,
#: and only its full fit reaches the floor)
SCREEN_KEEP = 2.25
#: largest change of a base parameter (ln value) in a kept candidate's start step
SCREEN_STEP = 0.25
#: Gauss–Newton steps in the base parameters (the base fit's Jacobian, one simulation
#: each, at most SCREEN_GN_STEP in ln value) at each screening point of a circuit whose
#: cycle does not re-centre them (a driven one)
SCREEN_GN = 2
SCREEN_GN_STEP = 0.5
#: largest move of a fitted clock in one such step, sample spacings: the base fit's clock
#: takes up some of what a missing effect does (the two tanks' heat exchange, recorded
#: from 1.8 s after the supply's step: 18 ms, 0.9 samples)
SCREEN_CLOCK_STEP = 2.0
#: a screening point's simulation budget, (× the base fit's typical simulation, at
#: least s; CPU time): a point that makes the circuit this much stiffer or chatter (a
#: 4.3 kPa·s/mg tube in the oscillator's supply line: 545 jumps in 21 s) is a failed
#: point, as it would be in a fit, not seconds lost.  An effect may cost several base
#: simulations (the oscillator's heat exchange: 0.25 s against 0.1 s of CPU), and two
#: processes on one core's two hardware threads each get about half of it: at (5, 1 s)
#: every heat-exchange point failed in a loaded test run when it cost 0.4 s
SCREEN_BUDGET = (10.0, 1.0)


def _run_task(task):
    return task()


def _run_step(task_at):
    return task_at[0].step(task_at[1])


def screen_candidates(cand, names, x_base, jac, params, model_args, data, pool, on_top=()):
    """Screen rows, best first: per candidate its best grid point (values with the base
    parameters re-centred, rss after that).  ``names``/``x_base``/``jac``/``params``: the
    fitted model's parameters (ln values, its Jacobian, (guess, low, high) each); with
    ``on_top``, the effects that model already holds (their parameters among ``names``):
    each candidate is screened in addition to them."""
    bounds = (np.log([params[k][1] for k in names]), np.log([params[k][2] for k in names]))
    if data is not None and len(data) > 6:  # the fit's clock: its shift within half a period
        half = 0.5 * model_args[1]["state"].clock_period / data[6]
        x_base, bounds = np.append(x_base, 0.0), (np.append(bounds[0], -half),
                                                  np.append(bounds[1], half))
    tasks = [ScreenTask(e, p, names, x_base, jac, bounds, model_args, data, on_top)
             for e in cand for p in e.grid()]
    outs = evaluate_many(_run_task, tasks, pool)
    rows = []
    for e in cand:
        mine = [(o, t) for t, o in zip(tasks, outs) if t.effect is e]
        best, task = min(mine, key=lambda ot: ot[0]["rss"])
        rows.append(dict(best, effect=e, task=task,
                         simulations=sum(o["simulations"] for o, _ in mine)))
    rows.sort(key=lambda r: r["rss"])
    return rows


#: rounds of zoom around the best screen point of a candidate that is fitted fully
#: (:func:`zoom_rows`, the spacing halved each round): the grid is coarse (a dead
#: volume's five points over 4.6 decades, a factor 8.3 apart) where a valley can be
#: narrow (the oscillator's 3.4 mL dead volume at 50 Hz: merit 480 at the truth, 2,460
#: at the grid's 1 mL, 562,751 at its 8.3 mL, 374 at the zoom's 2.9 mL; from 1 mL the
#: fit ran out of its budget at 1.95× the noise floor and a second start was needed,
#: from 2.9 mL it reached the floor: 404 simulations in all, not 450; at 100 Hz 724,
#: not 982)
ZOOM_ROUNDS = 3


def zoom_points(effect, centre: dict, steps: dict) -> list[dict]:
    """The points ``steps`` (ln value, per parameter) either side of ``centre`` along
    each of ``effect``'s parameters, inside its range."""
    out = []
    for k, (_, lo, hi) in effect.params.items():
        for sign in (-1.0, 1.0):
            v = centre[k] * math.exp(sign * steps[k])
            if lo <= v <= hi:
                out.append({**centre, k: v})
    return out


def zoom_rows(rows, pool) -> None:
    """Each screen row's best point refined in place: :data:`ZOOM_ROUNDS` rounds, each
    screening the points half the last spacing either side of the best along every
    effect parameter (:func:`zoom_points`; the first round's spacing is the grid's) and
    keeping a better one; points of all rows in parallel.  Rows that failed everywhere
    are left as they are."""
    todo = [r for r in rows if math.isfinite(r["rss"]) and "task" in r]
    steps = [r["effect"].grid_steps() for r in todo]
    for _ in range(ZOOM_ROUNDS):
        steps = [{k: h / 2 for k, h in st.items()} for st in steps]
        tasks = [(row, row["task"].at_point(p)) for row, st in zip(todo, steps)
                 for p in zoom_points(row["effect"], row["task"].point, st)]
        for (row, task), out in zip(tasks, evaluate_many(_run_task, [t for _, t in tasks],
                                                        pool)):
            row["simulations"] += out["simulations"]
            if out["rss"] < row["rss"]:
                row.update({k: v for k, v in out.items() if k != "simulations"}, task=task)


def step_starts(rows, pool) -> None:
    """Move the start values (``x``) of the screen ``rows`` that will be fitted fully:
    their best points zoomed in on (:func:`zoom_rows`), then one Gauss–Newton step each
    (:meth:`ScreenTask.step`, in parallel); rows that failed everywhere are left as
    they are."""
    zoom_rows(rows, pool)
    todo = [r for r in rows if math.isfinite(r["rss"]) and "at" in r]
    for row, (values, calls) in zip(todo, evaluate_many(
            _run_step, [(r["task"], r.pop("at")) for r in todo], pool)):
        row["x"], row["simulations"] = values, row["simulations"] + calls
