"""Coverage study of the 95 % intervals of ``fit_valve`` on virtual-bench data.

For each of the paper's three valves (axi, mirror forward, mirror backward) and
bench seeds 0 … N−1, simulate the paper's 4410-point protocol with the bench
defaults (realistic noise, setpoint errors, outlet regulator), fit it back with
``fit_valve(data, mdot_min="auto")`` and check whether each parameter's truth lies
inside its reported 95 % interval.  Prints per parameter and valve the empirical
coverage, the mean z-score (bias in units of the reported standard error) and the
rms z-score (≈ 1 when the standard errors are honest), plus the largest errors
against the accuracy criteria of issue 4 (R_f and a_in + a_out within 3 %,
p_close within 5 kPa).

With n fits per cell the coverage has a binomial standard error of
√(0.95·0.05/n): ±0.05 for n = 20, ±0.028 over the 60 fits pooled per parameter.

Run:  python benchmarks/coverage_fit.py [--seeds 20] [--jobs 2] [--csv out.csv]
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np
import pandas as pd

VALVES = ("axi", "mirror_forward", "mirror_backward")


def one(task):
    name, seed, options = task
    from pneunet.truth.valves.identify import fit_valve, simulate_bench
    from pneunet.truth.valves.identify.fit import NAMES
    from pneunet.physics.valve_params import PAPER_VALVES

    truth = PAPER_VALVES[name]
    data = simulate_bench(truth, seed=seed)
    start = time.perf_counter()
    fit = fit_valve(data, mdot_min="auto", **options)
    elapsed = time.perf_counter() - start
    rows = []
    for k in NAMES:
        lo, hi = fit.ci95[k]
        t = getattr(truth, k)
        rows.append({"valve": name, "seed": seed, "param": k, "truth": t,
                     "value": getattr(fit.params, k), "stderr": fit.stderr[k],
                     "lo": lo, "hi": hi, "covered": bool(lo <= t <= hi), "time_s": elapsed})
    rows.append({"valve": name, "seed": seed, "param": "ain+aout",
                 "truth": truth.ain + truth.aout, "value": fit.params.ain + fit.params.aout,
                 "stderr": math.sqrt(max(fit.covariance.loc["ain", "ain"]
                                         + fit.covariance.loc["aout", "aout"]
                                         + 2 * fit.covariance.loc["ain", "aout"], 0.0)),
                 "lo": np.nan, "hi": np.nan, "covered": np.nan, "time_s": elapsed})
    return rows


def summarise(table: pd.DataFrame) -> str:
    from pneunet.truth.valves.identify.fit import NAMES

    table = table.copy()
    table["z"] = (table["value"] - table["truth"]) / table["stderr"]
    lines = []
    n_seeds = table["seed"].nunique()
    lines.append(f"coverage of the 95 % intervals, {n_seeds} seeds per valve "
                 f"(cell: coverage / mean z / rms z)")
    header = f"{'param':<8}" + "".join(f"{v:>24}" for v in VALVES) + f"{'all':>10}"
    lines.append(header)
    for k in NAMES:
        sub = table[table["param"] == k]
        cells = []
        for v in VALVES:
            s = sub[sub["valve"] == v]
            cells.append(f"{s['covered'].mean():5.2f} / {s['z'].mean():+5.2f} / "
                         f"{math.sqrt((s['z'] ** 2).mean()):4.2f}")
        lines.append(f"{k:<8}" + "".join(f"{c:>24}" for c in cells)
                     + f"{sub['covered'].mean():>10.3f}")
    per_fit = table[table["param"].isin(NAMES)].groupby(["valve", "seed"])["covered"].all()
    lines.append(f"fits with all six truths inside their intervals: {int(per_fit.sum())} / "
                 f"{len(per_fit)}")
    # accuracy criteria of issue 4
    acc = []
    for v in VALVES:
        s = table[table["valve"] == v].set_index(["param", "seed"])
        rf = (s.loc["Rf", "value"] / s.loc["Rf", "truth"] - 1).abs().max()
        area = (s.loc["ain+aout", "value"] / s.loc["ain+aout", "truth"] - 1).abs().max()
        pc = (s.loc["pclose", "value"] - s.loc["pclose", "truth"]).abs().max()
        acc.append(f"{v}: |ΔRf| ≤ {100 * rf:.2f} %, |Δ(ain+aout)| ≤ {100 * area:.2f} %, "
                   f"|Δpclose| ≤ {pc:.2f} kPa")
    lines.append("largest errors (criteria: 3 %, 3 %, 5 kPa):")
    lines.extend("    " + a for a in acc)
    t = table.drop_duplicates(["valve", "seed"])["time_s"]
    lines.append(f"fit time: median {1e3 * t.median():.0f} ms, max {1e3 * t.max():.0f} ms "
                 f"(study run with other jobs in parallel)")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="bench seeds 0..N-1 per valve")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument("--csv", help="write every fit's parameters to this CSV")
    parser.add_argument("--n-boot", type=int, default=None, help="pass n_boot to fit_valve")
    args = parser.parse_args(argv)
    options = {} if args.n_boot is None else {"n_boot": args.n_boot}
    tasks = [(v, s, options) for v in VALVES
             for s in range(args.first_seed, args.first_seed + args.seeds)]
    start = time.perf_counter()
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.jobs) as pool:
            results = list(pool.map(one, tasks))
    else:
        results = [one(t) for t in tasks]
    table = pd.DataFrame([row for rows in results for row in rows])
    if args.csv:
        table.to_csv(args.csv, index=False)
    print(summarise(table))
    print(f"{len(tasks)} fits in {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
