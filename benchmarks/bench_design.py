"""Benchmark: design search + 1,000-sample yield of the paper's oscillator (issue 13).

    python benchmarks/bench_design.py                 # 2 workers, 1000 samples (target ≤ 60 s)
    python benchmarks/bench_design.py --samples 100   # quick check

Searches R_out, R_vent and V of ``netlists/oscillator_design.pn`` for a 3 s period with at
least 130 kPa swing, then the yield of the design under p_close ± 5 kPa (uniform), on one
local process pool.  Prints the wall times, the number of simulations of each stage, the
yield with its standard error and the load average (the machine may be shared).
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
    args = ap.parse_args()
    from pneunet.design.problem import Problem
    from pneunet.design.search import design
    from pneunet.design.spread import from_tolerances
    from pneunet.design.yields import yield_analysis

    start = time.perf_counter()
    problem = Problem(NETLIST, ["period=3s", "swing>=130kPa"], workers=args.workers,
                      progress=True)
    with problem:
        result = design(problem, {"Rout": (0.6, 3), "Rvent": (1, 10), "V": (40, 400)})
        t_search = time.perf_counter() - start
        spread = from_tolerances(problem, result.values, ["X1.pclose=±5kPa"])
        y = yield_analysis(problem, result.values, spread, n=args.samples, seed=0,
                           nominal=result.metrics)
    total = time.perf_counter() - start
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, reaped
    cpu = usage.ru_utime + usage.ru_stime
    sims = result.simulations + y.simulations
    print(result.report())
    print(y.report())
    print(f"search: {t_search:.1f} s, {result.simulations} simulations; yield: "
          f"{y.wall_time_s:.1f} s, {y.simulations} simulations; total {total:.1f} s on "
          f"{args.workers} workers (target ≤ 60 s); load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if cpu:
        print(f"workers' CPU {cpu:.1f} s = {cpu / sims * 1e3:.0f} ms per simulation: "
              f"{cpu / args.workers:.1f} s of wall time on {args.workers} idle cores")


if __name__ == "__main__":
    main()
