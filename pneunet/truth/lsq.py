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


def least_squares_log(fun, x0, lb, ub, *, max_nfev: int = 40, diff_step: float = 1e-3,
                      pool=None, xtol: float = 1e-5, ftol: float = 1e-6) -> LsqResult:
    """Levenberg–Marquardt on ``fun(x)`` (x: ln-parameters, kept in [lb, ub] by clipping)
    with forward differences of step ``diff_step`` (backwards at an upper bound).

    ``max_nfev`` caps the simulations, Jacobian columns included."""
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
    res = optimize.least_squares(f, np.clip(x0, lb, ub), jac=jac, method="lm",
                                 max_nfev=max(2, max_nfev // (p + 1)), xtol=xtol, ftol=ftol)
    x = np.clip(res.x, lb, ub)
    return LsqResult(x, np.asarray(res.fun), np.asarray(res.jac), count["n"], bool(res.success),
                     str(res.message))
