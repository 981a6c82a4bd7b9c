"""``pneunet design``: parameter values that meet a specification (and their yield)."""
from __future__ import annotations

import json

from . import netlist_args
from .executors import add_executor_args
from .numbers import real, whole, within
from .outputs import output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "design", help="find parameter values that meet targets (period, swing, .meas...)",
        description="Search the given parameter ranges for values that meet every target: a "
                    "Latin hypercube over the box, then bounded least squares in log "
                    "parameters, on the sweep machinery (local process pool or dask). "
                    "When no point meets the targets, the closest design is reported with "
                    "its misses and the bounds that limit it. See docs/design.md. "
                    "Example: pneunet design netlists/oscillator_design.pn --vary Rout=0.6:3 "
                    "--vary Rvent=1:10 --vary V=40:400 --target period=3s "
                    "--target 'swing>=130kPa'. Exit code 1 when no point meets the targets.")
    p.add_argument("netlist", metavar="FILE.pn",
                   help="netlist to design (without --vary: checked at its own values)")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LOW:HIGH",
                   help="a searched parameter (a .param name or ELEMENT.PARAM such as "
                        "Vtank.V), 0 < LOW < HIGH; repeatable")
    netlist_args.add_param(p)
    p.add_argument("--target", action="append", default=[], metavar="SPEC",
                   help="period=3s, period=3s±0.1s, duty=0.4±10%%, swing>=130kPa, "
                        "p_min@out<=190kPa, or any .meas name of the netlist; repeatable "
                        "(equality: ±5%% unless given)")
    p.add_argument("--node", default=None,
                   help="node of the built-in metrics (default: the first valve's control "
                        "node)")
    p.add_argument("--starts", type=whole(1), default=None, metavar="N",
                   help="Latin-hypercube points of the first stage (default 6 per "
                        "parameter, at least 8)")
    p.add_argument("--max-evaluations", type=whole(1), default=25, metavar="N",
                   help="least-squares iterations per start (default 25)")
    p.add_argument("--seed", type=whole(0), default=0, help="seed of the Latin hypercube and the yield's samples")
    add_executor_args(p)
    y = p.add_argument_group("yield under manufacturing spread")
    y.add_argument("--yield", dest="n_yield", type=whole(0), default=0, metavar="N",
                   help="Monte Carlo samples of the spread at the design (or, without "
                        "--vary, at the netlist's values): yield with its standard error, "
                        "sensitivities")
    y.add_argument("--yield-se", dest="yield_se", type=_standard_error, default=None,
                   metavar="SE",
                   help="stop sampling once the yield is known this well: the 95%% Wilson "
                        "interval's half-width at most 1.96·SE (a fraction: 0.02 for ±2%%); "
                        "--yield N is then the most samples (default: all N)")
    y.add_argument("--tolerance", action="append", default=[], metavar="NAME=±X",
                   help="a stated spread, e.g. X1.pclose=±5kPa or X1.e=±5%%; repeatable")
    y.add_argument("--tolerance-dist", choices=["uniform", "normal"], default="uniform",
                   help="uniform over ±X (default) or normal with ±X as ±2σ")
    y.add_argument("--fit", action="append", default=[], metavar="ELEMENT=FIT.json",
                   help="a valve's fitted covariance from 'pneunet fit DATA.csv --json', "
                        "centred on the netlist's values, e.g. X1=fit.json")
    y.add_argument("--derivatives", action="store_true",
                   help="also the effects of ±1 SD by central differences at the design "
                        "(2 simulations per spread parameter): a check of linearity")
    y.add_argument("--tornado", metavar="PNG", default=None, type=output_file(plot=True), help="write the tornado plot")
    y.add_argument("--samples", metavar="CSV", default=None, type=output_file(),
                   help="write the yield samples (parameters, metrics, pass)")
    p.add_argument("--json", action="store_true", help="print the result as JSON only")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    netlist_args.add(p, strict=False)
    p.set_defaults(func=main)


def main(args) -> int:
    from ...design.store import check_writable
    from ...netlist.builder import NetlistBuilder
    from ...design.problem import Problem
    from ...design.search import design, evaluate
    from ...design.spec import parse_range, parse_tolerance
    from ...design.spread import combined, no_uncertainty, spread_hint
    from ...design.yields import yield_analysis
    from ...common.errors import ParameterError
    from .executors import dask_or_local

    limits = netlist_args.limits(args)
    within(args.n_yield, "--yield", limits, "max_samples")
    within(args.starts or 0, "--starts", limits, "max_samples")
    within(args.max_evaluations, "--max-evaluations", limits, "max_samples")
    ranges = [parse_range(text) for text in args.vary]
    tolerances = [parse_tolerance(text) for text in args.tolerance]
    fits = [_element_file(text) for text in args.fit]
    if not args.target:
        raise ParameterError("no target given", hint="e.g. --target period=3s")
    if (tolerances or fits) and not args.n_yield:
        raise ParameterError("--tolerance/--fit need --yield N (Monte Carlo samples)")
    if args.yield_se is not None and not args.n_yield:
        raise ParameterError("--yield-se needs --yield N (the most samples to draw)",
                             hint="e.g. --yield 1000 --yield-se 0.02")
    for path, what in ((args.tornado, "tornado plot"), (args.samples, "samples table")):
        if path:
            check_writable(path, what, "choose a writable file")
    fixed = netlist_args.params(args.param)  # given values: checked (and their yield)
    build = NetlistBuilder(args.netlist, parse=netlist_args.parse_options(args))
    progress = not (args.no_progress or args.json or args.quiet)
    with dask_or_local(args.dask, args.workers) as executor:
        problem = Problem(build, args.target, node=args.node, workers=args.workers, fixed=fixed,
                          executor=executor, progress=progress)
        if args.n_yield and not (tolerances or fits):
            raise ParameterError(no_uncertainty(build), hint=spread_hint())
        with problem:
            if ranges:
                result = design(problem, ranges, n_start=args.starts,
                                max_nfev=args.max_evaluations, seed=args.seed)
            else:
                result = evaluate(problem, fixed)
            out = result.to_json()
            if args.n_yield:
                spread = combined(problem, result.values, tolerances, fits,
                                  args.tolerance_dist)
                y = yield_analysis(problem, result.values, spread, args.n_yield, args.seed,
                                   nominal=result.metrics, derivatives=args.derivatives,
                                   se=args.yield_se)
        if args.n_yield:
            out["yield"] = y.to_json()
            if args.tornado:
                out["yield"]["tornado"] = str(y.plot_tornado(args.tornado))
            if args.samples:
                y.samples.to_csv(args.samples, index=False)
                out["yield"]["samples"] = args.samples
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(result.report())
        if args.n_yield:
            print(y.report())
            for key in ("tornado", "samples"):
                if key in out["yield"]:
                    print(f"{key} -> {out['yield'][key]}")
    return 0 if result.met else 1


def _standard_error(text: str) -> float:
    """--yield-se: a fraction 0 < SE < 0.5."""
    import argparse

    try:
        return real(above=0, below=0.5)(text)
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(f"{err} (the yield's standard error as a fraction, "
                                         "e.g. 0.02 for ±2 %)") from None


def _element_file(text: str) -> tuple:
    from ...common.errors import ParameterError

    element, eq, path = text.partition("=")
    if not eq or not element.strip() or not path.strip():
        raise ParameterError(f"cannot read --fit {text!r}", hint="ELEMENT=FIT.json, e.g. "
                             "X1=fit.json (from pneunet fit DATA.csv --json > fit.json)")
    return element.strip(), path.strip()
