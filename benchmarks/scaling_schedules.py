"""Multirate against single-rate IDA on bench_scaling's network (issue 18).

Run through ``python benchmarks/bench_scaling.py --schedule independent`` (or
``groups``).  Every cell of the network has its own PULSE control source:

* ``groups``: delays staggered over 8 phase groups (bench_scaling's default);
* ``independent``: delays uniform in 0.2–4.2 s, one per cell (seeded), so a solver
  with one global step must resolve every cell's edges.

Each run is a fresh process (peak memory = its maximum resident set, plus that of the
largest worker process times the number of workers when the cells are split over
processes: an upper bound), timed from
the circuit's assembly to the solution (netlist-free: ``Circuit`` calls).  The error
is the largest actuator or line pressure difference (kPa) on the 50 ms output grid
against single-rate IDA at rtol = atol = 1e-8, for N ≤ ``--reference-max``.
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
T_STOP, T_STEP = 10.0, 0.05


def build(n, schedule, method, rtol, atol=1e-5):
    """bench_scaling's network of ``n`` cells with the given control schedule."""
    sys.path.insert(0, HERE)
    import bench_scaling as bs

    delays = (0.25 * (np.arange(n) % bs.PHASES) + 0.2 if schedule == "groups"
              else np.random.default_rng(18).uniform(0.2, 4.2, n))
    circuit = bs.build(n, rtol, atol, delays=delays, method=method)
    circuit.title = f"scaling N={n} ({schedule})"
    return circuit


def one(n, schedule, method, rtol, atol, save):
    """Run once in this process; print JSON (wall s, steps, peak MB); save pressures."""
    c = build(n, schedule, method, rtol, atol)
    t0 = time.perf_counter()
    sol = c.tran(T_STOP, t_step=T_STEP)
    wall = time.perf_counter() - t0
    names = [f"act{k}" for k in range(n)] + ["line"]
    np.save(save, np.column_stack([sol.t] + [sol.pressure(x) for x in names]))
    workers = int(sol.stats.get("processes", 1))
    peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss + (workers if workers > 1 else 0)
            * resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    print(json.dumps(dict(wall=wall, steps=int(sol.stats.get("steps", 0)), peak_mb=peak,
                          method=sol.stats.get("method", "single"),
                          sweeps=sol.stats.get("sweeps"), windows=sol.stats.get("windows"))))


def measure(n, schedule, method, rtol, atol=1e-5):
    """One run in a fresh process: its JSON record plus the saved pressures."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "p.npy")
        out = subprocess.run([sys.executable, __file__, "--one", str(n), schedule, method,
                              repr(rtol), repr(atol), path], capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=os.path.dirname(HERE)))
        if out.returncode:
            raise RuntimeError(out.stderr[-2000:])
        record = json.loads(out.stdout.strip().splitlines()[-1])
        record["pressures"] = np.load(path)
    return record


def error(run, ref) -> float:
    """Largest pressure difference (kPa) on the output grid."""
    t = run[:, 0]
    return float(max(np.max(np.abs(run[:, j] - np.interp(t, ref[:, 0], ref[:, j])))
                     for j in range(1, run.shape[1])))


def study(sizes, schedule, rtol, single_max, reference_max, repeat=1):
    """Print the table of issue 18 for one schedule; return its rows.  ``repeat``: runs
    of the multirate method per N, its median time shown (and the range): this machine's
    speed drifts by ±20 % within minutes."""
    print(f"{schedule} schedule, {T_STOP:g} s, rtol {rtol:g}, atol 1e-5; fresh process per run; "
          f"error against single-rate IDA at rtol 1e-8 (N ≤ {reference_max})"
          + (f"; multirate: median of {repeat} runs (range)" if repeat > 1 else ""))
    print(f"{'N':>6} | {'multirate s':>11} {'steps':>9} {'MB':>6} {'error kPa':>9} | "
          f"{'single s':>9} {'steps':>7} {'MB':>6} {'error kPa':>9}")
    rows = []
    for n in sizes:
        ref = measure(n, schedule, "single", 1e-8, 1e-8)["pressures"] if n <= reference_max else None
        row = {"N": n}
        for method in ("multirate", "single"):
            if method == "single" and n > single_max:
                continue
            runs = [measure(n, schedule, method, rtol)
                    for _ in range(repeat if method == "multirate" else 1)]
            r = row[method] = runs[0]
            walls = sorted(run["wall"] for run in runs)
            r["wall"], r["range"] = float(np.median(walls)), (walls[0], walls[-1])
            r["error"] = error(r.pop("pressures"), ref) if ref is not None else np.nan
        rows.append(row)
        m, s = row["multirate"], row.get("single")
        single = (f"{s['wall']:9.2f} {s['steps']:7d} {s['peak_mb']:6.0f} {s['error']:9.3f}"
                  if s else f"{'(skipped: N > --single-max)':>34}")
        spread = (f" ({m['range'][0]:.2f}–{m['range'][1]:.2f})" if repeat > 1 else "")
        print(f"{n:6d} | {m['wall']:11.2f} {m['steps']:9d} {m['peak_mb']:6.0f} "
              f"{m['error']:9.3f} | {single}{spread}")
        sys.stdout.flush()
    walls = {r["N"]: r["multirate"]["wall"] for r in rows}
    if 300 in walls and 3000 in walls:
        print(f"growth exponent of the multirate time 300 → 3000: "
              f"{np.log(walls[3000] / walls[300]) / np.log(10):.2f} (target ≤ 1.15)")
    return rows


def compare(n, rtol, repeat=3):
    """Issue 35, item 3: the same ``n`` cells switched independently against on 8 phase
    groups, each as a user runs it (``method`` auto), fresh processes alternating so that
    both see the machine's same drift; prints the medians and their ratio."""
    walls = {"independent": [], "groups": []}
    methods = {}
    for _ in range(repeat):
        for schedule in walls:
            r = measure(n, schedule, "auto", rtol)
            walls[schedule].append(r["wall"])
            methods[schedule] = r["method"]
    med = {k: float(np.median(v)) for k, v in walls.items()}
    print(f"N = {n}, {T_STOP:g} s, rtol {rtol:g}, method auto, {repeat} alternating fresh "
          f"processes each (load average {os.getloadavg()[0]:.1f})")
    for k, v in walls.items():
        print(f"  {k:<12} {methods[k]:<10} median {med[k]:6.2f} s  runs "
              + " / ".join(f"{w:.2f}" for w in v))
    print(f"  independent / groups = {med['independent'] / med['groups']:.2f} (target ≤ 1.5)")
    return med


if __name__ == "__main__" and sys.argv[1:2] == ["--one"]:
    n, schedule, method, rtol, atol, save = sys.argv[2:8]
    one(int(n), schedule, method, float(rtol), float(atol), save)
