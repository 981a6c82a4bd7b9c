"""``pneunet piping``: the piping-footprint study of paper Fig. 1B (issue 12)."""
from __future__ import annotations

import json

from . import netlist_args
from .numbers import real, whole, within
from .outputs import output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "piping", help="tubing cross-section and fill times: individual lines, one supply "
                       "line + control lines, or a demultiplexer (Fig. 1B)",
        description="Compare, for a robot of N actuators at the end of LENGTH of tubing, one "
                    "power line per actuator (valves at the source) with one supply line + a "
                    "valve at each actuator + one thin control line each, and with a binary "
                    "demultiplexer (log2 N address lines). Prints the total tubing "
                    "cross-section (outer diameter and bore, mm2, and the saving) and the "
                    "simulated fill time of the actuators through their tubes. Defaults: the "
                    "paper's Fig. 1B arm as pneunet reads it (docs/soft-robot.md). "
                    "Example: pneunet piping --actuators 8 --length 1m --plot piping.png")
    p.add_argument("--actuators", "-n", type=whole(1), default=4, help="number of actuators (4)")
    p.add_argument("--length", default="1m", help="tube length source to robot (1m)")
    p.add_argument("--spacing", default="0mm",
                   help="distance between neighbouring actuators along the robot (0mm: all "
                        "at its base)")
    p.add_argument("--volume", default="50mL", help="volume of each actuator (50mL)")
    p.add_argument("--power", default="2.5/4", metavar="BORE/OUTER",
                   help="individual power lines, mm (2.5/4)")
    p.add_argument("--control", default="1.2/3", metavar="BORE/OUTER",
                   help="control and address lines, mm (1.2/3)")
    p.add_argument("--supply", default=None, metavar="BORE/OUTER",
                   help="the shared supply line, mm (default: as --power)")
    p.add_argument("--valve", default="axi", help="membrane valve of every design (axi)")
    p.add_argument("--pH", default="496kPa", help="supply pressure (496kPa)")
    p.add_argument("--pL", default="96kPa", help="ambient pressure (96kPa)")
    p.add_argument("--level", type=real(above=0, high=0.999), default=0.9,
                   help="filled: this fraction of the supply's gauge pressure (0.9)")
    p.add_argument("--designs", default="individual,supply+control,demux",
                   help="comma-separated designs to compare (all three)")
    p.add_argument("--plot", metavar="PNG", default=None, type=output_file(plot=True), help="write the figure")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--quiet", "-q", action="store_true", help="no warnings on stderr")
    netlist_args.add_limit(p)
    p.set_defaults(func=main)


def _quantity(text: str, slot: str, what: str) -> float:
    from ...common.errors import ParameterError
    from ...physics.units import split_quantity, to_internal

    q = split_quantity(text)
    try:
        return float(to_internal(q.magnitude, q.unit, slot, gauge=q.gauge, name=what))
    except ParameterError as err:
        raise ParameterError(f"--{what}: {err.message}", hint=err.hint) from None


def main(args) -> int:
    from ...design.piping import PipingSpec, piping_study, plot_piping, with_sizes

    within(args.actuators, "--actuators", netlist_args.limits(args), "max_elements")
    spacing = _quantity(args.spacing, "length", "spacing")
    spec = PipingSpec(actuators=args.actuators, length=_quantity(args.length, "length", "length"),
                      positions=tuple(k * spacing for k in range(max(args.actuators, 0))),
                      volume=_quantity(args.volume, "volume", "volume"), valve=args.valve,
                      p_supply=_quantity(args.pH, "pressure", "pH"),
                      ambient=_quantity(args.pL, "pressure", "pL"), level=args.level)
    sizes = {"power": args.power, "control": args.control}
    if args.supply:
        sizes["supply"] = args.supply
    spec = with_sizes(spec, **sizes)
    study = piping_study(spec, [d.strip() for d in args.designs.split(",") if d.strip()])
    out = study.as_dict()
    if args.plot:
        out["plot"] = str(plot_piping(study, args.plot))
    if args.json:
        print(json.dumps(out, indent=1, default=float))
        return 0
    along = f" (+ {spacing:g} mm per actuator along the robot)" if spacing else ""
    print(f"{spec.actuators} actuators of {spec.volume:g} mL, {spec.length:g} mm of tubing"
          f"{along}, supply {spec.p_supply:g} kPa, filled at {spec.filled:g} kPa")
    table = study.table.rename(columns={
        "outer_mm2": "outer mm2", "saving_outer_pct": "saving %", "bore_mm2": "bore mm2",
        "saving_bore_pct": "bore saving %", "fill_alone_min_s": "one: fastest s",
        "fill_alone_max_s": "slowest s", "fill_all_s": "all s"})
    print(table.to_string(float_format=lambda x: f"{x:.3g}"))
    if "plot" in out:
        print(f"plot: {out['plot']}")
    return 0
