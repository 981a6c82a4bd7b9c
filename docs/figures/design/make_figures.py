"""Regenerate the figures of docs/design.md (except regime_map.png, written by the
`pneunet sweep` command shown there).  Run from the repository root:

    python docs/figures/design/make_figures.py [--skip-demux]
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent
ROOT = OUT.parents[2]


def branches():
    from pneunet.physics.oscillator_branches import (OscillatorSpec, plot_branches,
                                                     stationary_branches)
    from pneunet.design.circuits import oscillator

    for name, rout in (("branches_rout0.png", 0.0), ("branches_rout2rf.png", 1.132)):
        b = stationary_branches(OscillatorSpec(Rout=rout))
        sol = oscillator({"Rout": rout}).tran(30)
        plot_branches(b, OUT / name, trajectory=(sol.pressure("tank"), sol.flow("X1")))
        print(name, json.dumps({k: b.as_dict()[k] for k in ("turning_points", "equilibria",
                                                            "regime")}))


def oscillation():
    from pneunet.physics.oscillator_branches import stationary_branches
    from pneunet.design.circuits import oscillator
    from pneunet.engine.oscillation import oscillator_period
    from pneunet.common.plotting import pyplot, save

    res = oscillator_period(oscillator(), "tank")
    o, sol = res.oscillation, res.solution
    b = stationary_branches()
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(sol.t, sol.pressure("tank"), label="p_c (tank)")
    ax.plot(sol.t, sol.pressure("out"), lw=0.8, label="p_out (valve output)")
    for v, lab in ((b.p_c_min, "p_c,min from branches"), (b.p_c_max, "p_c,max from branches")):
        ax.axhline(v, color="crimson", ls="--", lw=0.8)
        ax.text(0.2, v + 3, f"{lab}: {v:.2f} kPa", color="crimson", fontsize=8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pressure (kPa abs)")
    ax.set_title(f"oscillator_period: {o.kind}, period {o.period_s:.4f} s, duty {o.duty_cycle:.2f}, "
                 f"p_c {o.p_min:.2f}–{o.p_max:.2f} kPa ({res.t_simulated:g} s simulated)",
                 fontsize=9)
    ax.legend(fontsize=8, loc="upper right")
    save(fig, OUT / "oscillator_period.png")
    print("oscillator_period", o.period_s, o.p_min, o.p_max, res.t_simulated)


def tolerance():
    from pneunet.design.circuits import oscillator
    from pneunet.design.sweep import OscillationMeasure, latin_hypercube, run_sweep, tolerance
    from pneunet.common.plotting import pyplot, save

    pts = latin_hypercube({"X1.pclose": tolerance(96.42, 5)}, 24, seed=3)
    r = run_sweep(oscillator, pts, OscillationMeasure(), workers=2, progress=False)
    t = r.table.sort_values("X1.pclose")
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(8, 3.2))
    ax[0].plot(t["X1.pclose"], t["period_s"], "o-")
    ax[0].set_xlabel("p_close (kPa), LHS over 96.42 ± 5")
    ax[0].set_ylabel("period (s)")
    ax[1].plot(t["X1.pclose"], t["p_min"], "o-", label="p_c,min")
    ax[1].plot(t["X1.pclose"], t["p_max"], "s-", label="p_c,max")
    ax[1].set_xlabel("p_close (kPa)")
    ax[1].set_ylabel("kPa abs")
    ax[1].legend(fontsize=8)
    fig.suptitle("oscillator under a fabrication tolerance of p_close (24-point Latin hypercube)",
                 fontsize=9)
    fig.tight_layout()
    save(fig, OUT / "tolerance_pclose.png")
    print("tolerance", t[["X1.pclose", "period_s", "p_min", "p_max"]].describe().loc[["min", "max"]])


def fill():
    from pneunet.design import sizing as design

    V = design.cylinder_volume(173, 20)
    design.plot_fill(V, 0.566, 596, 96, 296, OUT / "fill_time.png", valve="axi")
    print("fill", design.fill_time(V, 0.566, 596, 96, 296),
          design.simulated_fill_time(V, 0.566, 596, 96, 296),
          design.simulated_fill_time(V, None, 596, 96, 296, valve="axi"))


def logic(demux=True):
    from pneunet.design.circuits import nor_gate
    from pneunet.design.logic import demux_expected, plot_truth_table, truth_table
    from pneunet.netlist.builder import NetlistBuilder

    tt = truth_table(NetlistBuilder(ROOT / "netlists" / "inverter.pn"), {"in": "Pin"},
                     ["out1", "out2"], expected=lambda b: (1 - b[0], b[0]), t_settle=3)
    print(tt.table.to_string(), tt.margins.to_string(), sep="\n")
    tt = truth_table(nor_gate, {"A": "PA", "B": "PB"}, ["y"], t_settle=3,
                     expected=lambda b: (int(not (b[0] or b[1])),))
    print(tt.table.to_string(), tt.margins.to_string(), sep="\n")
    if demux:
        tt = truth_table(NetlistBuilder(ROOT / "netlists" / "demux3.pn"),
                         {"a0": "PA[0]", "a1": "PA[1]", "a2": "PA[2]"},
                         [f"act[{k}]" for k in range(8)], expected=demux_expected, t_settle=6)
        print(tt.table.to_string(), tt.margins.to_string(), sep="\n")
        plot_truth_table(tt, OUT / "demux3_truth_table.png",
                         title="3-bit demultiplexer (netlists/demux3.pn): actuator pressures")


if __name__ == "__main__":
    branches()
    oscillation()
    fill()
    tolerance()
    logic(demux="--skip-demux" not in sys.argv)
