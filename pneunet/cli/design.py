"""``pneunet design``: parameter values that meet a specification (and their yield)."""
from __future__ import annotations

import json
import sys

from . import netlist_args


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "design", help="find parameter values that meet targets (period, swing, .meas...)",
        description="Search the given parameter ranges for values that meet every target: a "
                    "Latin hypercube over the box, then bounded least squares in log "
                    "parameters, on the sweep machinery (local process pool or dask). "
                    "When no point meets the targets, the closest design is reported with "
                    "its misses and the bounds that limit it. See docs/design.md. "
                    "Example: pneunet design netlists/oscillator.pn --vary Rout=0.6:3 "
                    "--vary Rvent=1:10 --vary Vtank.V=40:400 --target period=3s "
                    "--target 'swing>=130kPa'. Exit code 1 when no point meets the targets.")
    p.add_argument("netlist", metavar="FILE.pn", help="netlist to design")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LOW:HIGH",
                   help="a searched parameter (a .param name or ELEMENT.PARAM such as "
                        "Vtank.V), 0 < LOW < HIGH; repeatable")
    p.add_argument("--target", action="append", default=[], metavar="SPEC",
                   help="period=3s, period=3s±0.1s, duty=0.4±10%%, swing>=130kPa, "
                        "p_min@out<=190kPa, or any .meas name of the netlist; repeatable "
                        "(equality: ±5%% unless given)")
    p.add_argument("--node", default=None,
                   help="node of the built-in metrics (default: the first valve's control "
                        "node)")
    p.add_argument("--starts", type=int, default=None, metavar="N",
                   help="Latin-hypercube points of the first stage (default 6 per "
                        "parameter, at least 8)")
    p.add_argument("--max-evaluations", type=int, default=25, metavar="N",
                   help="least-squares iterations per start (default 25)")
    p.add_argument("--seed", type=int, default=0, help="seed of the Latin hypercube")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: all cores; 1 = no pool)")
    p.add_argument("--dask", metavar="ADDRESS", default=None,
                   help="run on a dask.distributed scheduler (ADDRESS or 'local')")
    p.add_argument("--json", action="store_true", help="print the result as JSON only")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    netlist_args.add(p, strict=False)
    p.set_defaults(func=main)


def main(args) -> int:
    from ..analysis.sweep import NetlistBuilder
    from ..design.search import design
    from ..design.spec import parse_range
    from ..errors import ParameterError
    from .executors import dask_or_local

    ranges = [parse_range(text) for text in args.vary]
    if not ranges:
        raise ParameterError("no parameter to vary", hint="e.g. --vary Rout=0.6:3")
    if not args.target:
        raise ParameterError("no target given", hint="e.g. --target period=3s")
    build = NetlistBuilder(args.netlist, parse=netlist_args.parse_options(args))
    progress = not (args.no_progress or args.json or args.quiet)
    with dask_or_local(args.dask, args.workers) as executor:
        result = design(build, ranges, args.target, n_start=args.starts,
                        max_nfev=args.max_evaluations, seed=args.seed, node=args.node,
                        workers=args.workers, executor=executor, progress=progress)
    if args.json:
        print(json.dumps(result.to_json(), indent=1))
    else:
        print(result.report())
    return 0 if result.met else 1
