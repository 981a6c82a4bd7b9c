"""Benchmark: the paper oscillator's n × n (R_out, R_vent) regime sweep with 2 workers vs 1.

    python benchmarks/bench_sweep.py            # 20 × 20, both runs (long: minutes)
    python benchmarks/bench_sweep.py --n 6      # quick check
    python benchmarks/bench_sweep.py --workers 2   # 20 × 20 on 2 workers only (target ≤ 30 s)

Each point runs the transient until its cycle converges (or settles) and the
stationary-branch prediction.  Prints wall times, the speed-up and the agreement
between transient and branch classifications.  No store: every point is computed.
"""
from __future__ import annotations

import argparse
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--t-stop", type=float, default=None,
                    help="fixed transient length instead of running to convergence")
    ap.add_argument("--workers", type=int, nargs="+", default=[2, 1],
                    help="worker counts to time (default: 2 and 1)")
    args = ap.parse_args()
    from pneunet.analysis.circuits import oscillator
    from pneunet.analysis.regime import RegimeMeasure, agreement
    from pneunet.analysis.sweep import grid, lin, run_sweep

    pts = grid(lin("Rout", 0.2, 3.0, args.n), lin("Rvent", 1.0, 6.0, args.n))
    analysis = RegimeMeasure(t_stop=args.t_stop)
    times, tables = {}, {}
    for workers in args.workers:
        t0 = time.perf_counter()
        r = run_sweep(oscillator, pts, analysis, workers=workers, progress=True)
        times[workers] = time.perf_counter() - t0
        tables[workers] = r.table.drop(columns="elapsed_s")
        print(f"{workers} worker(s): {times[workers]:.1f} s for {len(pts)} points "
              f"({r.failed} failed)")
    if {1, 2} <= set(times):
        same = tables[1].equals(tables[2])
        print(f"speed-up 2 workers vs 1: {times[1] / times[2]:.2f}x; identical tables: {same}")
    a = agreement(tables[args.workers[0]])
    print(f"transient vs branches agree at {a['agree']} of {a['compared']} points")


if __name__ == "__main__":
    main()
