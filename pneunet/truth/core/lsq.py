"""Budgeted least squares through a simulator, in ln-parameters, with the Jacobian's
finite-difference columns evaluated in parallel.

Each residual evaluation is a simulation, so what counts is the number of simulations
and how many run at once: the Jacobian's columns are independent and go to a process
pool (``pool``; 2 workers on a 2-core machine halve the wall time of a Jacobian).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .intervals import NOISE_RATIO, noise_directions


@dataclass
class LsqResult:
    """x (ln-parameters), residual ``fun``, Jacobian ``jac`` at x, simulations used;
    ``on_budget``: LM stopped on its simulation budget (MINPACK status 5)."""

    x: np.ndarray
    fun: np.ndarray
    jac: np.ndarray
    nfev: int
    success: bool
    message: str
    on_budget: bool = False
    #: the Jacobian at x from differences on each parameter's other side, where the
    #: fit computed it (its cliff check), else None
    other_jac: np.ndarray | None = None


class Abandoned(Exception):
    """A fit given up by its ``give_up`` rule (:func:`least_squares_log`) after
    ``nfev`` simulations, at a cost (sum of squares) ``cost`` above the one it had to
    reach."""

    def __init__(self, nfev: int, cost: float):
        super().__init__(f"abandoned after {nfev} simulations")
        self.nfev, self.cost = nfev, cost


def evaluate_many(fun, xs, pool=None) -> list:
    """``[fun(x) for x in xs]``, in ``pool`` (an Executor) when given (the workers'
    solver messages are counted here too)."""
    if pool is None or len(xs) < 2:
        return [fun(x) for x in xs]
    from ...common.solver_messages import pool_map

    return pool_map(pool, fun, xs)


#: fresh starts of LM after it stepped past a bound (each with that parameter held there)
RESTARTS = 2
#: MINPACK's relative step tolerance, applied to ln x shifted by a constant (see
#: :func:`least_squares_log`): small, so that the shift keeps the sums exact
_MINPACK_XTOL = 1e-8
#: LM's first trust radius in ln x (Euclidean over the free parameters): the first step
#: changes the parameters by at most a factor e^0.5 ≈ 1.65 together; LM widens the
#: radius itself after steps that do what its model predicted
FIRST_RADIUS = 0.5


#: LM's default stopping radius in ln x (0.05 % of every parameter)
XTOL = 5e-4
#: a refined fit stops when LM's trust radius falls below this fraction of the smallest
#: linearised standard error (in ln x) of the fit it refines
REFINE_SE = 0.2
#: the smallest stopping radius a refinement uses (ln x)
REFINE_XTOL_MIN = 1e-6


#: a fit with a ``give_up`` cost is abandoned where this many times the pace of its last
#: two steps (the fall of ln cost per step), kept up over the steps its budget has left,
#: would not bring it there
PACE_MARGIN = 10.0


#: fresh starts of LM away from a cliff it stopped beside (:func:`least_squares_log`)
BACKOFFS = 2
#: how far away (ln value, Euclidean) from a cliff such a start is: the 150 mL
#: oscillator's dead-volume fit, stopped beside the end of its oscillation, stopped there
#: again from 0.03 away and reached its truth from 0.1
BACKOFF = 0.1
#: a start away from a cliff whose LM did not converge (its budget ended) replaces the
#: converged fit beside the cliff only below this fraction of its rms: the oscillator of
#: tests/traces/test_refine.py, 0.25 % from the end of its oscillation, ran out of budget
#: from 0.1 away at 0.326 kPa, unrefined, where beside the cliff it was refined to 0.319
BACKOFF_GAIN = 0.9


def least_squares_log(fun, x0, lb, ub, *, max_nfev: int = 40, diff_step: float = 1e-3,
                      pool=None, xtol: float = XTOL, ftol: float = 1e-6,
                      give_up: float | None = None) -> LsqResult:
    """Levenberg–Marquardt (:func:`_levenberg_marquardt`) on ``fun(x)`` (x:
    ln-parameters in [lb, ub]), started again away from a cliff of the cost it
    converged beside.

    ``give_up``: a cost (sum of squares) the fit is of use only below.  Where
    :data:`PACE_MARGIN` times the pace of LM's last two steps, kept up over the steps
    its budget has left, would not bring the cost there, the fit raises
    :class:`Abandoned` (the base model fitted again from the oscillator's polytropic
    fit's values, 40 % off its V: it crept from rms 61 kPa to 55 in 76 + 31 simulations,
    the base fit's 0.94; now abandoned after 9–17).  The Gauss–Newton model's least cost is
    no such guide: an exponential decay started a factor 2 off predicted 10× the cost it
    reached.  A plateau, where the cost hardly moves before it falls, is abandoned
    too: the decay started at the corner of its box, (0.1, 10) for a true (2, 0.7).

    Where LM converges with an ill-conditioned Jacobian (:data:`CHECK_BELOW`; a column
    that crossed a cliff makes it so), the Jacobian is differenced on each parameter's
    other side too (:func:`other_side_jacobian`, ``other_jac`` of the result).  A column
    whose two sides differ more than :data:`CLIFF` times crossed a cliff (an oscillation
    that stops): LM stopped because the cliff blocks its model's step, not at a minimum.
    It starts again :data:`BACKOFF` away from the cliff (each such parameter moved away
    from the side that crossed it), at most :data:`BACKOFFS` times, and the better end
    is kept (an unconverged one only when much better: :data:`BACKOFF_GAIN`).  The
    150 mL oscillator with a hidden 4 mL dead volume, fitted with it from the screen's
    2.9 mL, stopped at 3.2× its noise floor beside the end of its oscillation (R_vent's
    forward column 44× its backward one), the cost falling all the way to the truth;
    from 0.1 away it reached the truth.  ``max_nfev`` covers every start and check."""
    lb, ub = np.asarray(lb, float), np.asarray(ub, float)
    res = _levenberg_marquardt(fun, x0, lb, ub, max_nfev=max_nfev, diff_step=diff_step,
                               pool=pool, xtol=xtol, ftol=ftol, give_up=give_up)
    for attempt in range(BACKOFFS + 1):
        if not res.success or max_nfev - res.nfev < 3 * len(res.x) + 2 \
                or not _ill_conditioned(res.jac):  # a cliff's column would make it so
            break
        other, used = other_side_jacobian(fun, res, lb, ub, diff_step=diff_step, pool=pool)
        res = replace(res, nfev=res.nfev + used, other_jac=other)
        crossed = _cliffs(res.jac, other)
        if not crossed.any() or attempt == BACKOFFS:
            break
        # away from each cliff: against the side that crossed it (res.jac's forward)
        away = -crossed * np.where(res.x + diff_step <= ub, 1.0, -1.0)
        start = np.clip(res.x + BACKOFF * away / np.linalg.norm(away), lb, ub)
        again = _levenberg_marquardt(fun, start, lb, ub, max_nfev=max_nfev - res.nfev,
                                     diff_step=diff_step, pool=pool, xtol=xtol, ftol=ftol)
        used = res.nfev + again.nfev
        cost, cost_again = float(res.fun @ res.fun), float(again.fun @ again.fun)
        if not (cost_again < cost if again.success else cost_again < BACKOFF_GAIN ** 2 * cost):
            return replace(res, nfev=used)
        res = replace(again, nfev=used)
    return res


def _levenberg_marquardt(fun, x0, lb, ub, *, max_nfev: int, diff_step: float, pool,
                         xtol: float, ftol: float, give_up: float | None = None) -> LsqResult:
    """Levenberg–Marquardt on ``fun(x)`` (x: ln-parameters in [lb, ub]) with forward
    differences of step ``diff_step`` (backwards at an upper bound).

    LM knows no bounds: a step past one is clipped, and LM starts again (at most
    :data:`RESTARTS` times) with that parameter held at its bound and the others free.
    ``max_nfev`` caps the simulations, Jacobian columns included; no point is simulated
    twice.  MINPACK caps its calls assuming a Jacobian at each; where it stops on that
    cap with simulations left, LM goes on from its point with them.  The Jacobian
    returned has a column for every parameter.

    LM's trust region is a ball in ln x (every parameter relative to its value): it
    starts at radius :data:`FIRST_RADIUS`, and LM stops when it falls below ``xtol``
    (5e-4: 0.05 % of every parameter; :func:`refine` goes on where the fit's intervals are
    not far wider) or a
    step lowers the cost by less than ``ftol`` relatively.  MINPACK's own rules,
    radius < xtol·‖x‖ and a first radius of 100·‖x‖, depend on the units a parameter
    is written in (ln x = 0 for a value of exactly 1 in its unit) and let the first step
    go to a corner of the box: LM runs on u = ln x + K, a shift that changes no step,
    with K·√n·1e-8 = ``xtol``, and MINPACK's ``factor`` sets the first radius.
    ``give_up``: as in :func:`least_squares_log`."""
    from scipy import optimize

    lb, ub = np.asarray(lb, float), np.asarray(ub, float)
    count = {"n": 0}
    costs = []  # the costs at the points LM took a Jacobian at
    # by point: LM comes back to its best point after a rejected step, scipy asks for f
    # and J at the solution once more, a restart reuses the free parameters' columns
    residuals, columns = {}, {}

    def f(x):
        key = x.tobytes()
        if key not in residuals:
            count["n"] += 1
            residuals[key] = fun(x)
        return residuals[key]

    def jacobian(x, which):
        f0 = f(x)
        steps = np.where(x + diff_step <= ub, diff_step, -diff_step)
        todo = [i for i in which if (x.tobytes(), i) not in columns]
        points = []
        for i in todo:
            xi = x.copy()
            xi[i] += steps[i]
            points.append(xi)
        for i, col in zip(todo, evaluate_many(fun, points, pool)):
            columns[x.tobytes(), i] = (col - f0) / steps[i]
        count["n"] += len(todo)
        jac = np.column_stack([columns[x.tobytes(), i] for i in which])
        if give_up is not None and (not costs or costs[-1][0] != x.tobytes()):
            costs.append((x.tobytes(), float(f0 @ f0)))
            _check_pace([c for _, c in costs], give_up, max_nfev - count["n"], len(which),
                        count["n"])
        return jac

    x = np.clip(np.asarray(x0, float), lb, ub)
    free = np.ones(len(x), bool)
    restarts = 0
    while True:
        idx = np.flatnonzero(free)

        def at(z, base=x.copy(), idx=idx):
            full = base.copy()
            full[idx] = np.clip(z, lb[idx], ub[idx])
            return full

        left = max_nfev - count["n"]
        shift = xtol / (_MINPACK_XTOL * math.sqrt(idx.size))
        u0 = x[idx] + shift
        u, _, _, message, status = optimize.leastsq(
            lambda u: f(at(u - shift)), u0,
            Dfun=lambda u, idx=idx: jacobian(at(u - shift), idx), full_output=True,
            maxfev=max(2, left // (idx.size + 1)), xtol=_MINPACK_XTOL, ftol=ftol,
            factor=FIRST_RADIUS / float(np.linalg.norm(u0)), diag=np.ones(idx.size))
        z = u - shift
        x = at(z)
        # LM walked past a bound, where the clipped residual is flat: hold it there;
        # release a held parameter whose gradient points back into the box
        hold = idx[x[idx] != z]
        if max_nfev - count["n"] < 2 * (len(x) + 1):
            break
        g = jacobian(x, range(len(x))).T @ f(x)
        release = np.flatnonzero(~free & (((x >= ub) & (g > 0)) | ((x <= lb) & (g < 0))))
        if not hold.size and not release.size:
            if status == 5 and max_nfev - count["n"] < left:
                continue  # LM's call cap (a Jacobian per call assumed) left simulations
            break
        restarts += 1
        if restarts > RESTARTS:
            break
        free[hold], free[release] = False, True
        if not free.any():
            break
    return LsqResult(x, np.asarray(f(x)), jacobian(x, range(len(x))), count["n"],
                     1 <= status <= 4, " ".join(str(message).split()), status == 5)


def _check_pace(costs, give_up, left, n_free, nfev) -> None:
    """Raise :class:`Abandoned` where :data:`PACE_MARGIN` × the pace of the last two
    steps (the fall of ln cost per step, over the ``costs`` at LM's Jacobians), over the
    steps ``left`` simulations allow (a Jacobian of ``n_free`` columns each), falls
    short of ``give_up``."""
    cost = costs[-1]
    if len(costs) < 3 or not cost > give_up:
        return
    pace = math.log(costs[-3] / cost) / 2
    if PACE_MARGIN * pace * left / (n_free + 1) < math.log(cost / give_up):
        raise Abandoned(nfev, cost)


def other_side_jacobian(fun, res: LsqResult, lb, ub, *, diff_step: float, pool=None):
    """The Jacobian at ``res.x`` by differences of step ``diff_step`` on the other side
    of each parameter from :func:`least_squares_log`'s (backwards where it stepped
    forwards); a column whose other side leaves the box is ``res.jac``'s.  Returns (J,
    simulations).  ``res.jac`` minus it is the columns' curvature and simulation noise
    (:func:`~pneunet.truth.core.intervals.inverse_normal_matrix`)."""
    x, f0 = res.x, res.fun
    steps = -np.where(x + diff_step <= ub, diff_step, -diff_step)
    inside = (x + steps >= lb) & (x + steps <= ub)
    todo = np.flatnonzero(inside)
    jac = res.jac.copy()
    points = [x + steps * (np.arange(len(x)) == i) for i in todo]
    for i, col in zip(todo, evaluate_many(fun, points, pool)):
        jac[:, i] = (col - f0) / steps[i]
    return jac, len(todo)


def refine(fun, res: LsqResult, lb, ub, *, max_nfev: int, diff_step: float, pool=None,
           xtol: float = XTOL) -> LsqResult | None:
    """``res`` (a converged fit, stopped at trust radius ``xtol``) refined on ``fun``
    (the same residual, perhaps simulated more finely) until its step is below
    :data:`REFINE_SE` × its smallest standard error (linearised, from its Jacobian and
    residual); None when ``xtol`` is already that small.  A long, quiet recording
    determines a parameter to 0.02 %: a fit stopped at a fixed 0.05 % radius ends several
    standard errors from its optimum, and its intervals miss the truth.

    First chord Gauss–Newton steps with the fit's own Jacobian (:func:`chord_steps`: a
    simulation each, no new Jacobian until the step is small); where they do not get
    there, LM from where they stopped (the simulations of both count).  A fit whose
    Jacobian crossed a cliff (``res.other_jac``, :func:`_cliffs`) is left to LM from its
    point: beside a cliff the cost is rough."""
    n, p = res.jac.shape
    s2 = float(res.fun @ res.fun) / max(n - p, 1)
    var = s2 * np.diag(np.linalg.pinv(res.jac.T @ res.jac))
    se = np.sqrt(var[var > 0])
    if not se.size:
        return None
    finer = max(REFINE_SE * float(se.min()), REFINE_XTOL_MIN)
    if not finer < xtol:
        return None
    if res.other_jac is not None and _cliffs(res.jac, res.other_jac).any():
        return least_squares_log(fun, res.x, lb, ub, max_nfev=max_nfev, diff_step=diff_step,
                                 pool=pool, xtol=finer)
    chord = chord_steps(fun, res, lb, ub, finer, diff_step=diff_step, pool=pool)
    if chord.success:
        return chord
    again = least_squares_log(fun, chord.x, lb, ub, max_nfev=max(max_nfev - chord.nfev, 2),
                              diff_step=diff_step, pool=pool, xtol=finer)
    return replace(again, nfev=again.nfev + chord.nfev)


#: chord Gauss–Newton steps a refinement takes before it leaves the rest to LM
CHORD_STEPS = 6
#: the message of a fit refined by chord steps alone
CHORD_MESSAGE = "refined by chord Gauss-Newton steps to below 0.2 standard errors"


def chord_steps(fun, res: LsqResult, lb, ub, radius: float, *, diff_step: float,
                pool=None) -> LsqResult:
    """Gauss–Newton steps on ``fun`` from ``res.x`` with the Jacobian held from step to
    step (one simulation a step), while each lowers the cost, until a step is shorter
    than ``radius`` (ln x, Euclidean) with a Jacobian differenced on ``fun`` itself at
    this point or the one before (forward, backwards at an upper bound; its columns in
    ``pool``); where a step of the held one, first ``res.jac``, is that short, the
    Jacobian is differenced afresh.  A converged fit sits a few standard errors from the
    optimum of a finer simulation, where its Jacobian still points the way: a step or
    two and one Jacobian, where LM spends a Jacobian per step (the oscillator's
    polytropic fit: 21 simulations, now 7).  The result at the last point kept; not
    ``success`` where a step does not lower the cost (a rough cost, where LM's trust
    region does better) or :data:`CHORD_STEPS` do not get there."""
    lb, ub = np.asarray(lb, float), np.asarray(ub, float)
    x, jac = np.array(res.x, float), np.array(res.jac, float)
    r, nfev = np.asarray(fun(x), float), 1
    age = None  # steps since jac was differenced on fun (None: it is res.jac)
    for _ in range(CHORD_STEPS):
        if not np.all(np.isfinite(r)):
            break
        trial = np.clip(x + np.linalg.lstsq(jac, -r, rcond=None)[0], lb, ub)
        if np.linalg.norm(trial - x) < radius:
            if age is not None and age <= 1:
                return LsqResult(x, r, jac, nfev, True, CHORD_MESSAGE)
            jac, used = difference_jacobian(fun, x, r, ub, diff_step=diff_step, pool=pool)
            nfev, age = nfev + used, 0
            continue
        r1 = np.asarray(fun(trial), float)
        nfev += 1
        if not r1 @ r1 < r @ r:  # a failed simulation's residual is large too
            break
        x, r = trial, r1
        age = None if age is None else age + 1
    return LsqResult(x, r, jac, nfev, False, "chord steps stopped short")


def difference_jacobian(fun, x, f0, ub, *, diff_step: float, pool=None):
    """The Jacobian of ``fun`` at ``x`` (residual ``f0`` there) by forward differences of
    step ``diff_step`` (backwards where that would pass ``ub``), its columns evaluated
    in ``pool``.  Returns (J, simulations)."""
    steps = np.where(x + diff_step <= ub, diff_step, -diff_step)
    points = [x + steps * (np.arange(len(x)) == i) for i in range(len(x))]
    cols = evaluate_many(fun, points, pool)
    return np.column_stack([(c - f0) / h for c, h in zip(cols, steps)]), len(x)


#: a fit whose Jacobian's smallest singular value is below this fraction of its largest
#: has its weak directions checked against the Jacobian from the other side
#: (:func:`jacobian_spread`); the paper's oscillator's R_out, R_vent, V: 0.04–0.07
CHECK_BELOW = 1e-2


def jacobian_spread(res, fun, lb, ub, diff_step: float, pool):
    """(Jacobian, its spread, simulations, columns at a cliff) of a fit whose Jacobian is
    ill-conditioned (:data:`CHECK_BELOW`); else (``res.jac``, None, 0, []).

    The spread is J minus the Jacobian from differences on each parameter's other side:
    two Jacobians that disagree along a weak direction show it to be the simulation's
    noise, not the record's information (two tanks charged through two lines, all four
    fitted from pressures alone: only the products R·V are determined, and the forward
    differences alone gave R₁ [1.23, 3.15] for a true 0.5).  A column whose two sides
    differ more than :data:`CLIFF` times crossed a cliff of the cost on its larger side
    (the 44.6 mL oscillator's fit lies 0.25 % in R_vent from where its oscillation
    stops): the smaller side's column is kept, and its spread is unknown (zero)."""
    if not _ill_conditioned(res.jac):
        return res.jac, None, 0, []
    if res.other_jac is not None:  # the fit's own cliff check computed it
        other, simulations = res.other_jac, 0
    else:
        other, simulations = other_side_jacobian(fun, res, lb, ub, diff_step=diff_step,
                                                 pool=pool)
    crossed = _cliffs(res.jac, other)
    spread = res.jac - other
    jac = res.jac.copy()
    jac[:, crossed > 0] = other[:, crossed > 0]
    spread[:, crossed != 0] = 0.0
    return jac, spread, simulations, np.flatnonzero(crossed).tolist()


