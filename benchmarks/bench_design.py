"""Benchmark: design search + yield of the paper's oscillator (issues 13, 35).

    python benchmarks/bench_design.py                     # 2 workers, --yield-se 0.025 against all 1000 samples
    python benchmarks/bench_design.py --samples 100       # quick check
    python benchmarks/bench_design.py --yield-se 0        # only the 1000-sample yield (issue 13)
    python benchmarks/bench_design.py --early-only        # search + early-stopped yield only
    python benchmarks/bench_design.py --whole             # whole transients (no steady cycle)

Searches R_out, R_vent and V of ``netlists/oscillator_design.pn`` for a 3 s period with at
least 130 kPa swing, then the yield of the design under p_close ± 5 kPa (uniform), on one
local process pool: first stopped at the standard error asked (``--yield-se``, issue 35:
search + yield ≤ 15 s), then, in the same run on a fresh cache, with all ``--samples``
(the baseline).  Prints the wall times, the number of simulations of each stage, the
yields with their intervals, the ratio of the two totals and the load average (the
machine may be shared).  Points are simulated on their steady cycle
(:mod:`pneunet.design.cycles`) unless ``--whole``.  Run against an older tree with
``PYTHONPATH=/tmp/clone:$SITE python -S benchmarks/bench_design.py`` (``-S``: the
editable install's finder would win over PYTHONPATH).
"""
from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "oscillator_design.pn"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--yield-se", type=float, default=0.025,
                    help="standard error asked of the early-stopped yield (0: none)")
    ap.add_argument("--early-only", action="store_true",
                    help="search + early-stopped yield only (no all-samples baseline)")
    ap.add_argument("--whole", action="store_true",
                    help="simulate every point's whole transient (no steady cycle)")
    args = ap.parse_args()
    from pneunet.design.problem import Problem
    from pneunet.design.search import design
    from pneunet.design.spread import from_tolerances
    from pneunet.design.yields import yield_analysis

    start = time.perf_counter()
    problem = Problem(NETLIST, ["period=3s", "swing>=130kPa"], workers=args.workers,
                      progress=True)
    problem.analysis.steady = not args.whole
    with problem:
        result = design(problem, {"Rout": (0.6, 3), "Rvent": (1, 10), "V": (40, 400)})
        t_search = time.perf_counter() - start
        spread = from_tolerances(problem, result.values, ["X1.pclose=±5kPa"])
        if args.yield_se:
            early = yield_analysis(problem, result.values, spread, n=args.samples, seed=0,
                                   nominal=result.metrics, se=args.yield_se)
            print(early.report())
            t_early = time.perf_counter() - start
            print(f"EARLY STOP (--yield-se {args.yield_se}): search + yield {t_early:.1f} s, "
                  f"{result.simulations} + {early.simulations} simulations (target ≤ 15 s); "
                  f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
            problem._cache.clear()  # the baseline simulates every sample again
        if not (args.early_only and args.yield_se):
            y = yield_analysis(problem, result.values, spread, n=args.samples, seed=0,
                               nominal=result.metrics)
    if args.early_only and args.yield_se:
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, reaped
        cpu, sims = usage.ru_utime + usage.ru_stime, result.simulations + early.simulations
        print(f"workers' CPU {cpu:.1f} s = {cpu / sims * 1e3:.0f} ms per simulation ({sims}); "
              f"steady cycle: {not args.whole}")
        return
    total = t_search + y.wall_time_s
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, reaped
    cpu = usage.ru_utime + usage.ru_stime
    sims = result.simulations + y.simulations + (early.simulations if args.yield_se else 0)
    print(result.report())
    print(y.report())
    print(f"search: {t_search:.1f} s, {result.simulations} simulations; yield: "
          f"{y.wall_time_s:.1f} s, {y.simulations} simulations; total {total:.1f} s on "
          f"{args.workers} workers (target ≤ 60 s); load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if args.yield_se:
        print(f"early stop / all samples: {t_early / total:.2f} of the time, "
              f"{early.n} / {y.n} samples; yields {100 * early.yield_:.1f} % and "
              f"{100 * y.yield_:.1f} %")
    if cpu:
        print(f"workers' CPU {cpu:.1f} s = {cpu / sims * 1e3:.0f} ms per simulation: "
              f"{cpu / args.workers:.1f} s of wall time on {args.workers} idle cores")


if __name__ == "__main__":
    main()
