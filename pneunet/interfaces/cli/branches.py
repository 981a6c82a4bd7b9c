"""``pneunet branches``: stationary branches of the oscillator (paper Fig. 11)."""
from __future__ import annotations

import json

from . import netlist_args
from .numbers import real
from .outputs import output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "branches", help="stationary branches, turning points and predicted cycle of an oscillator",
        description="Trace the admissible stationary (p_c, mdot) curve of the valve + R_out "
                    "subsystem (eqs. 27-28) by pseudo-arclength continuation, find its "
                    "turning points and equilibria with the vented volume (eq. 29), and "
                    "predict the regime and p_c,min/max. The circuit comes from a netlist "
                    "(the oscillator is recognised in it) or from the options below.")
    p.add_argument("netlist", nargs="?", metavar="FILE.pn", help="netlist with the oscillator")
    p.add_argument("--node", default=None, help="control node of the oscillator (netlist)")
    p.add_argument("--pH", type=real(above=0, unit=" kPa"), default=496.0, help="supply pressure, kPa abs (496)")
    p.add_argument("--pL", type=real(above=0, unit=" kPa"), default=96.0, help="vent pressure, kPa abs (96)")
    p.add_argument("--rout", type=real(above=0, unit=" kPa*s/mg"), default=1.132, help="R_out, kPa*s/mg (1.132 = 2 R_f)")
    p.add_argument("--rvent", type=real(above=0, unit=" kPa*s/mg"), default=3.0, help="R_vent, kPa*s/mg (3)")
    p.add_argument("--valve", default="axi", help="paper valve name (axi, mirror, ...)")
    p.add_argument("--simulate", type=real(0, unit=" s"), default=0.0, metavar="S",
                   help="also simulate S seconds and overlay the trajectory / compare extremes")
    p.add_argument("--plot", metavar="PNG", default=None, type=output_file(plot=True), help="write the Fig. 11 style plot")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    netlist_args.add(p)
    p.set_defaults(func=main)


def main(args) -> int:
    from ...physics.oscillator_branches import (OscillatorSpec, plot_branches, spec_from_circuit,
                                                stationary_branches)

    circuit = None
    if args.netlist:
        from ...netlist import parse_file

        circuit = parse_file(args.netlist, **netlist_args.parse_options(args)).circuit
        netlist_args.check_nodes(circuit, args.strict)
        spec = spec_from_circuit(circuit, args.node)
    else:
        spec = OscillatorSpec(pH=args.pH, pL=args.pL, Rout=args.rout, Rvent=args.rvent,
                              valve=args.valve)
    b = stationary_branches(spec)
    out = b.as_dict()
    traj = None
    if args.simulate:
        if circuit is None:
            from ...design.circuits import oscillator

            circuit = oscillator({"pH": spec.pH, "pL": spec.pL, "Rout": spec.Rout,
                                  "Rvent": spec.Rvent, "valve": args.valve})
        node = args.node or "tank"
        sol = circuit.tran(args.simulate, progress=not (args.no_progress or args.json
                                                       or args.quiet))
        from ...engine.oscillation import analyze_oscillation

        osc = analyze_oscillation(sol.t, sol.pressure(node))
        out["simulated"] = {k: v for k, v in osc.as_dict().items()}
        out["simulated"]["solver_messages"] = sol.stats.get("solver_diagnostics", {"count": 0})
        flow_key = next((k for k in sol.signals if k.startswith("mdot_") and k[5:] in circuit.elements
                         and circuit.elements[k[5:]].kind == "valve"), None)
        if flow_key:
            traj = (sol.pressure(node), sol[flow_key])
    if args.plot:
        out["plot"] = str(plot_branches(b, args.plot, trajectory=traj))
    if args.json:
        print(json.dumps(out, indent=1, default=float))
        return 0
    print(f"R_out = {spec.Rout:g}, R_vent = {spec.Rvent:g} kPa*s/mg, p_H = {spec.pH:g}, "
          f"p_L = {spec.pL:g} kPa: {b.regime}")
    print(f"valve closed (mdot = 0) for p_c >= {b.closed_from:.2f} kPa")
    for tp in b.turning_points:
        print(f"turning point: p_c = {tp.p_c:.2f} kPa, mdot = {tp.mdot:.2f} mg/s")
    for eq in b.equilibria:
        print(f"equilibrium ({'stable' if eq.stable else 'unstable'}): p_c = {eq.p_c:.3f} kPa, "
              f"mdot = {eq.mdot:.2f} mg/s")
    if b.regime == "oscillation":
        print(f"predicted cycle: p_c,min = {b.p_c_min:.2f} kPa, p_c,max = {b.p_c_max:.2f} kPa")
    if "simulated" in out:
        s = out["simulated"]
        print(f"simulated: {s['kind']}, p_min = {s['p_min']:.2f}, p_max = {s['p_max']:.2f} kPa, "
              f"period = {s['period_s']:.4g} s")
    if args.plot:
        print(f"plot -> {out['plot']}")
    return 0