def _ill_conditioned(jac) -> bool:
    """Whether ``jac``'s smallest singular value is below :data:`CHECK_BELOW` of its
    largest."""
    sv = np.linalg.svd(jac, compute_uv=False)
    return bool(sv.size) and sv[-1] < CHECK_BELOW * sv[0]


#: a Jacobian column whose differences on the two sides of its parameter differ by more
#: than this factor in norm crossed a cliff of the cost on its larger side
CLIFF = 10.0


def _cliffs(jac, other):
    """Per column of two Jacobians (differences on either side of each parameter): +1
    where ``jac``'s is more than :data:`CLIFF` times ``other``'s in norm (its side
    crossed a cliff), −1 where ``other``'s is, else 0."""
    ours, theirs = np.linalg.norm(jac, axis=0), np.linalg.norm(other, axis=0)
    return np.where(ours > CLIFF * theirs, 1, np.where(theirs > CLIFF * ours, -1, 0))


#: steps (ln value along a unit direction), smallest first, of the secants that measure a
#: direction the differences' noise blurs (:func:`secant_checked`)
SECANT_STEPS = (0.01, 0.03, 0.1)
#: the χ² change (cost change over s²) a secant step must bring for its direction to
#: count as resolved: 4, a step of two standard errors
SECANT_CHI2 = 4.0
#: directions with ‖J·v‖ below this many times ‖spread·v‖ are measured by secants: at 1.2×
#: the two close time constants' J·v was noise-inflated 1.7× (their interval 0.57× of the
#: truth's); a noiseless determined direction is at 1/(step × relative curvature), ~90
SECANT_RATIO = 3.0


