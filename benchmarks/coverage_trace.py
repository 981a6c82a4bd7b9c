"""Coverage of the circuit-recording fit on clean recordings made as a logger makes them.

Each recording comes from a stand-alone model (tests/traces/standalone.py,
standalone_driven.py: scipy's Radau on equations written out by hand, nothing of
pneunet) with random parameters, started at a random time after switch-on (the logger's
own start), 0.2–0.5 kPa of white noise:

* ``oscillator``: the paper's oscillator (R_out 0.9–1.6, R_vent 2–5, V 40–150 mL random,
  drawn again where it does not oscillate), recorded at 20 Hz
  for 30 s from a random time 5–25 s after switch-on (after its first cycle), p_tank
  and p_out, time counted from the first sample; fitted R_out, R_vent, V;
* ``driven``: the flow amplifier filling a 15–60 mL actuator through a 0.1–0.5
  kPa·s/mg line (netlists/amplifier.pn, valves switched by antiphase pulses every 5 s),
  recorded at 100 Hz for 30 s from a random time 0–20 s on the sources' clock, p_act
  and p_muscle; fitted the line's R and the actuator's V;
* ``driven-own-clock``: the same recordings with the logger's own clock (time from 0 at
  the first sample): the sources' phase is found from the record and fitted (each JSON
  line's ``first_sample_off_ms``: how far it ends from the truth).

Every recording is diagnosed (``diagnose_trace``: start state chosen automatically,
candidates screened when the base model is not adequate).  Printed: per circuit the
share of 95 % intervals covering the truth (target 90–98 %), the mean interval width
against the spread of the estimates (|estimate − truth| / standard error: its rms is 1
for honest widths), and the share of ``adequate`` verdicts (target ≥ 95 %).

    python benchmarks/coverage_trace.py                      # 40 × 3 recordings (~35 min)
    python benchmarks/coverage_trace.py --n 10 --circuit driven-own-clock
    options: --seed N, --dt S (sample spacing), --out results.jsonl (one line per
    recording, appended)
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OSC_PARAMS = {"Rout": (1.4, 0.3, 5.0), "Rvent": (3.8, 0.5, 20.0), "V": (90.0, 5.0, 500.0)}
DRIVEN_PARAMS = {"Rtube.R": (0.25, 0.02, 2.0), "Amck.V": (35.0, 5.0, 200.0)}


def oscillator_case(rng, dt=None):
    """(recording, truth, fit parameters, build, cycle node, its draws), sampled every
    ``dt`` s (default 0.05)."""
    from pneunet.design.circuits import oscillator
    from tests.traces.standalone import oscillator_record

    while True:  # parameters where the circuit oscillates (a 30 kPa swing or more)
        truth = {"Rout": float(rng.uniform(0.9, 1.6)), "Rvent": float(rng.uniform(2.0, 5.0)),
                 "V": float(np.exp(rng.uniform(np.log(40.0), np.log(150.0))))}
        start = float(rng.uniform(5.0, 25.0))
        noise = float(rng.uniform(0.2, 0.5))
        rec = oscillator_record(start + 30.0, dt=dt or 0.05, noise=noise,
                                seed=int(rng.integers(1 << 30)), **truth)
        rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
        if np.ptp(rec["p_tank_kPa"]) > 30.0:
            break
    rec["time_s"] -= rec["time_s"].iloc[0]
    return rec, truth, OSC_PARAMS, oscillator, "tank", {"start_s": start, "noise": noise}


def driven_case(rng, dt=None):
    from pneunet.netlist.builder import NetlistBuilder
    from tests.traces.standalone_driven import amplifier_record

    truth = {"Rtube.R": float(np.exp(rng.uniform(np.log(0.1), np.log(0.5)))),
             "Amck.V": float(np.exp(rng.uniform(np.log(15.0), np.log(60.0))))}
    start = float(rng.uniform(0.0, 20.0))
    noise = float(rng.uniform(0.2, 0.5))
    dt = dt or 0.01
    rec = amplifier_record(start, 30.0, dt=dt, noise=noise, seed=int(rng.integers(1 << 30)),
                           R_line=truth["Rtube.R"], V=truth["Amck.V"])
    return (rec, truth, DRIVEN_PARAMS, NetlistBuilder(str(ROOT / "netlists" / "amplifier.pn")),
            "muscle", {"start_s": start, "noise": noise})


def driven_own_clock_case(rng, dt=None):
    """The driven case with the logger's own clock: time counted from the first sample."""
    rec, *rest = driven_case(rng, dt)
    rec["time_s"] -= rec["time_s"].iloc[0]
    return (rec, *rest)


