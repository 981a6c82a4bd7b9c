"""Yield under manufacturing spread: the fraction of circuits that meet every target.

``n`` Monte Carlo samples of a :class:`~pneunet.design.spread.Spread` around the design
values are simulated on the sweep machinery; a sample passes if every target is met (a
failed simulation or an unmeasured metric fails).  The yield p = passed/n is reported
with its Monte Carlo standard error √(p(1−p)/n) and the 95 % Wilson score interval, the
pass fraction of every target, and the sensitivities of each target's metric
(:mod:`~pneunet.design.sensitivity`).

With ``se`` the samples are simulated in batches, in the order drawn, and sampling stops
as soon as the Wilson interval's half-width is at most 1.96·se (the half-width of a
normal 95 % interval with that standard error): the result is that of the first samples
of the full run (the same seed), and ``n`` is then the most samples drawn.  Each batch is
sized from the yield so far to reach the width in one more step (:func:`_next_batch`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

from ..common.reprs import Summarized
from .problem import Problem
from .sensitivity import derivative_effects, most_important, plot_tornado, sensitivities
from .spec import require_whole

#: parameters per metric in the text report
TOP = 3
#: the 95 % normal quantile: the interval's half-width asked for is Z·se
Z = 1.959963984540054
#: samples of the first batch, and at least per later batch, when sampling stops early
FIRST_BATCH, MIN_BATCH = 64, 16


def wilson(passed: int, n: int) -> tuple:
    """The 95 % Wilson score interval of a binomial proportion passed/n (scipy's)."""
    from scipy.stats import binomtest

    ci = binomtest(passed, n).proportion_ci(0.95, method="wilson")
    return (float(ci.low), float(ci.high))


def _half_width(p: float, n: float) -> float:
    """Half-width of the 95 % Wilson interval at a yield p over n samples (closed form)."""
    return Z * math.sqrt(p * (1 - p) / n + Z * Z / (4 * n * n)) / (1 + Z * Z / n)


def _next_batch(passed: int, done: int, se: float, n_max: int) -> int:
    """Samples to simulate next: as many as the yield so far needs to bring the interval's
    half-width down to Z·se (at least MIN_BATCH, at most what is left of n_max)."""
    if done == 0:
        return min(FIRST_BATCH, n_max)
    p, low, high = passed / done, done, n_max
    while low < high:  # the fewest samples whose half-width at p is narrow enough
        mid = (low + high) // 2
        low, high = (low, mid) if _half_width(p, mid) <= Z * se else (mid + 1, high)
    return min(max(low - done, MIN_BATCH), n_max - done)


def _sample(problem: Problem, points: list, se: float | None) -> list:
    """Evaluated rows of ``points`` (all of them, or the first until the interval is
    as narrow as ``se`` asks)."""
    if se is None:
        return problem.evaluate(points)
    rows, passed = [], 0
    while len(rows) < len(points):
        batch = problem.evaluate(points[len(rows):len(rows) +
                                        _next_batch(passed, len(rows), se, len(points))])
        rows += batch
        passed += sum(problem.met(problem.metrics(r)) for r in batch)
        low, high = wilson(passed, len(rows))
        if (high - low) / 2 <= Z * se:
            break
    return rows


@dataclass(repr=False)
class YieldResult(Summarized):
    """``yield_`` (fraction), ``se`` (Monte Carlo standard error), ``interval`` (95 %
    Wilson), ``passed``/``n``, ``per_target`` pass fractions, ``sensitivities`` (table),
    ``most_important`` ({metric: parameter}), ``samples`` (one row per sample: parameters,
    metrics, ``pass``), ``spread`` (described), ``nominal`` (metrics at the design)."""

    yield_: float
    se: float
    interval: tuple
    passed: int
    n: int
    failed_simulations: int
    per_target: dict
    sensitivities: object
    most_important: dict
    samples: object
    spread: dict
    notes: list
    nominal: dict
    units: dict
    seed: int
    simulations: int
    wall_time_s: float
    se_target: float | None = None
    n_max: int | None = None

    def _summary(self):
        rows = [("yield", f"{100 * self.yield_:.1f} % ± {100 * self.se:.1f} % "
                          f"({self.passed} of {self.n})"),
                ("most important", ", ".join(f"{k}: {v}" for k, v in self.most_important.items())),
                ("wall time", f"{self.wall_time_s:.3g} s")]
        return "", rows, ".samples, .sensitivities, .plot_tornado(path), .to_json()"

    @property
    def limiting_parameter(self):
        """(parameter, metric): the most important parameter of the target that fails
        most often (None when every sample passes every target or none was measured)."""
        failing = {k: v for k, v in self.per_target.items() if v < 1 and k in self.most_important}
        if not failing:
            return None
        metric = min(failing, key=failing.get)
        return self.most_important[metric], metric

    def to_json(self) -> dict:
        table = self.sensitivities.astype(object).where(self.sensitivities.notna(), None)
        return {"yield": self.yield_, "se": self.se, "interval95": list(self.interval),
                "passed": self.passed, "n": self.n, "seed": self.seed,
                "failed_simulations": self.failed_simulations, "per_target": self.per_target,
                "most_important": self.most_important,
                "limiting_parameter": self.limiting_parameter and
                dict(zip(("parameter", "metric"), self.limiting_parameter)),
                "spread": self.spread,
                "sensitivities": table.to_dict(orient="records"), "notes": self.notes,
                "se_target": self.se_target, "n_max": self.n_max,
                "simulations": self.simulations, "wall_time_s": round(self.wall_time_s, 3)}

    def report(self) -> str:
        lo, hi = self.interval
        lines = [f"yield {100 * self.yield_:.1f} % ± {100 * self.se:.1f} % (Monte Carlo SE; "
                 f"95 % Wilson {100 * lo:.1f}–{100 * hi:.1f} %): {self.passed} of {self.n} "
                 f"samples meet every target"]
        if self.se_target is not None:
            half, asked = 50 * (hi - lo), 100 * Z * self.se_target
            lines.append(f"  sampling stopped at {self.n} of at most {self.n_max} samples: "
                         f"Wilson half-width {half:.3g} % ≤ {asked:.3g} % (--yield-se "
                         f"{self.se_target:g})" if half <= asked else
                         f"  all {self.n_max} samples drawn: the Wilson half-width "
                         f"{half:.3g} % is wider than the {asked:.3g} % asked (--yield-se "
                         f"{self.se_target:g}; draw more with --yield)")
        lines += [f"  {k:<24} {100 * v:.1f} % pass" for k, v in self.per_target.items()]
        if self.failed_simulations:
            lines.append(f"  {self.failed_simulations} simulations failed (counted as misses)")
        lines.append("sensitivities (effect of one SD; share of the metric's variance; "
                     f"at most {TOP} parameters per metric, all in the JSON):")
        table = self.sensitivities.assign(order=-self.sensitivities["share"].fillna(0))
        top = table.sort_values(["order"], kind="stable").groupby("metric", sort=False).head(TOP)
        wm = max(map(len, table["metric"]), default=0)
        wp = max(map(len, table["parameter"]), default=0)
        for row in top.loc[table.index.intersection(top.index)].itertuples():
            effect = "n/a (too few samples)" if math.isnan(row.effect) else \
                f"{row.effect:+.4g} {self.units.get(row.metric, '')}  share {row.share:.0%}"
            if hasattr(row, "effect_fd"):
                effect += f"  (derivative: {row.effect_fd:+.4g})"
            lines.append(f"  {row.metric:<{wm}}  {row.parameter:<{wp}}  SD {row.sd:<9.4g} "
                         f"effect {effect}")
        lines += [f"  most important for {k}: {v}" for k, v in self.most_important.items()]
        if self.limiting_parameter:
            name, metric = self.limiting_parameter
            lines.append(f"the yield is limited most by the spread of {name} (through "
                         f"{metric}, the target missed most often)")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def plot_tornado(self, path=None):
        return plot_tornado(self.sensitivities, self.nominal, self.units, path)


def yield_analysis(problem: Problem, values: dict, spread, n: int = 1000, seed: int = 0,
                   nominal: dict | None = None, derivatives: bool = False,
                   se: float | None = None) -> YieldResult:
    """Monte Carlo yield of the design ``values`` under ``spread`` (module docstring);
    ``problem`` runs the simulations (use it as a context manager for one pool);
    ``nominal`` the metrics at the design (simulated if not given); ``derivatives``: add
    the central-difference effects (column ``effect_fd``, 2 simulations per parameter);
    ``se``: the standard error asked (a fraction, 0 < se < 0.5): stop once the Wilson
    interval's half-width is at most 1.96·se, ``n`` being the most samples (None: all n)."""
    import pandas as pd

    require_whole("yield: the number of samples (--yield)", n, 1)
    require_whole("yield: seed", seed, 0)
    if se is not None and not (isinstance(se, (int, float)) and 0 < se < 0.5):
        from ..common.errors import ParameterError

        raise ParameterError(f"yield: the standard error asked (--yield-se) must be a "
                             f"fraction between 0 and 0.5, got {se!r}",
                             hint="e.g. 0.02 for a yield known to about ±2 % (±3.9 % at 95 %)")
    start, sims = time.perf_counter(), problem.simulations
    if nominal is None:
        nominal = problem.metrics(problem.evaluate([dict(values)])[0])
    n_max = n
    points = [dict(values, **s) for s in spread.sample(n, seed)]
    rows = _sample(problem, points, se)
    n = len(rows)  # the table pairs the first n points with their rows
    table = pd.DataFrame([dict(p, **problem.metrics(r), error=r.get("error"))
                          for p, r in zip(points, rows)])
    keys = [t.key for t in problem.targets]
    ok = {t.key: table[t.key].map(t.met) for t in problem.targets}
    table["pass"] = pd.concat(ok, axis=1).all(axis=1)
    passed = int(table["pass"].sum())
    p = passed / n
    sens = sensitivities(table, {k: spread.sd(k) for k in spread.names}, keys)
    if derivatives:
        fd = derivative_effects(problem, values, spread)
        sens["effect_fd"] = [fd[m, k] for m, k in zip(sens["metric"], sens["parameter"])]
    return YieldResult(yield_=p, se=math.sqrt(p * (1 - p) / n), interval=wilson(passed, n),
                       passed=passed, n=n, failed_simulations=int(table["error"].notna().sum()),
                       per_target={k: float(v.mean()) for k, v in ok.items()},
                       sensitivities=sens, most_important=most_important(sens),
                       samples=table, spread=spread.describe(), notes=list(spread.notes),
                       nominal=nominal, units={t.key: t.unit for t in problem.targets},
                       seed=seed, simulations=problem.simulations - sims,
                       wall_time_s=time.perf_counter() - start, se_target=se, n_max=n_max)