def secant_checked(fun, res, jac, spread, lb, ub, pool=None):
    """(Jacobian, spread, simulations, the unit directions J was measured along): each
    direction v along which ``jac``·v is within :data:`SECANT_RATIO` of the
    differences' noise (``spread``·v, :func:`~pneunet.truth.core.intervals.
    noise_directions`), weakest first, measured again by a secant of the residual over
    :data:`SECANT_STEPS` until one changes χ² by :data:`SECANT_CHI2` (resolved).  Its
    J·v becomes the secant's and its spread 0; so it does where no step resolves it but
    J·v is above the noise
    (the secant over 0.1 carries 20× less of the simulation's error than a 0.005
    difference); where J·v is within the noise and no step resolves it, the direction
    stays noise (undetermined).

    A difference step of 0.001–0.005 in ln value resolves a kinked cost badly (an
    oscillator's aligned cycles: the 150 mL, R_vent 4.2 oscillator's weakest direction
    had ‖J·v‖ 71 against a spread of 116, and secants of 73 at every step; every
    interval was unbounded), where an exact invariance of the model changes χ² by 0.05
    over 10 % (two tanks' R·V)."""
    if spread is None:
        return jac, spread, 0, []
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    n, p = jac.shape
    s = math.sqrt(float(res.fun @ res.fun) / max(n - p, 1))
    jac, spread = jac.copy(), spread.copy()
    simulations, measured = 0, []
    for k in noise_directions(sv, vt, spread, ratio=SECANT_RATIO):
        v = vt[k]
        above_noise = sv[k] > NOISE_RATIO * float(np.linalg.norm(spread @ v))
        for h in SECANT_STEPS:
            slope, used = _secant(fun, res, v, h, lb, ub, pool)
            simulations += used
            if slope is None:
                break
            resolved = float(np.linalg.norm(slope)) * h >= math.sqrt(SECANT_CHI2) * s
            if resolved or (above_noise and h == SECANT_STEPS[-1]):
                jac += np.outer(slope - jac @ v, v)
                spread -= np.outer(spread @ v, v)
                measured.append(v)
                break
    return jac, spread, simulations, measured


