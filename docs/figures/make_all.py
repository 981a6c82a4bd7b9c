"""Regenerate docs/figures/gallery/: one example of every figure the CLI and the Python API
draw (shown in docs/gallery.md).  Run from anywhere (a few minutes on 2 cores):

    python docs/figures/make_all.py [NAME ...]     # all figures, or only those named

Each figure comes from the public plotting call the CLI uses, on the shipped netlists,
the paper's circuits and the sample data in examples/data/.
"""
from __future__ import annotations

import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "gallery"
ROOT = OUT.parents[2]
BENCH = ROOT / "examples" / "data" / "bench_axi.csv"
RECORDING = ROOT / "examples" / "data" / "oscillator_rec.csv"


def solution():
    """``pneunet run --plot`` / ``Solution.plot``."""
    from pneunet.netlist import parse_file

    parse_file(ROOT / "netlists" / "oscillator.pn").circuit.tran(20.0).plot(OUT / "solution.png")


def sweep():
    """``pneunet sweep --plot`` with one axis (plot_sweep) and two (plot_regime_map)."""
    from pneunet.design.circuits import oscillator
    from pneunet.design.regime import RegimeMeasure, plot_regime_map
    from pneunet.design.sweep import DeckMeasure, OscillationMeasure, grid, lin, run_sweep
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.design.sweep_plot import plot_sweep
    from pneunet.netlist.runner import measure_unit

    one = run_sweep(oscillator, grid(lin("Rout", 0.0, 3.0, 13)),
                    OscillationMeasure(t_stop=40.0), progress=False)
    plot_sweep(one.table, "Rout", OUT / "sweep_1d.png")
    netlist = NetlistBuilder(ROOT / "netlists" / "oscillator.pn")
    meas = run_sweep(netlist, grid(lin("Rvent", 1.0, 6.0, 11)), DeckMeasure(netlist),
                     progress=False)
    plot_sweep(meas.table, "Rvent", OUT / "sweep_meas.png",
               units={m.name: measure_unit(m) for m in netlist.deck().measures})
    two = run_sweep(oscillator, grid(lin("Rout", 0.2, 3.0, 8), lin("Rvent", 1.0, 6.0, 8)),
                    RegimeMeasure(), progress=False)
    plot_regime_map(two.table, "Rout", "Rvent", OUT / "regime_map.png")


def branches():
    """``pneunet branches --plot`` / ``plot_branches``."""
    from pneunet.physics.oscillator_branches import (OscillatorSpec, plot_branches,
                                                     stationary_branches)
    from pneunet.design.circuits import oscillator

    sol = oscillator({"Rout": 1.132}).tran(30.0)
    plot_branches(stationary_branches(OscillatorSpec(Rout=1.132)), OUT / "branches.png",
                  trajectory=(sol.pressure("tank"), sol.flow("X1")))


def design():
    """``plot_fill`` and ``plot_truth_table``."""
    from pneunet.design import sizing as design
    from pneunet.design.logic import plot_truth_table, truth_table
    from pneunet.netlist.builder import NetlistBuilder

    design.plot_fill(design.cylinder_volume(173, 20), 0.566, 596, 96, 296,
                     OUT / "fill_time.png", valve="axi")
    tt = truth_table(NetlistBuilder(ROOT / "netlists" / "inverter.pn"), {"in": "Pin"},
                     ["out1", "out2"], expected=lambda b: (1 - b[0], b[0]), t_settle=3)
    plot_truth_table(tt, OUT / "truth_table.png", title="two inverters (netlists/inverter.pn)")


def identify():
    """``pneunet fit --plots`` / ``pneunet.truth.valves.identify.plots.all_figures``."""
    from pneunet.truth.valves.identify import fit_valve, load_measurements
    from pneunet.truth.valves.identify.plots import all_figures

    all_figures(fit_valve(load_measurements(BENCH)), OUT / "identify")


def diagnose():
    """``pneunet diagnose --plots`` / ``Diagnosis.plots``."""
    from pneunet.truth.valves.diagnose import diagnose as run
    from pneunet.truth.valves.diagnose.scenarios import LIBRARY_SCENARIOS, bench, truth_model

    leaky = truth_model({"leak": LIBRARY_SCENARIOS["leak"]})  # the axi valve with a leak
    run(bench(leaky, seed=0), progress=False).plots(OUT / "diagnose")


