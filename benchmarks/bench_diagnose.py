"""Benchmark of ``pneunet diagnose`` on 4410 points (issue 5, done-when 4).

    python benchmarks/bench_diagnose.py              # timing: must be < 60 s
    python benchmarks/bench_diagnose.py --confusion  # confusion matrix for docs/diagnose.md

The timing is printed with its ratio to a baseline measured in the same run: one
least-squares fit of the plain six-parameter model to the same data (the unit
of work the diagnosis repeats for every candidate and fold).
"""
from __future__ import annotations

import argparse
import sys
import time

LIMIT_S = 60.0


def timing(scenario: str, seed: int) -> int:
    from threadpoolctl import threadpool_limits

    from pneunet.truth.valves.diagnose import diagnose
    from pneunet.truth.valves.diagnose.fitting import fit_model, initial_params
    from pneunet.truth.valves.diagnose.features import prepare
    from pneunet.truth.valves.diagnose.scenarios import bench, scenario_truth
    from pneunet.physics.valve_effects import ValveModel

    data = bench(scenario_truth(scenario), seed=seed)
    df, _ = prepare(data)
    with threadpool_limits(1):
        t0 = time.perf_counter()
        fit_model(df, ValveModel(initial_params(df)))
        t_base = time.perf_counter() - t0
    t0 = time.perf_counter()
    diag = diagnose(data, progress=True)
    t_diag = time.perf_counter() - t0
    j = diag.to_json()
    print(f"data: scenario {scenario!r}, {len(data)} points, {j['n_sweeps']} sweeps")
    print(f"baseline (identification + one six-parameter least-squares fit): {t_base:.2f} s")
    print(f"diagnose (full search, {len(j['rounds'])} round(s)): {t_diag:.2f} s "
          f"= {t_diag / t_base:.1f} x baseline; accepted {j['accepted']}, "
          f"unexplained {j['unexplained']}")
    ok = t_diag < LIMIT_S
    print(f"{'PASS' if ok else 'FAIL'}: {t_diag:.1f} s {'<' if ok else '>='} {LIMIT_S:.0f} s")
    return 0 if ok else 1


def confusion(seed: int) -> int:
    from pneunet.truth.valves.diagnose.scenarios import (LIBRARY_SCENARIOS, UNLISTED_SCENARIOS,
                                                         run_scenario)

    names = (["clean"] + list(LIBRARY_SCENARIOS) + list(UNLISTED_SCENARIOS)
             + ["leak+hysteresis", "choked+laminar", "internal-drop+leak"])
    cols = ["adequate"] + list(LIBRARY_SCENARIOS) + ["unexplained"]
    print("| truth (4410 points) | " + " | ".join(f"`{c}`" for c in cols)
          + " | accepted | where (top 2) | CV RMSE baseline → final / floor [mg/s] | time |")
    print("|" + "---|" * (len(cols) + 5))
    for name in names:
        t0 = time.perf_counter()
        diag, floor, _ = run_scenario(name, seed=seed)
        dt = time.perf_counter() - t0
        j = diag.to_json()
        called = ("adequate" if j["adequate"] else
                  (j["accepted"][0] if j["accepted"] else "unexplained"))
        cells = []
        for c in cols:
            hit = c == called or (c == "unexplained" and j["unexplained"] and called != c)
            cells.append("**1**" if c == called else ("(1)" if hit else "·"))
        where = ", ".join(w["feature"] for w in j["where"][:2])
        print(f"| {name} | " + " | ".join(cells) + f" | {', '.join(j['accepted']) or '—'} | "
              f"{where} | {j['baseline']['cv_rmse']:.2f} → {j['final']['cv_rmse']:.2f} / "
              f"{floor:.2f} | {dt:.0f} s |")
        sys.stdout.flush()
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--confusion", action="store_true")
    ap.add_argument("--scenario", default="leak+hysteresis",
                    help="bench scenario for the timing (default leak+hysteresis)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    return confusion(args.seed) if args.confusion else timing(args.scenario, args.seed)


if __name__ == "__main__":
    sys.exit(main())
