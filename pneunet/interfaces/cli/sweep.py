"""``pneunet sweep``: parameter sweeps of a netlist or a built-in circuit, in parallel."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from . import netlist_args
from .executors import add_executor_args
from .numbers import real, whole, within
from .outputs import output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep", help="sweep parameters (grid, Latin hypercube, Monte Carlo) in parallel",
        description="Evaluate a circuit at many parameter points on a local process pool "
                    "(all cores by default) or a dask cluster, write one table row per point, "
                    "and with two swept parameters of an oscillator draw the regime map. "
                    "Finished points are appended to a JSON-lines store: rerunning the same "
                    "command computes only the missing points. "
                    "Example: pneunet sweep --circuit oscillator --param Rout=lin:0.2:3:20 "
                    "--param Rvent=lin:1:6:20 --out map.csv --plot map.png")
    p.add_argument("netlist", nargs="?", metavar="FILE.pn",
                   help="netlist; plain names override its .param values, ELEMENT.PARAM sets "
                        "an element or valve-model parameter; without --param its .step "
                        "points are used")
    p.add_argument("--circuit", choices=["oscillator"], default=None,
                   help="a built-in circuit instead of a netlist (the paper's oscillator; "
                        "parameters pH pL Rout Rvent V n V_out R_tube)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=SPEC",
                   help="swept axis: NAME=lin:START:STOP:N, NAME=log:START:STOP:N, "
                        "NAME=list:a,b,c (repeat for a grid)")
    p.add_argument("--tol", action="append", default=[], metavar="NAME=NOMINAL:PLUSMINUS",
                   help="a tolerance for --lhs/--mc sampling, e.g. X1.pclose=96.42:5")
    p.add_argument("--lhs", type=whole(0), default=0, metavar="N",
                   help="N Latin-hypercube points over the --tol ranges")
    p.add_argument("--mc", type=whole(0), default=0, metavar="N", help="N Monte Carlo points")
    p.add_argument("--seed", type=whole(0), default=0, help="random seed for --lhs/--mc")
    p.add_argument("--analysis", choices=["regime", "oscillation", "meas"], default=None,
                   help="regime: oscillation + stationary-branch prediction (default for "
                        "oscillators); oscillation: period/duty/extremes; meas: the netlist's "
                        ".meas results (default for netlists with .meas)")
    p.add_argument("--node", default="tank", help="node analysed for oscillation (default tank)")
    p.add_argument("--t-stop", type=real(above=0, unit=" s"), default=None, metavar="S",
                   help="fixed transient length; default: simulate until the cycle converges")
    add_executor_args(p)
    p.add_argument("--out", "-o", metavar="CSV", default="sweep.csv", type=output_file(),
                   help="table to write (default sweep.csv)")
    p.add_argument("--store", metavar="JSONL", default=None, type=output_file(),
                   help="incremental results (default: <out>.jsonl); reruns resume from it")
    p.add_argument("--fresh", action="store_true", help="ignore and replace an existing store")
    p.add_argument("--retry-failed", action="store_true", help="recompute failed points")
    p.add_argument("--plot", metavar="PNG", default=None, type=output_file(plot=True),
                   help="regime map (two axes) or measurement vs parameter (one axis)")
    p.add_argument("--json", action="store_true", help="print a JSON summary with all rows")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    netlist_args.add(p)
    p.set_defaults(func=main)


def main(args) -> int:
    from ...common.errors import ParameterError
    from ...design import sweep as S
    from ...design.store import check_writable

    if bool(args.netlist) == bool(args.circuit):
        raise ParameterError("give a netlist file or --circuit oscillator (not both)")
    limits = netlist_args.limits(args)
    axes = [S.parse_axis(a, limits.max_sweep_points) for a in args.param]
    within(math.prod(len(a.values) for a in axes), "the --param grid", limits,
           "max_sweep_points")
    within(args.lhs or args.mc, "--lhs" if args.lhs else "--mc", limits, "max_samples")
    within(math.prod(len(a.values) for a in axes) * max(args.lhs or args.mc, 1),
           "the --param grid times the samples", limits, "max_sweep_points")
    dists = {}
    for t in args.tol:
        name, _, spec = t.partition("=")
        try:
            nominal, pm = (float(x) for x in spec.split(":"))
        except ValueError:
            raise ParameterError(f"bad tolerance {t!r}", hint="NAME=NOMINAL:PLUSMINUS") from None
        dists[name] = S.tolerance(nominal, pm)
    if args.netlist:
        parse = netlist_args.parse_options(args)
        build = S.NetlistBuilder(args.netlist, parse=parse)
        deck = build.deck()
        deck.validate()
        netlist_args.check_nodes(deck.circuit, args.strict)
        has_meas = bool(deck.measures)
        from ...netlist.runner import measure_unit

        units = {m.name: measure_unit(m) for m in deck.measures}
    else:
        from ...design.circuits import oscillator as build

        has_meas, units = False, {}
    if args.lhs or args.mc:
        if not dists:
            raise ParameterError("--lhs/--mc need --tol ranges")
        points = (S.latin_hypercube if args.lhs else S.monte_carlo)(dists, args.lhs or args.mc,
                                                                    seed=args.seed)
        if axes:
            points = [dict(g, **p) for g in S.grid(*axes) for p in points]
    elif axes:
        points = S.grid(*axes)
    elif args.netlist:
        points = S.netlist_steps(args.netlist, **parse)
        if points == [{}]:
            raise ParameterError("nothing to sweep", hint="add --param or .step lines")
    else:
        raise ParameterError("nothing to sweep", hint="add --param NAME=lin:START:STOP:N")

    S.check_points(build, points)
    kind = args.analysis or ("meas" if has_meas and not axes_are_oscillator(args) else "regime")
    if kind == "meas":
        if not args.netlist:
            raise ParameterError("--analysis meas needs a netlist with .meas statements")
        analysis = S.DeckMeasure(build)
    elif kind == "regime":
        from ...design.regime import RegimeMeasure

        analysis = RegimeMeasure(node=args.node, t_stop=args.t_stop)
    else:
        analysis = S.OscillationMeasure(node=args.node, t_stop=args.t_stop)

    out = Path(args.out)
    store = Path(args.store) if args.store else out.with_suffix(out.suffix + ".jsonl")
    for path, what in ((out, "table"), (args.plot, "plot")):
        if path:
            check_writable(path, what, "choose a writable file with --out / --plot")
    if args.fresh and store.exists():
        store.unlink()
    from .executors import dask_or_local

    progress = not (args.no_progress or args.json or args.quiet)
    try:
        with dask_or_local(args.dask, args.workers) as executor:
            result = S.run_sweep(build, points, analysis, executor=executor,
                                 workers=args.workers, store=store, progress=progress,
                                 retry_failed=args.retry_failed)
    except KeyboardInterrupt:
        kept = len(set(S.read_store(store)) & {S.point_key(p) for p in points})
        print(f"sweep interrupted: {kept} of {len(points)} points are finished and kept in "
              f"{store}; rerun the same command to compute the other {len(points) - kept}",
              file=sys.stderr)
        return 130
    result.to_csv(out)
    summary = {"points": len(points), "computed": result.computed, "reused": result.reused,
               "failed": result.failed, "with_solver_messages": result.with_solver_messages,
               "stale_recomputed": result.stale,
               "workers": result.workers,
               "wall_time_s": round(result.wall_time_s, 3), "table": str(out), "store": str(store)}
    table = result.table
    if "regime_branches" in table.columns:
        from ...design.regime import agreement

        summary["agreement"] = agreement(table)
    if args.plot:
        summary["plot"] = str(_plot(table, axes, args.plot, units))
    if args.json:
        summary["rows"] = json.loads(table.to_json(orient="records"))
        print(json.dumps(summary, indent=1))
    else:
        print(f"{summary['points']} points ({result.computed} computed, {result.reused} from "
              f"{store}), {result.failed} failed, {result.workers} worker(s), "
              f"{result.wall_time_s:.1f} s -> {out}")
        if result.stale:
            print(f"{result.stale} point(s) in {store} were made by another netlist, analysis "
                  "or pneunet version: recomputed")
        if result.with_solver_messages:
            print(f"{result.with_solver_messages} point(s) with integrator warnings that "
                  "recovered (column solver_messages)")
        if "agreement" in summary:
            a = summary["agreement"]
            print(f"regime: transient and stationary branches agree at {a['agree']} of "
                  f"{a['compared']} points")
        if args.plot:
            print(f"plot -> {summary['plot']}")
    return 1 if result.failed == len(points) else 0


def axes_are_oscillator(args) -> bool:
    return args.analysis in ("regime", "oscillation")


def _plot(table, axes, path, units):
    from ...design.regime import plot_regime_map
    from ...design.sweep_plot import plot_sweep

    names = [a.name for a in axes]
    if len(names) == 2 and "regime" in table.columns:
        return plot_regime_map(table, names[0], names[1], path)
    return plot_sweep(table, names[0] if names else table.columns[0], path, units=units)
