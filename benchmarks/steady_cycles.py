"""Steady cycles against whole transients: the same yield samples, both ways (issue 35).

    python benchmarks/steady_cycles.py                 # 1000 samples of the bench_design spec
    python benchmarks/steady_cycles.py --samples 100   # quick check

The design of ``bench_design.py`` (searched on whole transients), then ``--samples``
Monte Carlo samples of p_close ± 5 kPa simulated twice on 2 workers: with the steady
cycle (:mod:`pneunet.design.cycles`, the default of a design) and with the whole 12 s
transient.  Prints the largest difference of each metric and how many samples lie that
close to the spec's edge, the verdicts that flip, each flip's distance from the edge and
the whole transient's own error there (against rtol = atol = 1e-8), the workers' CPU per
simulation of both and the load average.
"""
from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "oscillator_design.pn"
TARGETS = ["period=3s", "swing>=130kPa"]
#: the whole transient's own error at rtol = atol = 1e-5, relative (its period against
#: rtol = 1e-8: 1.4e-4 to 1.7e-4 s of ~3 s)
OWN_ERROR = 5e-5


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pools' workers, reaped
    return usage.ru_utime + usage.ru_stime


def run(points, steady: bool, workers: int, build=NETLIST):
    """The problem (for its targets) and its rows at ``points``, and the workers' CPU."""
    from pneunet.design.problem import Problem

    problem = Problem(build, TARGETS, workers=workers)
    problem.analysis.steady = steady
    cpu, wall = children_cpu(), time.perf_counter()
    with problem:
        rows = problem.evaluate(points)
    return problem, rows, children_cpu() - cpu, time.perf_counter() - wall


def edge_distance(target, value: float) -> float:
    """How far ``value`` lies from the nearest edge of what ``target`` accepts."""
    import math

    if math.isnan(value):
        return math.inf
    if target.op == "=":
        return abs(abs(value - target.value) - target.tol)
    return abs(value - target.value)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    from pneunet.design.problem import Problem
    from pneunet.design.search import design
    from pneunet.design.spread import from_tolerances
    from pneunet.design.sweep import NetlistBuilder

    problem = Problem(NETLIST, TARGETS, workers=args.workers)
    problem.analysis.steady = False
    with problem:
        found = design(problem, {"Rout": (0.6, 3), "Rvent": (1, 10), "V": (40, 400)})
    spread = from_tolerances(problem, found.values, ["X1.pclose=±5kPa"])
    points = [dict(found.values, **s) for s in spread.sample(args.samples, 0)]
    print(f"design {found.values}; {len(points)} samples of X1.pclose ±5 kPa")
    fast, steady_rows, cpu_steady, wall_steady = run(points, True, args.workers)
    _, whole_rows, cpu_whole, wall_whole = run(points, False, args.workers)
    targets, flips, largest = fast.targets, [], {}
    for k, (a, b, p) in enumerate(zip(steady_rows, whole_rows, points)):
        ma, mb = fast.metrics(a), fast.metrics(b)
        for t in targets:
            d = abs(ma[t.key] - mb[t.key])
            if d > largest.get(t.key, (-1,))[0]:
                largest[t.key] = (d, k)
        if fast.met(ma) != fast.met(mb):
            flips.append((k, p, ma, mb))
    for t in targets:
        d, k = largest[t.key]
        close = max(d, OWN_ERROR * abs(t.value))
        near = sum(edge_distance(t, fast.metrics(r)[t.key]) <= close for r in whole_rows)
        print(f"largest |steady - whole| of {t.key}: {d:.3g} {t.unit} (sample {k}; the "
              f"spec's tolerance: {t.tol:g} {t.unit}); {near} samples lie within "
              f"{close:.2g} {t.unit} of its edge")
    n_steady = sum(fast.met(fast.metrics(r)) for r in steady_rows)
    n_whole = sum(fast.met(fast.metrics(r)) for r in whole_rows)
    print(f"passed: {n_steady} (steady) and {n_whole} (whole) of {len(points)}; "
          f"{len(flips)} verdicts flip")
    if flips:  # the whole transient's own error at the flipped samples
        tight = NetlistBuilder(NETLIST, rtol=1e-8, atol=1e-8)
        _, ref_rows, _, _ = run([p for _, p, _, _ in flips], False, 1, tight)
        for (k, p, ma, mb), ref in zip(flips, ref_rows):
            mr = fast.metrics(ref)
            for t in targets:
                print(f"  sample {k} (X1.pclose {p['X1.pclose']:.4f}): {t.key} steady "
                      f"{ma[t.key]:.6f}, whole {mb[t.key]:.6f}, rtol 1e-8 {mr[t.key]:.6f}; "
                      f"whole's error {abs(mb[t.key] - mr[t.key]):.2g}, its distance from "
                      f"the edge {edge_distance(t, mb[t.key]):.2g} {t.unit}")
    n = len(points)
    print(f"workers' CPU per simulation: steady {1e3 * cpu_steady / n:.1f} ms, whole "
          f"{1e3 * cpu_whole / n:.1f} ms ({cpu_whole / cpu_steady:.2f}x); wall {wall_steady:.1f}"
          f" s and {wall_whole:.1f} s on {args.workers} workers; load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