def secant_note(measured, names, diff_step: float) -> str:
    """The intervals' note on the directions :func:`secant_checked` measured (unit
    vectors over ``names``): who moves along each (shares above 0.1)."""
    return "; ".join(
        f"{', '.join(names[i] for i in np.argsort(-np.abs(v)) if abs(v[i]) > 0.1)} "
        "together: measured by secants over 1–10 % in ln value (a difference step of "
        f"{diff_step:.2g} resolves the fit poorly along them)" for v in measured)


def _secant(fun, res, v, h, lb, ub, pool):
    """(dr/dh along the unit direction ``v`` from the residuals at ``res.x`` ± h·v, each
    side shortened to stay inside [lb, ub]; one-sided where a side is under half of h;
    None where both are, simulations)."""
    x = res.x
    reach = []
    for sign in (1.0, -1.0):
        step = sign * h * v
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(step > 0, (ub - x) / step, np.where(step < 0, (lb - x) / step,
                                                               np.inf))
        reach.append(float(min(1.0, room.min())))
    sides = [(sign, t) for sign, t in zip((1.0, -1.0), reach) if t >= 0.5]
    if not sides:
        return None, 0
    outs = evaluate_many(fun, [x + sign * t * h * v for sign, t in sides], pool)
    if len(sides) == 2:
        return (outs[0] - outs[1]) / ((reach[0] + reach[1]) * h), 2
    sign, t = sides[0]
    return sign * (outs[0] - res.fun) / (t * h), 1
