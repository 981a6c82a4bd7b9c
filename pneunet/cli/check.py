"""``pneunet check FILE.pn``: parse and validate a netlist, print a summary."""
from __future__ import annotations

from . import netlist_args


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "check", help="parse and validate a netlist, print its nodes and elements",
        description="Parse and validate a netlist without simulating it: syntax, units, "
                    "parameter ranges, subcircuits, includes and the circuit's topology. "
                    "Exit code 0 if it is fine, 2 with file:line:column and a caret if not.")
    p.add_argument("netlist", metavar="FILE.pn", help="netlist file")
    netlist_args.add(p)
    p.set_defaults(func=main)


def main(args) -> int:
    from ..netlist import parse_file

    deck = parse_file(args.netlist, **netlist_args.parse_options(args))
    deck.validate()
    netlist_args.check_nodes(deck.circuit, args.strict)
    print(f"{args.netlist}: ok")
    print(deck.circuit.summary())
    analyses = ", ".join(f".{a.kind}" for a in deck.analyses) or "none"
    print(f"  analyses: {analyses}")
    if deck.steps:
        print("  steps: " + " x ".join(f"{s.param} ({len(s.values)})" for s in deck.steps))
    if deck.measures:
        print("  measurements: " + ", ".join(m.name for m in deck.measures))
    return 0
