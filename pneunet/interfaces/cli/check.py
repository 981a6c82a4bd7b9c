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
    p.add_argument("--verbose", "-v", action="store_true",
                   help=f"list every node and element (by default at most {LISTED} of each)")
    p.add_argument("--draw", metavar="OUT",
                   help="also draw the schematic (.svg, .png or .pdf; as pneunet draw)")
    from .draw import add_expand

    add_expand(p)
    netlist_args.add(p)
    p.set_defaults(func=main)


#: nodes and element names listed without --verbose (a 10,000-cell array has 30,000 nodes)
LISTED = 20


def main(args) -> int:
    from ...netlist import parse_file

    deck = parse_file(args.netlist, **netlist_args.parse_options(args))
    deck.validate()
    netlist_args.check_nodes(deck.circuit, args.strict)
    if args.draw:
        from .draw import check_format

        check_format(args.draw)
        deck.draw(args.draw, expand=args.expand)
    print(f"{args.netlist}: ok")
    print(summary(deck.circuit, args.verbose))
    analyses = ", ".join(f".{a.kind}" for a in deck.analyses) or "none"
    print(f"  analyses: {analyses}")
    for tran in (a for a in deck.analyses if a.kind == "tran"):
        from ...engine.simulate import transient_method

        print(f"  transient: {transient_method(deck.circuit, (tran.t_start, tran.t_stop))}")
    if deck.steps:
        print("  steps: " + " x ".join(f"{s.param} ({len(s.values)})" for s in deck.steps))
    if deck.measures:
        print("  measurements: " + ", ".join(m.name for m in deck.measures))
    return 0


def summary(circuit, verbose: bool = False) -> str:
    """Counts of nodes and elements (by kind), then their names: at most :data:`LISTED` of
    each unless ``verbose``."""
    kinds: dict[str, int] = {}
    for e in circuit.elements.values():
        kinds[e.kind] = kinds.get(e.kind, 0) + 1
    nodes = circuit.nodes
    lines = [f"circuit {circuit.title!r}: {len(nodes)} nodes, {len(circuit.elements)} elements"]
    lines += [f"  {k}: {v}" for k, v in sorted(kinds.items())]
    lines.append(_names("nodes", nodes, verbose))
    lines.append(_names("elements", list(circuit.elements), verbose))
    return "\n".join(lines)


def _names(label: str, names: list, verbose: bool) -> str:
    shown = names if verbose else names[:LISTED]
    more = len(names) - len(shown)
    return f"  {label}: " + " ".join(shown) + (f" … and {more} more (--verbose lists all)"
                                               if more else "")
