"""``pneunet run FILE.pn``: parse, validate, run every analysis, write CSV, print ``.meas``."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from . import netlist_args
from .outputs import output_folder


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "run", help="simulate a netlist: run its analyses, write CSV, print .meas results",
        description="Parse and validate a netlist, run every analysis (.tran, .op, .dc), "
                    "for each .step point if any, write one CSV per analysis (columns named "
                    "with units, e.g. p_tank_kPa) and print the .meas results. With .step, "
                    "also writes meas_summary.csv (one row per step). "
                    "Exit codes: 0 ok, 2 bad input or a simulation that cannot be "
                    "completed (a result with NaN or inf included).")
    p.add_argument("netlist", metavar="FILE.pn", help="netlist file")
    p.add_argument("-o", "--output", metavar="DIR", default=None, type=output_folder,
                   help="output folder (default: ./<netlist name>_results)")
    netlist_args.add_param(p)
    p.add_argument("--plot", action="store_true", help="also write a PNG plot per transient")
    p.add_argument("--json", action="store_true",
                   help="print measurements and written files as JSON on stdout")
    p.add_argument("--run-file", choices=("json", "npz"), default=None,
                   help="also write each transient whole to one file (every signal with its "
                        "unit, solver stats, the circuit as netlist text, options, versions); "
                        "pneunet.read_run loads it back")
    p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    netlist_args.add(p)
    p.set_defaults(func=main)


def _fmt(v):
    return "FAILED" if v is None else f"{v:.6g}"


def _check_saves(saves, columns, path) -> None:
    """A ``.save`` signal the results lack (``Tgas(VC)``) is an error naming what exists."""
    from ...common.errors import NetlistError

    for signal in saves:
        if not any(c == signal.key or c.startswith(signal.key + "_") for c in columns):
            mine = sorted(f"{c.split('_' + signal.target + '_')[0]}({signal.target})"
                          for c in columns if f"_{signal.target}_" in c)
            raise NetlistError(f".save {signal}: element {signal.target!r} has no signal "
                               f"{signal.quantity!r}", where=str(path),
                               hint="its signals: " + ", ".join(mine) if mine else None)


def _column_names(result) -> list[str]:
    """The result's table columns, without computing any signal (demux6: 450 MB if all
    element signals were computed just to learn their names)."""
    names = []
    result.table(lambda column: names.append(column))  # None: no column is computed
    return names


def main(args) -> int:
    from ...common.errors import SolverError
    from ...netlist import parse_file
    from ...netlist.runner import (RunResult, check_finite, evaluate_measures, measure_unit,
                                   run_analysis)
    from ...engine.solution import write_csv

    path = Path(args.netlist)
    deck = parse_file(path, netlist_args.params(args.param), **netlist_args.parse_options(args))
    deck.validate()
    netlist_args.check_nodes(deck.circuit, args.strict)
    points = deck.step_points()
    out_dir = Path(args.output) if args.output else Path.cwd() / f"{path.stem}_results"
    if out_dir.exists() and not out_dir.is_dir():
        from ...common.errors import PneunetError

        raise PneunetError(f"-o {out_dir}: a file of that name exists; the results go into a "
                           "folder", hint="name a new or an existing folder")
    out_dir.mkdir(parents=True, exist_ok=True)
    say = (lambda *a: None) if (args.quiet or args.json) else print
    progress = not (args.quiet or args.json or args.no_progress) and sys.stderr.isatty()
    saves = [s.key for s in deck.saves]
    report = {"netlist": str(path), "output": str(out_dir), "steps": []}
    summary_rows = []
    status = 0
    for i, point in enumerate(points, 1):
        d = deck.variant(point) if point else deck
        if point:
            d.validate()
            say("step " + str(i) + ": " + ", ".join(f"{k}={v:g}" for k, v in point.items()))
        tag = f"_step{i}" if point else ""
        res = RunResult(d)
        files = []
        counts: dict[str, int] = {}
        solver_messages = {}
        for analysis in d.analyses:  # write each result as soon as it exists
            try:
                result = run_analysis(d, analysis, progress)
            except SolverError as err:
                if not deck.steps:
                    raise
                # one failed step does not stop the sweep; the exit code says it failed
                print(f"step {i}: {err.report()}", file=sys.stderr)
                status = err.exit_code
                break
            res.results.append((analysis, result))
            counts[analysis.kind] = counts.get(analysis.kind, 0) + 1
            suffix = "" if counts[analysis.kind] == 1 else str(counts[analysis.kind])
            name = f"{analysis.kind}{suffix}{tag}"
            if saves and analysis.kind in ("tran", "dc"):  # only the saved signals
                _check_saves(deck.saves, _column_names(result), path)
                table = result.table(lambda c: any(c.startswith(s + "_") or c == s
                                                   for s in saves))
            else:
                table = result.table()
            check_finite(table, analysis.kind)
            csv = out_dir / f"{name}.csv"
            write_csv(csv, table)
            files.append(str(csv))
            if args.run_file and analysis.kind == "tran":
                files.append(str(result.save(out_dir / f"{name}.{args.run_file}", d.circuit)))
                say(f"  .tran: wrote {files[-1]}")
            if args.plot and analysis.kind == "tran":
                png = out_dir / f"{name}.png"
                result.plot(png, signals=saves or None)
                files.append(str(png))
            say(f"  .{analysis.kind}: wrote {csv}")
            if getattr(result, "stability", None) is not None:
                say(f"    {result.stability.describe()}")
            stats = dict(getattr(result, "stats", {}) or {})
            if "solver_messages" in stats:
                solver_messages[name] = stats.get("solver_diagnostics", {"count": 0})
            if stats:
                say("    stats: " + ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else
                                              f"{k}={v}" for k, v in stats.items()
                                              if isinstance(v, (int, float))))
        res.measures, res.failures = evaluate_measures(d.measures, res.results)
        for m in d.measures:
            v = res.measures.get(m.name)
            unit = measure_unit(m)
            line = f"  {m.name} = {_fmt(v)}" + (f" {unit}" if unit and v is not None else "")
            if v is None:
                line += f"  ({res.failures.get(m.name)})"
            say(line)
        report["steps"].append({"params": point, "measures": res.measures,
                                "failures": res.failures, "files": files,
                                "solver_messages": solver_messages})
        summary_rows.append({**point, **res.measures})
    if deck.steps:
        import pandas as pd

        summary = out_dir / "meas_summary.csv"
        write_csv(summary, pd.DataFrame(summary_rows).to_dict(orient="list"))
        report["summary"] = str(summary)
        say(f"wrote {summary}")
        if deck.measures:
            say(pd.DataFrame(summary_rows).to_string(index=False))
    if args.json:
        if not deck.steps:
            only = report["steps"][0]
            report.update(measures=only["measures"], failures=only["failures"],
                          files=only["files"], solver_messages=only["solver_messages"])
            del report["steps"]
        print(json.dumps(report, indent=2))
    return status
