"""Options shared by every command that reads a netlist: ``--include-path``, ``--limit``
(also on the commands that read none), ``--strict``."""
from __future__ import annotations

import sys


def add(parser, strict: bool = True) -> None:
    """Add the netlist-reading options to a sub-command's parser."""
    parser.add_argument("--include-path", action="append", default=[], metavar="DIR",
                        help="a folder .include may also read from (repeatable; also "
                             "PNEUNET_PATH); by default only the netlist's own folder")
    add_limit(parser)
    if strict:
        parser.add_argument("--strict", action="store_true",
                            help="a node with a single connection is an error, not a warning")


def add_limit(parser) -> None:
    """``--limit NAME=N``: the caps on sizes (read with :func:`limits`)."""
    parser.add_argument("--limit", action="append", default=[], metavar="NAME=N",
                        help="change a limit, e.g. --limit max_elements=2000000 "
                             "(names and defaults: docs/netlist.md, 'Limits')")


def add_param(parser) -> None:
    """``--param NAME=VALUE``: a ``.param`` value for this run (read with :func:`params`)."""
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="set a .param for this run (repeatable), e.g. --param Rout=1.4 "
                             "--param V=200mL; units as in .param")


def params(items) -> dict:
    """``{name: value}`` in internal units from ``NAME=VALUE`` strings (exit 2 if bad)."""
    import math

    from ...common.errors import NetlistError, ParameterError, SourceSpan
    from ...netlist.values import number_in_expression, split

    out = {}
    for item in items:
        name, eq, text = item.partition("=")
        name = name.strip()
        if not eq or not name or split(text.strip()) is None:
            raise ParameterError(f"--param {item!r}: expected NAME=VALUE",
                                 hint="e.g. --param Rout=1.4 or --param V=200mL")
        try:
            value = number_in_expression(text.strip(), SourceSpan("--param", 1, 1))
        except NetlistError as err:
            raise ParameterError(f"--param {item!r}: {err.message}", hint=err.hint) from None
        if not math.isfinite(value):
            raise ParameterError(f"--param {item!r}: not a finite number")
        out[name] = value
    return out


def limits(args):
    """The limits with the command's ``--limit`` changes (an unknown name is exit 2)."""
    from ...netlist.limits import DEFAULT

    return DEFAULT.replace(getattr(args, "limit", []))


def parse_options(args) -> dict:
    """``parse_file`` keyword arguments from the options (an unknown limit is exit 2)."""
    from ...netlist.limits import DEFAULT

    return {"limits": DEFAULT.replace(args.limit), "include_path": tuple(args.include_path)}


def check_nodes(circuit, strict: bool) -> None:
    """Warn on stderr about nodes with a single connection; with ``strict`` the first is an
    error (exit 2)."""
    from ...engine.topology import dangling_nodes
    from ...common.errors import TopologyError

    warnings = dangling_nodes(circuit)
    if strict and warnings:
        where, _, rest = warnings[0].rpartition(": node ")
        raise TopologyError("node " + rest, where=where or None,
                            hint="connect the node, or fix its spelling (without --strict "
                                 "this is a warning)")
    for warning in warnings[:WARNED]:
        print(f"warning: {warning}", file=sys.stderr)
    if len(warnings) > WARNED:
        print(f"warning: … and {len(warnings) - WARNED} more nodes with one connection",
              file=sys.stderr)


#: dangling-node warnings printed (an array of cells can make thousands)
WARNED = 20
