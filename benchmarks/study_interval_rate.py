"""Interval honesty of a dead-volume fit at a high sampling rate, on every sample and on
one sample in k (what a diagnosis fits: pneunet.truth.circuits.align.thinning).

Stand-alone records (tests/traces/standalone.py: scipy's Radau, not pneunet) of the
oscillator of ``netlists/oscillator.pn`` with R_vent 3.5, a 200 mL tank and a hidden
3 mL volume at ``out``, 100 Hz, 0.3 kPa, the logger started 12 s after switch-on, 40 s;
each fitted with ``dead_volume@out`` from its truth.  Prints each record's z (estimate
minus truth over the standard error, in ln value) and their rms: 1 for honest widths.

    python benchmarks/study_interval_rate.py              # every sample, 8 records
    python benchmarks/study_interval_rate.py --every 4    # one sample in 4
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TRUTH = {"Rout": 1.132, "Rvent": 3.5, "Vtank.V": 200.0, "V_dead@out": 3.0}


def main(argv=None) -> None:
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits import fit_trace
    from pneunet.truth.circuits.effects import candidates_for
    from tests.traces.standalone import oscillator_record

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=1, help="keep one sample in this many")
    ap.add_argument("--n", type=int, default=8, help="records (seeds 11, 12, ...)")
    args = ap.parse_args(argv)
    build = NetlistBuilder(str(ROOT / "netlists" / "oscillator.pn"))
    (dead,) = [e for e in candidates_for(build({})) if e.name == "dead_volume@out"]
    params = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0),
              "Vtank.V": (250.0, 50.0, 600.0), **dead.params}
    zs = {k: [] for k in TRUTH}
    for seed in range(11, 11 + args.n):
        rec = oscillator_record(52.0, dt=0.01, noise=0.3, seed=seed, V_out=3.0, Rvent=3.5,
                                V=200.0)
        rec = rec[rec["time_s"] >= 12.0 - 1e-9].iloc[::args.every].reset_index(drop=True)
        rec["time_s"] -= rec["time_s"].iloc[0]
        fit = fit_trace(build, rec, params, node="tank", effects=(dead,), x_start=TRUTH,
                        max_nfev=80)
        for k, true in TRUTH.items():
            lo, hi = fit.ci[k]
            zs[k].append(np.log(fit.values[k] / true) / (np.log(hi / lo) / 3.92))
        print(f"seed {seed}: " + ", ".join(f"{k} z {z[-1]:+.2f}" for k, z in zs.items()),
              flush=True)
    print("rms z: " + ", ".join(f"{k} {np.sqrt(np.mean(np.square(z))):.2f} "
                                f"({int(np.sum(np.abs(z) < 1.96))} of {len(z)} covering)"
                                for k, z in zs.items()))


if __name__ == "__main__":
    main()
