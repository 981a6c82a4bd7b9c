"""The trace diagnosis on stand-alone recordings: one row per hidden physics.

Each recording is the paper's oscillator (R_out 1.132, R_vent 3, V 50 mL) written out by
hand and integrated by scipy (tests/traces/standalone.py: nothing of pneunet's effect
code), 12 s = 8 cycles at 20 Hz, p_tank and p_out, 0.4 kPa noise.  The diagnosis fits
R_out, R_vent and V from guesses 20-30 % off and tries every registered circuit effect.

    python benchmarks/study_trace_diagnosis.py             # every case (~10 min)
    python benchmarks/study_trace_diagnosis.py clean side  # some cases
    options: --seed N
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: case → (stand-alone keywords, what a right answer is)
CASES = {
    "clean": ({}, "adequate"),
    "polytropic": ({"poly_n": 1.3}, "polytropic_volume"),
    "gas-law-n": ({"gas_law_n": 1.25}, "adequate"),  # = a tank of V/n: indistinguishable
    "dead-volume": ({"V_out": 1.5}, "dead_volume@out"),
    "control-tube": ({"tube_ctrl": (10.0, 2.0)}, "tube@X1.ctrl"),
    "supply-tube": ({"tube_supply": (0.5, 20.0)}, "tube@X1.in"),
    "heat-transfer": ({"heat_tau": 0.5}, "volume_heat_transfer"),
    "creep": ({"creep": 0.4}, "unexplained"),
    "ripple": ({"ripple": (12.0, 0.37)}, "unexplained"),
    "side": ({"side": (2.0, 30.0)}, "unexplained"),
}
PARAMS = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "V": (65.0, 5.0, 500.0)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", default=list(CASES))
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    from pneunet.analysis.circuits import oscillator
    from pneunet.traces import diagnose_trace
    from tests.traces.standalone import oscillator_record

    print("| case | expected | verdict | accepted | held-out / floor (base → final) | "
          "floor kPa | time s |")
    print("|---|---|---|---|---|---|---|")
    for name in args.cases:
        kw, expected = CASES[name]
        rec = oscillator_record(12.0, noise=0.4, seed=args.seed, **kw)
        t0 = time.perf_counter()
        d = diagnose_trace(oscillator, rec, PARAMS, node="tank")
        wall = time.perf_counter() - t0
        steps = d.waterfall.steps
        ratio = f"{steps[0].held_out / d.noise_floor:.2f} → {steps[-1].held_out / d.noise_floor:.2f}"
        print(f"| {name} | {expected} | {d.verdict} | {', '.join(d.accepted) or '–'} | {ratio} | "
              f"{d.noise_floor:.3f} | {wall:.0f} |", flush=True)


if __name__ == "__main__":
    main()
