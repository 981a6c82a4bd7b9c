"""Budgeted least squares through a simulator, in ln-parameters, with the Jacobian's
finite-difference columns evaluated in parallel.

Each residual evaluation is a simulation, so what counts is the number of simulations
and how many run at once: the Jacobian's columns are independent and go to a process
pool (``pool``; 2 workers on a 2-core machine halve the wall time of a Jacobian).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class LsqResult:
    """x (ln-parameters), residual ``fun``, Jacobian ``jac`` at x, simulations used."""

    x: np.ndarray
    fun: np.ndarray
    jac: np.ndarray
    nfev: int
    success: bool
    message: str


def evaluate_many(fun, xs, pool=None) -> list:
    """``[fun(x) for x in xs]``, in ``pool`` (an Executor) when given."""
    if pool is None or len(xs) < 2:
        return [fun(x) for x in xs]
    return list(pool.map(fun, xs))


#: fresh starts of LM from the bound after it stepped outside the box
RESTARTS = 2


def least_squares_log(fun, x0, lb, ub, *, max_nfev: int = 40, diff_step: float = 1e-3,
                      pool=None, xtol: float = 1e-5, ftol: float = 1e-6) -> LsqResult:
    """Levenberg–Marquardt on ``fun(x)`` (x: ln-parameters, kept in [lb, ub] by clipping)
    with forward differences of step ``diff_step`` (backwards at an upper bound).

    ``max_nfev`` caps the simulations, Jacobian columns included (over the
    :data:`RESTARTS` fresh starts from a bound that LM stepped past)."""
    from scipy import optimize

    lb, ub = np.asarray(lb, float), np.asarray(ub, float)
    count = {"n": 0}
    cache = {}

    def f(x):
        xc = np.clip(x, lb, ub)
        key = xc.tobytes()
        if key not in cache:
            count["n"] += 1
            cache.clear()
            cache[key] = fun(xc)
        return cache[key]

    def jac(x):
        xc = np.clip(x, lb, ub)
        f0 = f(x)
        steps = np.where(xc + diff_step <= ub, diff_step, -diff_step)
        pts = []
        for i in range(len(xc)):
            xi = xc.copy()
            xi[i] += steps[i]
            pts.append(xi)
        cols = evaluate_many(fun, pts, pool)
        count["n"] += len(pts)
        return np.column_stack([(c - f0) / h for c, h in zip(cols, steps)])

    p = len(x0)
    x = np.clip(x0, lb, ub)
    for _ in range(1 + RESTARTS):
        left = max_nfev - count["n"]
        res = optimize.least_squares(f, x, jac=jac, method="lm",
                                     max_nfev=max(2, left // (p + 1)), xtol=xtol, ftol=ftol)
        x = np.clip(res.x, lb, ub)
        # LM walked past a bound, where the clipped residual is flat and its damping
        # grows without progress: start again from the bound with fresh damping
        if np.array_equal(x, res.x) or max_nfev - count["n"] < 2 * (p + 1):
            break
    return LsqResult(x, np.asarray(res.fun), np.asarray(res.jac), count["n"], bool(res.success),
                     str(res.message))
