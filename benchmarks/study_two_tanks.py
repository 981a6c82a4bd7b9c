"""A circuit of lines and tanks that none of the other studies has: two tanks charged and
vented through quadrature lines by a supply step (netlists/two_tanks.pn), diagnosed from
recordings of a stand-alone model (tests/traces/standalone_tanks.py: its own equations,
scipy's Radau, nothing of pneunet).

Each case: p_t1 and p_t2 at ``--rate`` Hz, 0.2-0.5 kPa of noise, the logger started at a
random time (before the step or during the charge), its clock from 0, 18 s; the tanks'
volumes given (R and V of such a circuit are determined only as products), the lines'
R fitted from guesses 40 % and 25 % off, every candidate effect screened.  Hidden: none,
heat exchange in tank 1 (energy balance, τ = 0.4 s), and outside the library a leak of
tank 2 (40 kPa·s/mg, laminar) and a dead-end volume behind a line at tank 2 (the netlist
fitted with V2 given, so no volume can take it up).

    python benchmarks/study_two_tanks.py                  # 3 starts per case
    python benchmarks/study_two_tanks.py --runs 6 --seed 5 --rate 20
    python benchmarks/study_two_tanks.py --pulse          # a square-wave supply instead
    python benchmarks/study_two_tanks.py --sine           # a sine supply instead

``--pulse``: the supply a square wave (96 kPa until 1 s, then 296 kPa for 3 s in every
6 s; netlists/two_tanks_pulse.pn), the logger started at a random time 4-30 s after
switch-on, 36 s recorded: a periodic driven circuit whose clock the diagnosis must find.
``--sine``: the supply 196 − 100·cos(2π·0.2·t) kPa (netlists/two_tanks_sine.pn: a SIN
with a phase), started and recorded as ``--pulse``: a drive without edges.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CASES = {"clean": ({}, "adequate"),
         "heat in tank 1 (tau 0.4 s)": ({"heat_tau": 0.4}, "explained"),
         "leak of tank 2 (outside)": ({"leak": 40.0}, "unexplained"),
         "dead end 30 mL behind 1 kPa*s/mg (outside)": ({"side": (1.0, 30.0)},
                                                        "unexplained")}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="logger starts per case")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rate", type=float, default=50.0, help="samples per second")
    ap.add_argument("--pulse", action="store_true", help="a square-wave supply")
    ap.add_argument("--sine", action="store_true", help="a sine supply")
    args = ap.parse_args(argv)

    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import diagnose_trace
    from tests.traces.standalone_tanks import (TRUTH, sine_supply, square_supply, supply,
                                               tanks_record)

    netlist, source = ("two_tanks_pulse.pn", square_supply) if args.pulse \
        else ("two_tanks_sine.pn", sine_supply) if args.sine else ("two_tanks.pn", supply)
    periodic = args.pulse or args.sine
    starts, seconds = ((4.0, 30.0), 36.0) if periodic else ((0.3, 3.5), 18.0)
    build = NetlistBuilder(str(ROOT / "netlists" / netlist))
    params = {"R1": (0.7, 0.05, 5.0), "R2": (1.5, 0.1, 20.0)}
    fixed = {"V1": TRUTH["V1"], "V2": TRUTH["V2"]}
    rng = np.random.default_rng(args.seed)
    print(f"{netlist}: {args.rate:g} Hz, {seconds:g} s, clock from 0; V1 {fixed['V1']:g} mL and V2 "
          f"{fixed['V2']:g} mL given, R1 (0.5) and R2 (2) fitted\n")
    print("| hidden | start s | noise kPa | verdict (want) | accepted | base → final × floor "
          "| R1 [95 %] | R2 [95 %] | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    right = total = covered = intervals = 0
    for name, (hidden, want) in CASES.items():
        for _ in range(args.runs):
            start, noise = float(rng.uniform(*starts)), float(rng.uniform(0.2, 0.5))
            rec = tanks_record(start=start, seconds=seconds, dt=1.0 / args.rate, noise=noise,
                               seed=int(rng.integers(1 << 30)), source=source, **hidden)
            t0 = time.perf_counter()
            d = diagnose_trace(build, rec, params, fixed=fixed, node="t2")
            wall = time.perf_counter() - t0
            steps = d.waterfall.steps
            fit = d.final
            cells = []
            for k in ("R1", "R2"):
                lo, hi = fit.ci[k]
                inside = lo <= TRUTH[k] <= hi
                if not hidden or d.verdict == "explained":
                    covered += inside
                    intervals += 1
                cells.append(f"{fit.values[k]:.4g} [{lo:.4g}, {hi:.4g}]{'' if inside else ' ✗'}")
            right += d.verdict == want
            total += 1
            print(f"| {name} | {start:.2f} | {noise:.2f} | {d.verdict} ({want}) | "
                  f"{', '.join(d.accepted) or '–'} | {steps[0].held_out / d.noise_floor:.2f} → "
                  f"{steps[-1].held_out / d.noise_floor:.2f} | {cells[0]} | {cells[1]} | "
                  f"{wall:.1f} |", flush=True)
    print(f"\nverdicts right: {right}/{total}; intervals of the models accepted or adequate "
          f"covering the truth: {covered}/{intervals}")


if __name__ == "__main__":
    main()
