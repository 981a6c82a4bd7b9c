"""Benchmark: the paper oscillator's n × n (R_out, R_vent) regime sweep with 2 workers vs 1.

    python benchmarks/bench_sweep.py            # 20 × 20, both runs (long: minutes)
    python benchmarks/bench_sweep.py --n 6      # quick check
    python benchmarks/bench_sweep.py --workers 2   # 20 × 20 on 2 workers only (target ≤ 30 s)
    python benchmarks/bench_sweep.py --n 12 --workers 1 --cluster   # issue 35: ≥ 85 %

Each point runs the transient until its cycle converges (or settles) and the
stationary-branch prediction.  Prints wall times, the speed-up and the agreement
between transient and branch classifications.  No store: every point is computed.

``--cluster`` also runs the sweep on a real dask cluster that the benchmark starts on
this machine (``dask scheduler`` and ``dask worker --nworkers 2 --nthreads 1`` as
processes of their own, joined by a scheduler file in a temporary folder) and prints its
parallel efficiency against ``--workers 1`` of the same run: T1 / (2 · T_cluster).  The
cluster is shut down however the benchmark ends.  Each run also prints the CPU time of
all its processes (this one, the pool's or the cluster's scheduler, nannies and workers):
T1's CPU over a run's CPU is the efficiency it would have on two idle cores, less any
end-of-run imbalance — the figure to read when other jobs share the cores.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


@contextlib.contextmanager
def dask_cluster(nworkers: int = 2, timeout: float = 60.0):
    """``(client, cpu)``: a dask client of a scheduler and ``nworkers`` single-thread
    workers started here as CLI processes, and ``cpu()`` the CPU seconds the cluster's
    processes have used; both processes are stopped on exit (error or Ctrl-C included)."""
    import psutil
    from distributed import Client

    with tempfile.TemporaryDirectory(prefix="pneunet-cluster-") as tmp:
        sfile = Path(tmp) / "scheduler.json"
        common = dict(cwd=tmp, start_new_session=True, stdout=subprocess.DEVNULL,
                      stderr=open(Path(tmp) / "log.txt", "w"))
        dask = [sys.executable, "-m", "dask"]  # the `dask` command of this Python
        procs = [subprocess.Popen(dask + ["scheduler", "--scheduler-file", str(sfile),
                                          "--port", "0", "--host", "127.0.0.1",
                                          "--no-dashboard", "--idle-timeout", "120s"],
                                 **common)]  # idle: this process was killed; workers follow
        client = None
        try:
            deadline = time.monotonic() + timeout
            while not _written(sfile):
                if time.monotonic() > deadline or procs[0].poll() is not None:
                    raise RuntimeError("the dask scheduler did not start: "
                                       + (Path(tmp) / "log.txt").read_text()[-2000:])
                time.sleep(0.1)
            procs.append(subprocess.Popen(
                dask + ["worker", "--scheduler-file", str(sfile), "--nworkers", str(nworkers),
                        "--nthreads", "1", "--no-dashboard", "--death-timeout", "30"], **common))
            client = Client(scheduler_file=str(sfile), timeout=timeout)
            client.wait_for_workers(nworkers, timeout=timeout)
            tree = [psutil.Process(p.pid) for p in procs]
            tree += [c for p in list(tree) for c in p.children(recursive=True)]
            yield client, lambda: sum(sum(p.cpu_times()[:2]) for p in tree)
        finally:
            if client is not None:
                with contextlib.suppress(Exception):
                    client.close()
            for proc in reversed(procs):  # workers first, then the scheduler
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(proc.pid, 15)
                try:
                    proc.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, 9)
                    proc.wait()
            common["stderr"].close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--t-stop", type=float, default=None,
                    help="fixed transient length instead of running to convergence")
    ap.add_argument("--workers", type=int, nargs="+", default=[2, 1],
                    help="worker counts to time (default: 2 and 1)")
    ap.add_argument("--cluster", action="store_true",
                    help="also run on a dask scheduler + 2 single-thread workers started here")
    args = ap.parse_args()
    from pneunet.design.circuits import oscillator
    from pneunet.design.regime import RegimeMeasure, agreement
    from pneunet.design.sweep import grid, lin, run_sweep

    pts = grid(lin("Rout", 0.2, 3.0, args.n), lin("Rvent", 1.0, 6.0, args.n))
    analysis = RegimeMeasure(t_stop=args.t_stop)
    times, tables, cpus = {}, {}, {}
    run_sweep(oscillator, pts[:1], analysis, workers=1, progress=False)  # imports, caches:
    # the 1-worker baseline and the pool forked from here start warm, the cluster cold
    runs = list(args.workers) + (["cluster"] if args.cluster else [])
    for run in runs:
        load = os.getloadavg()[0]
        with (dask_cluster(2) if run == "cluster" else
              contextlib.nullcontext((None, lambda: 0.0))) as (client, cluster_cpu):
            c0, t0 = _cpu() + cluster_cpu(), time.perf_counter()
            r = run_sweep(oscillator, pts, analysis, workers=None if client else run,
                          executor=client, progress=True)
            times[run] = time.perf_counter() - t0
            cpus[run] = _cpu() + cluster_cpu() - c0
        tables[run] = r.table.drop(columns="elapsed_s")
        what = "dask cluster (2 workers)" if run == "cluster" else f"{run} worker(s)"
        print(f"{what}: {times[run]:.1f} s for {len(pts)} points ({r.failed} failed), CPU "
              f"{cpus[run]:.1f} s; load {load:.2f} before, {os.getloadavg()[0]:.2f} after")
    if 1 in times:
        for run in runs:
            n = 2 if run == "cluster" else run
            if n > 1:
                print(f"{run}: speed-up {times[1] / times[run]:.2f}x, parallel efficiency "
                      f"{times[1] / (n * times[run]):.0%} against 1 worker (CPU: "
                      f"{cpus[1] / cpus[run]:.0%}); identical table: "
                      f"{tables[1].equals(tables[run])}")
    a = agreement(tables[runs[0]])
    print(f"transient vs branches agree at {a['agree']} of {a['compared']} points")


def _written(path: Path) -> bool:
    """Whether the scheduler has written its whole file (JSON)."""
    try:
        return isinstance(json.loads(path.read_text()), dict)
    except (OSError, ValueError):
        return False


def _cpu() -> float:
    """CPU seconds of this process and of its children that have ended (a pool's)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


if __name__ == "__main__":
    main()