CIRCUITS = {"oscillator": oscillator_case, "driven": driven_case,
            "driven-own-clock": driven_own_clock_case}
#: the driven circuit's sources' period, s (its first sample's phase is checked)
DRIVEN_PERIOD = 10.0
#: a circuit whose recordings are another's (the same random draws): one clock or the other
SAME_RECORDINGS = {"driven-own-clock": "driven"}


def run_one(kind, rng, dt=None):
    from pneunet.truth.circuits import diagnose_trace

    rec, truth, params, build, node, info = CIRCUITS[kind](rng, dt)
    t0 = time.perf_counter()
    d = diagnose_trace(build, rec, params, node=node)
    wall = time.perf_counter() - t0
    fit = d.base
    rows = {}
    for k, v in truth.items():
        lo, hi = fit.ci[k]
        se = fit.stderr_log[k]
        rows[k] = {"truth": v, "estimate": float(fit.values[k]), "ci": [lo, hi],
                   "covered": bool(lo <= v <= hi),
                   "z": float(math.log(fit.values[k] / v) / se) if se > 0 else None}
    if fit.start_state.driven:  # how far the first sample's netlist time is off, ms
        off = (fit.start_state.first_time - info["start_s"]) % DRIVEN_PERIOD
        info["first_sample_off_ms"] = 1e3 * min(off, DRIVEN_PERIOD - off)
    return {"circuit": kind, **info, "verdict": d.verdict, "accepted": d.accepted,
            "start": fit.start_state.mode, "params": rows, "wall_s": wall,
            "base_ratio": d.waterfall.steps[0].held_out / d.noise_floor}


def summary(results) -> str:
    lines = ["| circuit | recordings | intervals covering the truth | rms z (1 = honest width) "
             "| adequate | start states | median s (max) |",
             "|---|---|---|---|---|---|---|"]
    for kind in CIRCUITS:
        mine = [r for r in results if r["circuit"] == kind]
        if not mine:
            continue
        cov = [p["covered"] for r in mine for p in r["params"].values()]
        zs = [p["z"] for r in mine for p in r["params"].values() if p["z"] is not None]
        per = {k: np.mean([r["params"][k]["covered"] for r in mine]) for k in mine[0]["params"]}
        starts = {m: sum(r["start"] == m for r in mine) for m in ("rest", "record", "settled")}
        walls = [r["wall_s"] for r in mine]
        lines.append(
            f"| {kind} | {len(mine)} | {100 * np.mean(cov):.0f} % ("
            + ", ".join(f"{k} {100 * v:.0f} %" for k, v in per.items())
            + f") | {math.sqrt(np.mean(np.square(zs))):.2f} | "
            f"{100 * np.mean([r['verdict'] == 'adequate' for r in mine]):.0f} % | "
            + ", ".join(f"{k} {v}" for k, v in starts.items() if v)
            + f" | {np.median(walls):.1f} ({max(walls):.0f}) |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=40, help="recordings per circuit (40)")
    ap.add_argument("--circuit", choices=list(CIRCUITS), action="append", default=None)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--dt", type=float, default=None,
                    help="sample spacing, s (default 0.05 for the oscillator, 0.01 driven)")
    ap.add_argument("--out", default=None, help="append one JSON line per recording here")
    args = ap.parse_args(argv)
    results = []
    for kind in args.circuit or list(CIRCUITS):
        rng = np.random.default_rng([args.seed,
                                     list(CIRCUITS).index(SAME_RECORDINGS.get(kind, kind))])
        for i in range(args.n):
            r = run_one(kind, rng, args.dt)
            results.append(r)
            flags = " ".join(f"{k}={'ok' if p['covered'] else 'MISS'}"
                             for k, p in r["params"].items())
            print(f"{kind} {i + 1}/{args.n}: start {r['start_s']:.1f} s ({r['start']}), "
                  f"{r['verdict']}, base {r['base_ratio']:.2f}× floor, {flags}, "
                  + (f"first sample {r['first_sample_off_ms']:.2g} ms off, "
                     if "first_sample_off_ms" in r else "")
                  + f"{r['wall_s']:.1f} s", flush=True)
            if args.out:
                with open(args.out, "a") as fh:
                    fh.write(json.dumps(r) + "\n")
    print(summary(results))


if __name__ == "__main__":
    main()