def traces():
    """``pneunet fit-trace --plot`` (plot_fit) and ``--candidates --waterfall``
    (plot_waterfall, also ``TraceDiagnosis.plots``)."""
    from pneunet.design.circuits import oscillator
    from pneunet.truth.circuits import diagnose_trace, fit_trace, read_trace
    from pneunet.truth.circuits.plots import plot_fit, plot_waterfall

    data = read_trace(RECORDING)
    fit = fit_trace(oscillator, data, {"Rvent": (3.5, 1.0, 10.0)}, fixed={"Rout": 1.132})
    plot_fit(fit, data, OUT / "trace_fit.png")
    diag = diagnose_trace(oscillator, data, {"Rvent": (3.5, 1.0, 10.0), "V": (150, 50, 400)},
                          fixed={"Rout": 1.132}, effects=["dead_volume"], max_nfev=20)
    plot_waterfall(diag, OUT / "trace_waterfall.png")


def tornado():
    """``pneunet design … --yield N --tornado PNG`` / ``YieldResult.plot_tornado``: which
    spread moves each specification most (a 40-sample yield, p_close and R_vent spread)."""
    from pneunet.design import Problem, from_tolerances, yield_analysis

    problem = Problem(str(ROOT / "netlists" / "oscillator_design.pn"),
                      ["period=3s±0.3s", "swing>=130kPa"], workers=1)
    with problem:
        values = {"Rout": 1.2302, "Rvent": 2.359, "V": 114.67}
        spread = from_tolerances(problem, values, ["X1.pclose=±5kPa", "Rvent=±5%"])
        yield_analysis(problem, values, spread, n=40, seed=0).plot_tornado(OUT / "tornado.png")


def soft_robot():
    """``pneunet piping --plot`` / ``plot_piping`` (the paper's Fig. 1B arm, N = 4) and
    ``plot_control_lines`` (docs/soft-robot.md)."""
    from pneunet.design.piping import (control_line_delays, piping_study, plot_control_lines,
                                       plot_piping)

    plot_piping(piping_study(), OUT / "piping.png")
    plot_control_lines(control_line_delays(lengths=(500, 1000, 2000, 4000, 8000)),
                       OUT / "control_lines.png")


def mckibben():
    """``plot_muscle_run``: the paper's Fig. 12 run (netlists/fig12_mckibben.pn, 50 s)."""
    from pneunet.design.muscle import plot_muscle_run
    from pneunet.netlist import parse_file

    sol = parse_file(ROOT / "netlists" / "fig12_mckibben.pn").circuit.tran(50.0, t_step=0.01)
    plot_muscle_run(sol, "M1", ("tank", "out"), OUT / "fig12_mckibben.png",
                    title="Fig. 12: oscillator driving a 53 cm McKibben lifting 200 g")


SCHEMATICS = ("fill_time", "amplifier", "oscillator", "inverter", "demux3", "demux6")
#: netlists with subcircuit instances: drawn as boxes (the default) and --expand
EXPANDED = ("inverter", "demux3", "demux6", "oscillators100")


def schematics():
    """``pneunet draw``: the paper's circuits; the oscillator also at 12.5 s of its run;
    those with subcircuits also expanded."""
    from pneunet.interfaces.cli import main

    for name in SCHEMATICS + EXPANDED[3:]:
        main(["draw", str(ROOT / "netlists" / f"{name}.pn"),
              "-o", str(OUT / "schematic" / f"{name}.svg")])
    for name in EXPANDED:
        main(["draw", str(ROOT / "netlists" / f"{name}.pn"), "--expand",
              "-o", str(OUT / "schematic" / f"{name}_expanded.svg")])
    main(["draw", str(ROOT / "netlists" / "oscillator.pn"), "--at", "12.5s",
          "-o", str(OUT / "schematic" / "oscillator_at12.5s.svg")])


FIGURES = {f.__name__: f for f in (solution, sweep, branches, design, identify, diagnose,
                                   traces, tornado, soft_robot, mckibben, schematics)}

if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    for name in sys.argv[1:] or FIGURES:
        FIGURES[name]()
        print("done:", name, flush=True)
