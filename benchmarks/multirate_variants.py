"""Multirate accuracy away from bench_scaling's parameters (issue 18: generalise, don't tune).

The coupling's settings (first window, Anderson depth, acceptance in local tolerances)
were measured on bench_scaling's network.  This study reruns the same cell structure
with other supply, line, actuator, vent and control values and other schedules (delays
uniform in 0.1–3.0 s, seeded; pulses 1.3 s wide every 2.7 s), and prints for each the
largest actuator and line pressure errors (kPa) of multirate and of single-rate IDA at
rtol 5e-6 against single-rate IDA at rtol = atol = 1e-8, with both times and the sweeps.

Run:  python benchmarks/multirate_variants.py [--cells 120] [--t-stop 8]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

AMBIENT = 101.325
#: (line mL per cell, actuator mL, vent kPa·s/mg, control kPa·s/mg, seed): a stiff hub
#: (5 mL per cell), a soft one (40 mL), and the stiffest (2 mL) with its own schedule
VARIANTS = [(5, 20, 1.0, 2.0, 1), (40, 80, 6.0, 8.0, 2), (2, 30, 2.0, 3.0, 3)]


def build(n, method, rtol, v_line, v_act, r_vent, r_ctl, seed):
    """N cells on one supply line; every cell its own control delay."""
    from pneunet import Circuit
    from pneunet.physics.waveforms import Pulse

    delays = np.random.default_rng(seed).uniform(0.1, 3.0, n)
    c = Circuit("multirate variant", rtol=rtol, atol=min(rtol, 1e-5), ambient=AMBIENT,
                method=method)
    c.pressure_source("PS", "sup", 450.0)
    c.resistor("RS", "sup", "line", R=0.5 / n)
    c.volume("VL", "line", V=f"{v_line * n}mL", p0=450.0)
    for k, delay in enumerate(delays):
        c.pressure_source(f"PC{k}", f"c{k}", Pulse(AMBIENT, 380.0, delay=delay, rise=0.02,
                                                  fall=0.08, width=1.3, period=2.7))
        c.resistor(f"RC{k}", f"c{k}", f"ctl{k}", R=r_ctl)
        c.volume(f"VC{k}", f"ctl{k}", V="6mL")
        c.valve(f"X{k}", "line", f"act{k}", f"ctl{k}", model="axi")
        c.volume(f"VA{k}", f"act{k}", V=f"{v_act}mL")
        c.resistor(f"RV{k}", f"act{k}", "atm", R=r_vent)
    return c


def errors(sol, ref, n):
    """Largest actuator and line pressure differences (kPa) on sol's output grid."""
    def off(node):
        return np.abs(sol.pressure(node) - np.interp(sol.t, ref.t, ref.pressure(node))).max()
    return max(off(f"act{k}") for k in range(n)), off("line")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=120)
    ap.add_argument("--t-stop", type=float, default=8.0)
    args = ap.parse_args(argv)
    n, t_stop = args.cells, args.t_stop
    print(f"{n} cells, {t_stop:g} s, rtol 5e-6; errors (kPa) against single-rate IDA at rtol 1e-8")
    print(f"{'variant (line, act, Rvent, Rctl, seed)':>40} | {'method':>9} {'s':>6} "
          f"{'act err':>8} {'line err':>8} {'sweeps':>6}")
    for variant in VARIANTS:
        ref = build(n, "single", 1e-8, *variant).tran(t_stop, t_step=0.05)
        for method in ("multirate", "single"):
            start = time.perf_counter()
            sol = build(n, method, 5e-6, *variant).tran(t_stop, t_step=0.05)
            wall = time.perf_counter() - start
            act, line = errors(sol, ref, n)
            print(f"{str(variant):>40} | {method:>9} {wall:6.2f} {act:8.3f} {line:8.3f} "
                  f"{sol.stats.get('sweeps', ''):>6}")


if __name__ == "__main__":
    main()
