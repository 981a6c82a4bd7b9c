"""``pneunet draw FILE.pn -o circuit.svg``: the circuit's schematic, optionally with the
node pressures and element flows of an operating point (``--op``) or of the netlist's
transient at one time (``--at 12.5s``)."""
from __future__ import annotations

from . import netlist_args

FORMATS = (".svg", ".png", ".pdf")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "draw", help="draw the circuit's schematic (SVG, PNG, PDF), optionally with results",
        description="Draw a netlist's schematic: ISO 1219-1 style symbols, flow from the "
                    "supply (left) to the exhaust (right), control lines dashed; an array "
                    "is drawn once with its count; each subcircuit instance is a box "
                    "(--expand: its elements). --op or --at write each node's pressure "
                    "(kPa absolute) and each element's flow (mg/s) on it.")
    p.add_argument("netlist", metavar="FILE.pn", help="netlist file")
    p.add_argument("-o", "--output", required=True, metavar="OUT",
                   help="the drawing: .svg, .png or .pdf (by the suffix)")
    add_expand(p)
    when = p.add_mutually_exclusive_group()
    when.add_argument("--op", action="store_true", help="annotate the operating point")
    when.add_argument("--at", metavar="TIME",
                      help="annotate the netlist's .tran at TIME (e.g. 12.5s; simulated from "
                           "its start to TIME)")
    netlist_args.add(p)
    p.set_defaults(func=main)


def add_expand(p) -> None:
    p.add_argument("--expand", action="store_true",
                   help="draw the elements inside each subcircuit instance, not a box")


def check_format(path: str) -> None:
    """Exit 2 unless ``path`` ends in a drawing format."""
    from ...common.errors import ParameterError

    if not path.lower().endswith(FORMATS):
        raise ParameterError(f"{path}: unknown drawing format",
                             hint="end the name in " + ", ".join(FORMATS))


def main(args) -> int:
    from ...netlist import parse_file

    check_format(args.output)
    deck = parse_file(args.netlist, **netlist_args.parse_options(args))
    deck.validate()
    netlist_args.check_nodes(deck.circuit, args.strict)
    results = None
    if args.op:
        results = deck.circuit.op(stability=False)
    elif args.at is not None:
        results = _transient_at(deck, args.at)
    lay = deck.draw(args.output, results=results, expand=args.expand)
    symbols = sum(1 for b in lay.boxes if b[0] == "symbol")
    print(f"wrote {args.output}: {symbols} symbols, {len(lay.overlaps())} overlaps, "
          f"{lay.crossings()} wire crossings")
    return 0


def _transient_at(deck, text: str):
    """``(Solution, t)``: the deck's .tran from its start to ``t`` (s)."""
    from ...common.errors import ParameterError
    from ...netlist.deck import Tran
    from ...physics.units import split_quantity, to_internal

    try:
        q = split_quantity(text.strip())
        t = float(to_internal(q.magnitude, q.unit or "s", "time", name="--at"))
    except (ParameterError, ValueError, TypeError):
        raise ParameterError(f"--at {text!r}: not a time", hint="e.g. --at 12.5s or --at 500ms") \
            from None
    tran = next((a for a in deck.analyses if isinstance(a, Tran)), None)
    if tran is None:
        raise ParameterError(f"--at {text}: {deck.file or 'the netlist'} has no .tran",
                             hint="add a .tran line, or use --op")
    if not tran.t_start < t <= tran.t_stop:
        raise ParameterError(f"--at {text}: outside the .tran interval "
                             f"({tran.t_start:g} s, {tran.t_stop:g} s]",
                             hint="give a time within it")
    sol = deck.circuit.tran(t, t_step=tran.t_step, t_start=tran.t_start,
                            max_output_points=deck.source.limits.max_output_points)
    return sol, t
