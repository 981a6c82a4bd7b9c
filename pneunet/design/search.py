"""Design search: parameter values inside given ranges that meet a specification.

Two stages, both on the sweep machinery (one process pool):

1. a Latin hypercube of ``n_start`` points over the box, uniform in log of every
   parameter, evaluated in parallel;
2. from the best of them, bounded least squares (``scipy.optimize.least_squares``, trust
   region reflective) in log parameters on the targets' residuals (in units of their
   tolerance, :meth:`~pneunet.design.spec.Target.residual`); its Jacobian is a batch of
   forward differences (``step`` in log) simulated in parallel.  If the result misses,
   the next best start is tried (``tries`` in all).

A point that cannot be measured (no oscillation, failed simulation) has residual
:data:`PENALTY` per target.  When no point meets the targets the result is the closest
design (least squares) with each target's miss and the parameters that limit it: at a
bound of their range with the cost's gradient pointing out of the box.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..common.reprs import Summarized, listed
from .problem import Problem
from .spec import Range, make_range, parse_range, require_whole

PENALTY = 30.0


@dataclass(repr=False)
class DesignResult(Summarized):
    """``values`` (chosen parameters), ``metrics`` (achieved, by target key),
    ``targets`` (per target: value, tolerance, achieved, miss, met), ``met``,
    ``limiting`` (parameters at a bound that stops the search; empty when met),
    simulation counts and wall time (s)."""

    values: dict
    metrics: dict
    targets: list
    met: bool
    limiting: list
    ranges: dict
    simulations: int
    failed_simulations: int
    starts: int
    wall_time_s: float

    def _summary(self):
        rows = [("values", listed(f"{k}={v:.4g}" for k, v in self.values.items())),
                ("met", str(self.met)), ("simulations", str(self.simulations)),
                ("wall time", f"{self.wall_time_s:.3g} s")]
        if self.limiting:
            rows.append(("limited by", listed(f"{d['parameter']} at its {d['bound']} bound"
                                              for d in self.limiting)))
        return "", rows, ".values, .metrics, .targets, .to_json()"

    def to_json(self) -> dict:
        return {"values": self.values, "met": self.met, "metrics": _nan_none(self.metrics),
                "targets": [_nan_none(t) for t in self.targets], "limiting": self.limiting,
                "ranges": self.ranges, "simulations": self.simulations,
                "failed_simulations": self.failed_simulations, "starts": self.starts,
                "wall_time_s": round(self.wall_time_s, 3)}

    def report(self) -> str:
        if not self.ranges:
            lines = ["the circuit " + ("meets" if self.met else "misses") + " the targets"]
        else:
            lines = ["design " + ("meets the targets" if self.met else
                                  "cannot meet the targets: the closest design")]
        lines += [f"  {k} = {v:.6g}" for k, v in self.values.items()]
        for t in self.targets:
            ok = "ok" if t["met"] else "not measured (no oscillation?)" if \
                math.isnan(t["miss"]) else f"misses by {t['miss']:.4g} {t['unit']}".rstrip()
            lines.append(f"  {t['target']:<24} achieved {_fmt(t['achieved'])} {t['unit']}"
                         f"  {ok}")
        for d in self.limiting:
            lines.append(f"  limited by {d['parameter']} at its {d['bound']} bound "
                         f"{d['value']:.6g} (widen the range)")
        lines.append(f"  {self.simulations} simulations ({self.failed_simulations} failed), "
                     f"{self.wall_time_s:.1f} s")
        return "\n".join(lines)


def design(build, ranges, targets=None, *, n_start: int | None = None, tries: int = 2,
           max_nfev: int = 25, step: float = 0.01, seed: int = 0, **options) -> DesignResult:
    """Find values of ``ranges`` ({name: (low, high)}, Ranges or 'NAME=LOW:HIGH') meeting
    ``targets`` (strings of :mod:`~pneunet.design.spec` or Targets) for ``build`` (a
    netlist path, NetlistBuilder, picklable builder, or a :class:`Problem` that holds the
    targets); see the module docstring.  ``n_start``: Latin-hypercube points (default 6
    per parameter, at least 8); ``options``: those of :class:`Problem` (``node``,
    ``t_stop``, ``fixed``, ``workers``, ``executor``, ``progress``)."""
    start_time = time.perf_counter()
    for name, value, at_least in (("n_start (--starts)", n_start or 1, 1), ("tries", tries, 1),
                                  ("max_nfev (--max-evaluations)", max_nfev, 1),
                                  ("seed", seed, 0)):
        require_whole(f"design: {name}", value, at_least)
    ranges = _ranges(ranges)
    problem = build if isinstance(build, Problem) else Problem(build, targets, **options)
    lo = np.log([r.low for r in ranges])
    hi = np.log([r.high for r in ranges])
    names = [r.name for r in ranges]
    problem.check(dict(zip(names, np.exp(0.5 * (lo + hi)))))
    with problem:
        starts = _latin_hypercube(lo, hi, n_start or max(8, 6 * len(ranges)), seed)
        rows = problem.evaluate([_point(names, x) for x in starts])
        costs = [_cost(_residuals(problem, r)) for r in rows]
        order = np.argsort(costs, kind="stable")
        best = None
        for i in order[:tries]:
            x, cost = _least_squares(problem, names, starts[i], lo, hi, max_nfev, step)
            if best is None or cost < best[1]:
                best = (x, cost)
            if problem.met(problem.metrics(problem.evaluate([_point(names, best[0])])[0])):
                break
        x = best[0]
        result = evaluate(problem, _point(names, x), start_time, ranges)
        if not result.met:
            result.limiting = _limiting(problem, ranges, x, lo, hi, step)
    result.starts = len(starts)
    result.wall_time_s = time.perf_counter() - start_time
    return result


def evaluate(problem: Problem, values: dict | None = None, start_time: float | None = None,
             ranges=()) -> DesignResult:
    """The targets at fixed ``values`` (default: the circuit's own), without a search."""
    start_time = start_time or time.perf_counter()
    values = dict(values or {})
    problem.check(values)
    metrics = problem.metrics(problem.evaluate([values])[0])
    return DesignResult(values=values, metrics=metrics,
                        targets=[_target_row(t, metrics[t.key]) for t in problem.targets],
                        met=problem.met(metrics), limiting=[],
                        ranges={r.name: [r.low, r.high] for r in ranges},
                        simulations=problem.simulations, failed_simulations=problem.failed,
                        starts=0, wall_time_s=time.perf_counter() - start_time)


def _ranges(ranges) -> list[Range]:
    from ..common.errors import ParameterError

    if isinstance(ranges, dict):
        out = []
        for name, bounds in ranges.items():
            try:
                low, high = (float(b) for b in bounds)
            except (TypeError, ValueError):
                raise ParameterError(f"range of {name}: {bounds!r} is not (low, high)",
                                     hint="e.g. {'Rout': (0.6, 3.0)}") from None
            out.append(make_range(name, low, high))
    else:
        out = [r if isinstance(r, Range) else parse_range(r) for r in ranges]
    if not out:
        raise ParameterError("no parameter to vary", hint="e.g. --vary Rout=0.6:3")
    names = [r.name for r in out]
    if len(set(names)) != len(names):
        raise ParameterError(f"a parameter is varied twice: {names}")
    return out


def _latin_hypercube(lo, hi, n, seed):
    from scipy.stats import qmc

    u = qmc.LatinHypercube(d=len(lo), seed=seed).random(int(n))
    return lo + (hi - lo) * u


def _point(names, x) -> dict:
    return {k: float(f"{math.exp(v):.12g}") for k, v in zip(names, x)}


def _residuals(problem: Problem, row: dict) -> np.ndarray:
    metrics = problem.metrics(row)
    return np.array([t.residual(metrics[t.key]) if math.isfinite(metrics[t.key]) else PENALTY
                     for t in problem.targets])


def _cost(r) -> float:
    return float(0.5 * np.dot(r, r))


def _jacobian(problem, names, x, lo, hi, step):
    """Forward differences in log parameters, stepping inward at an upper bound; the
    base point and the d stepped points are simulated as one parallel batch."""
    steps = np.where(x + step <= hi, step, -step)
    points = [x] + [x + np.eye(len(x))[j] * steps[j] for j in range(len(x))]
    rows = problem.evaluate([_point(names, p) for p in points])
    r = [_residuals(problem, row) for row in rows]
    return r[0], np.column_stack([(r[j + 1] - r[0]) / steps[j] for j in range(len(x))])


def _least_squares(problem, names, x0, lo, hi, max_nfev, step):
    from scipy.optimize import least_squares

    def fun(x):
        return _residuals(problem, problem.evaluate([_point(names, x)])[0])

    def jac(x):
        return _jacobian(problem, names, x, lo, hi, step)[1]

    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    sol = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf", max_nfev=max_nfev,
                        xtol=1e-4, ftol=1e-6, gtol=1e-8)
    return sol.x, _cost(fun(sol.x))


def _limiting(problem, ranges, x, lo, hi, step) -> list:
    """Parameters at a bound (within 1e-3 in log) whose cost gradient points outward."""
    r, J = _jacobian(problem, [b.name for b in ranges], x, lo, hi, step)
    grad = J.T @ r
    out = []
    for j, b in enumerate(ranges):
        if x[j] - lo[j] < 1e-3 and grad[j] > 0:
            out.append({"parameter": b.name, "bound": "low", "value": b.low})
        elif hi[j] - x[j] < 1e-3 and grad[j] < 0:
            out.append({"parameter": b.name, "bound": "high", "value": b.high})
    return out


def _target_row(t, achieved) -> dict:
    return {"target": t.text, "metric": t.key, "op": t.op, "value": t.value,
            "tolerance": t.tol if t.op == "=" else None, "unit": t.unit,
            "achieved": achieved, "miss": t.miss(achieved), "met": t.met(achieved)}


def _nan_none(d: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in d.items()}


def _fmt(v) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.5g}"
