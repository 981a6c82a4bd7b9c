"""Sources that change once, recorded on the logger's own clock: one fit per logger start.

The amplifier of netlists/amplifier_once.pn (inflated at 5 s, deflated at 10 s) with a
0.24 kPa·s/mg line and a 30 mL actuator (the netlist says 0.2 and 25), recorded by the
stand-alone generator (tests/traces/standalone_driven.py, nothing of pneunet) at 50 Hz,
p_muscle, 0.3 kPa noise, 12 s from each start (before 0: the actuator at rest), the time
column from 0 (or a Unix time, or the sources' clock).  Fitted the line's R and V
(``fit_trace``: the first sample's netlist time found from the record).

With ``--supply-on``, netlists/amplifier_supply_on.pn instead: the valves pulse every
10 s from 0 s, the supply comes on at 13 s (periodic sources beside a one-off change);
14 s from each start.

    python benchmarks/study_one_shot_clock.py
    python benchmarks/study_one_shot_clock.py --starts 2 6.5 --seed 4
    python benchmarks/study_one_shot_clock.py --supply-on
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CLOCKS = {"from 0": lambda start: 0.0, "Unix time": lambda start: 1.7e9,
          "sources' clock": lambda start: start}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=float, nargs="*", default=[-3.0, 1.0, 2.0, 3.3, 7.0, 8.5,
                                                                  11.0])
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--supply-on", action="store_true",
                    help="the pulsed amplifier whose supply comes on at 13 s")
    args = ap.parse_args(argv)

    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import fit_trace
    from tests.traces.standalone_driven import amplifier_record
    from tests.traces.test_one_shot_clock import DT, PARAMS, TRUTH, record as once_record

    if args.supply_on:
        build = NetlistBuilder(str(ROOT / "netlists" / "amplifier_supply_on.pn"))
        if args.starts == ap.get_default("starts"):
            args.starts = [0.5, 3.0, 9.0, 12.5, 14.0, 21.0, 29.0]

        def record(start, seconds, clock, seed):
            rec = amplifier_record(start, 14.0, dt=DT, noise=0.3, seed=seed, supply_on=13.0,
                                   signals=("muscle",), R_line=TRUTH["Rtube.R"],
                                   V=TRUTH["Amck.V"])
            rec = rec.iloc[:int(round(14.0 / DT))].copy()
            rec["time_s"] = clock + DT * np.arange(len(rec))
            return rec
    else:
        build = NetlistBuilder(str(ROOT / "netlists" / "amplifier_once.pn"))
        record = once_record
    print("| logger started at (s) | time column | first sample (s), 95 % | "
          + " | ".join(f"{k} [95 %] ({v:g})" for k, v in TRUTH.items()) + " | rms kPa | s |")
    print("|---|---|---|" + "---|" * len(TRUTH) + "---|---|")
    runs = [(s, "from 0") for s in args.starts] + [(3.3, "Unix time"), (3.3, "sources' clock")]
    for start, clock in runs:
        rec = record(start, 8.0 if start > 10.01 else 12.0, CLOCKS[clock](start), args.seed)
        t0 = time.perf_counter()
        fit = fit_trace(build, rec, PARAMS, node="muscle")
        wall = time.perf_counter() - t0
        state = fit.start_state
        ci = state.clock_ci
        found = (f"{state.first_time:.4f} ± {(ci[1] - ci[0]) / 2 * 1e3:.2g} ms" if ci
                 else f"{state.first_time:.4g}" + (" (kept)" if not state.clock else
                                                   ", not fitted"))
        cols = [f"{fit.values[k]:.4g} [{fit.ci[k][0]:.3g}, {fit.ci[k][1]:.3g}]"
                for k in TRUTH]
        print(f"| {start:g} | {clock} | {found} | " + " | ".join(cols)
              + f" | {fit.error():.3f} | {wall:.1f} |", flush=True)


if __name__ == "__main__":
    np.seterr(over="ignore")
    main()
