"""The trace diagnosis on stand-alone recordings: one row per hidden physics.

Each recording comes from a model written out by hand and integrated by scipy
(tests/traces/standalone.py, standalone_driven.py: nothing of pneunet's effect code):

* ``oscillator`` cases: the paper's oscillator (R_out 1.132, R_vent 3, V 50 mL), 12 s
  = 8 cycles at 20 Hz, p_tank and p_out, 0.4 kPa noise; with ``--mid-run`` the logger
  starts at a random time 2–10 s after switch-on (after the first cycle), its clock
  restarted at 0.  Fitted R_out, R_vent, V from guesses 20–30 % off.
* ``driven`` cases: the flow amplifier (netlists/amplifier.pn) filling a 30 mL
  actuator through a 0.24 kPa·s/mg line (the netlist says 0.2), both valves switched by
  antiphase pulses every 5 s, recorded at 100 Hz for 30 s from a random time 0–20 s on
  the sources' clock, p_act and p_muscle, 0.3 kPa noise.  Fitted the line's R and V.
  With ``--once`` its pulses switch once (netlists/amplifier_once.pn: inflated at 5 s,
  deflated at 10 s), 15 s recorded from a random time 0–9 s.  ``--own-clock``: the
  driven cases' time column restarted at 0 (the logger's own clock).
* ``inverter`` cases: the chain of two inverters (netlists/inverter.pn; generator
  tests/traces/standalone_inverter.py) with R_pull 23 kPa·s/mg (the netlist says 20),
  the first gate's control a 4 s PULSE, recorded at 50 Hz for 20 s from a random time
  0–8 s on the sources' clock, p_out1 and p_out2, 0.3 kPa noise.  Fitted R_pull and both
  output volumes.  A dead volume at out1 is more of out1's fitted volume: the right
  answer there is ``adequate`` with X1.Vout.V at 2 mL + the dead volume.

Every registered circuit effect is a candidate.

    python benchmarks/study_trace_diagnosis.py                 # every oscillator case
    python benchmarks/study_trace_diagnosis.py --mid-run       # the same, started mid-run
    python benchmarks/study_trace_diagnosis.py --driven        # the driven circuit's cases
    python benchmarks/study_trace_diagnosis.py --inverter      # the inverter chain's cases
    python benchmarks/study_trace_diagnosis.py --driven --once --own-clock
    python benchmarks/study_trace_diagnosis.py clean side      # some cases
    options: --seed N
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

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

#: driven case → (stand-alone keywords, what a right answer is)
DRIVEN = {
    "clean": ({}, "adequate"),
    "heat-transfer": ({"heat_tau": 1.0}, "volume_heat_transfer"),
    "dead-volume": ({"V_act": 6.0}, "dead_volume@act"),
    "control-tube": ({"tube_ctrl": (5.0, 5.0)}, "tube@Xin.ctrl"),
    "heat+control-tube": ({"heat_tau": 1.0, "tube_ctrl": (5.0, 5.0)},
                          "volume_heat_transfer + tube@Xin.ctrl"),
    "leak": ({"leak": 15.0}, "unexplained"),
    "compliant": ({"compliance": 0.004}, "unexplained"),
}
DRIVEN_PARAMS = {"Rtube.R": (0.2, 0.02, 2.0), "Amck.V": (25.0, 5.0, 200.0)}
DRIVEN_TRUTH = {"Rtube.R": 0.24, "Amck.V": 30.0}

#: inverter case → (stand-alone keywords, what a right answer is)
INVERTER = {
    "clean": ({}, "adequate"),
    "heat-transfer": ({"heat_tau": 0.5}, "volume_heat_transfer@X1.Vout"),
    "dead-volume": ({"dead_volume": 1.5}, "adequate"),  # X1.Vout.V fitted at 3.5 mL
    "control-tube": ({"tube_ctrl": (20.0, 1.0)}, "tube@X2.Xv.ctrl"),
    "leak": ({"leak": 40.0}, "unexplained"),
    "compliant": ({"compliance": 0.004}, "unexplained"),
}
INVERTER_PARAMS = {"Rpull": (20.0, 2.0, 200.0), "X1.Vout.V": (2.5, 0.2, 20.0),
                   "X2.Vout.V": (2.5, 0.2, 20.0)}
INVERTER_TRUTH = {"Rpull": 23.0, "X1.Vout.V": 2.0, "X2.Vout.V": 2.0}


def oscillator_case(name, seed, mid_run):
    from pneunet.design.circuits import oscillator
    from tests.traces.standalone import oscillator_record

    kw, expected = CASES[name]
    start = float(np.random.default_rng([seed, 7]).uniform(2.0, 10.0)) if mid_run else 0.0
    rec = oscillator_record(12.0 + start, noise=0.4, seed=seed, **kw)
    rec = rec[rec["time_s"] >= start - 1e-9].reset_index(drop=True)
    rec["time_s"] -= rec["time_s"].iloc[0]
    return rec, oscillator, PARAMS, "tank", expected, start


def driven_case(name, seed, once=False):
    """The amplifier's case ``name``; ``once``: its pulses switch once
    (netlists/amplifier_once.pn), 15 s recorded from 0–9 s after switch-on."""
    from pneunet.netlist.builder import NetlistBuilder
    from tests.traces.standalone_driven import amplifier_record

    kw, expected = DRIVEN[name]
    start = float(np.random.default_rng([seed, 8]).uniform(0.0, 9.0 if once else 20.0))
    rec = amplifier_record(start, 15.0 if once else 30.0, dt=0.01, noise=0.3, seed=seed,
                           R_line=DRIVEN_TRUTH["Rtube.R"], V=DRIVEN_TRUTH["Amck.V"],
                           once=once, **kw)
    netlist = "amplifier_once.pn" if once else "amplifier.pn"
    return (rec, NetlistBuilder(str(ROOT / "netlists" / netlist)), DRIVEN_PARAMS,
            "muscle", expected, start)


def inverter_case(name, seed):
    from pneunet.netlist.builder import NetlistBuilder
    from tests.traces.standalone_inverter import inverter_record

    kw, expected = INVERTER[name]
    start = float(np.random.default_rng([seed, 9]).uniform(0.0, 8.0))
    rec = inverter_record(start, 20.0, dt=0.02, noise=0.3, seed=seed,
                          Rpull=INVERTER_TRUTH["Rpull"], **kw)
    return (rec, NetlistBuilder(str(ROOT / "netlists" / "inverter.pn")), INVERTER_PARAMS,
            "out1", expected, start)


def inverter_truth(name) -> dict:
    """The values the right model of an inverter case has (its effect's too)."""
    kw = INVERTER[name][0]
    truth = dict(INVERTER_TRUTH)
    truth["X1.Vout.V"] += kw.get("dead_volume", 0.0)
    if "tube_ctrl" in kw:
        truth["R_tube@X2.Xv.ctrl"], truth["V_tube@X2.Xv.ctrl"] = kw["tube_ctrl"]
    if "heat_tau" in kw:
        truth["tau@X1.Vout"] = kw["heat_tau"]
    return truth


def covered(d, truth) -> str:
    """Which of the final fit's 95 % intervals cover the truth."""
    ci = d.final.ci
    return ", ".join(f"{k} {'ok' if ci[k][0] <= v <= ci[k][1] else 'MISS'}"
                     for k, v in truth.items() if k in ci)


def right(d, expected) -> bool:
    if expected in ("adequate", "unexplained"):
        return d.verdict == expected
    return d.verdict == "explained" and " + ".join(d.accepted) == expected \
        or d.verdict == "explained" and set(d.accepted) == set(expected.split(" + "))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mid-run", action="store_true", help="oscillator logger started mid-run")
    ap.add_argument("--driven", action="store_true", help="the driven amplifier's cases")
    ap.add_argument("--inverter", action="store_true", help="the inverter chain's cases")
    ap.add_argument("--once", action="store_true",
                    help="driven cases: pulses that switch once (netlists/amplifier_once.pn)")
    ap.add_argument("--own-clock", action="store_true",
                    help="driven cases: the logger's own clock (time_s from 0), not the sources'")
    args = ap.parse_args(argv)

    from pneunet.truth.circuits import diagnose_trace

    table = INVERTER if args.inverter else DRIVEN if args.driven else CASES
    print("| case | start s | expected | verdict | accepted | held-out / floor (base → final) | "
          "start state | right | time s (base, screen, fits) | simulations |"
          + (" 95 % intervals vs truth |" if args.inverter else ""))
    print("|---|---|---|---|---|---|---|---|---|---|" + ("---|" if args.inverter else ""))
    for name in args.cases or list(table):
        if args.inverter:
            rec, build, params, node, expected, start = inverter_case(name, args.seed)
        elif args.driven:
            rec, build, params, node, expected, start = driven_case(name, args.seed,
                                                                    args.once)
        else:
            rec, build, params, node, expected, start = oscillator_case(name, args.seed,
                                                                        args.mid_run)
        if args.own_clock:
            rec = rec.copy()
            rec["time_s"] = float(np.median(np.diff(rec["time_s"]))) * np.arange(len(rec))
        t0 = time.perf_counter()
        d = diagnose_trace(build, rec, params, node=node)
        wall = time.perf_counter() - t0
        steps = d.waterfall.steps
        ratio = f"{steps[0].held_out / d.noise_floor:.2f} → {steps[-1].held_out / d.noise_floor:.2f}"
        if steps[-1].worst > steps[-1].held_out:  # the fitted window's, where it is worse
            ratio += f" (fitted {steps[-1].worst / d.noise_floor:.2f})"
        noted = any("correlated from sample to sample" in n for n in d.notes)
        print(f"| {name} | {start:.1f} | {expected} | {d.verdict}"
              f"{' (coloured-noise note)' if noted else ''} | "
              f"{', '.join(d.accepted) or '–'} | {ratio} | {d.final.start_state.mode} | "
              f"{'yes' if right(d, expected) else 'NO'} | {wall:.0f} ("
              + ", ".join(f"{d.timing.get(k, 0):.0f}" for k in ("base_fit_s", "screen_s",
                                                                  "candidate_fits_s"))
              + f") | {d.timing.get('simulations', 0) + d.timing.get('screen_simulations', 0)} |"
              + (f" {covered(d, inverter_truth(name))} |" if args.inverter else "")
              + (f" first sample {_phase(d, start, build)} |" if args.own_clock else ""),
              flush=True)


def _phase(d, start, build) -> str:
    """How far the first sample's netlist time lies from the logger's true start, in ms
    (modulo the period of the netlist's sources where they have one)."""
    from pneunet.truth.circuits.clock import common_period, varying_waveforms

    circuit = build({})
    period = common_period(varying_waveforms(circuit, start, start + 100.0))
    if period is None:  # sources that change once
        return f"{abs(d.final.start_state.first_time - start) * 1e3:.2g} ms off"
    apart = (d.final.start_state.first_time - start) % period
    return f"{min(apart, period - apart) * 1e3:.2g} ms off"


if __name__ == "__main__":
    main()
