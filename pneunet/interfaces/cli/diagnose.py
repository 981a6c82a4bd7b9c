"""``pneunet diagnose DATA.csv``: where the valve model fails and which effect is missing."""
from __future__ import annotations

import json
import sys

from ...common.csvdata import BENCH_MAX_ROWS
from .numbers import real, whole
from .outputs import output_file, output_folder


def register(subparsers):
    p = subparsers.add_parser(
        "diagnose", help="compare the valve model with measurements and name the missing effect",
        description="Fit the six-parameter valve model to static bench data, localise the "
                    "residuals, screen candidate physical effects under cross-validation "
                    "grouped by sweep, add those that clearly help, and report honestly "
                    "(adequate / explained / unexplained).")
    p.add_argument("data", help="bench CSV: time_s, p_in_kPa, p_out_kPa, p_ctrl_kPa, "
                                "mdot_mg_s (sweep optional; docs/identify.md)")
    p.add_argument("--effects", nargs="+", metavar="ID",
                   help="candidate effect ids (default: all registered effects)")
    p.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                   help="import a Python module (or file.py) that registers user effects; "
                        "repeatable")
    p.add_argument("--plots", metavar="DIR", type=output_folder, help="write the report figures (PNG) to DIR")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--model-out", metavar="FILE", type=output_file(),
                   help="write the fitted model with its effects as a .model card")
    p.add_argument("--name", default="VDIAG", help="model name of the card (default VDIAG)")
    p.add_argument("--folds", type=whole(2, 100), default=5, help="cross-validation folds (default 5)")
    p.add_argument("--max-effects", type=whole(0, 100), default=3, help="accept at most N effects")
    p.add_argument("--ambient", type=real(above=0, unit=" kPa"), metavar="KPA",
                   help="barometric pressure for gauge data (with --gauge)")
    p.add_argument("--gauge", action="store_true", help="pressures in the file are gauge")
    p.add_argument("--max-rows", type=whole(1), default=BENCH_MAX_ROWS, metavar="N",
                   help=f"read at most N data rows; a longer file is thinned evenly with a "
                        f"notice (default {BENCH_MAX_ROWS})")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    p.set_defaults(func=run)


def _load_plugin(spec):
    import importlib
    import importlib.util
    from pathlib import Path

    from ...common.errors import ParameterError

    if spec.endswith(".py"):
        path = Path(spec)
        if not path.exists():
            raise ParameterError(f"plugin file {spec} not found")
        if not path.is_file():
            raise ParameterError(f"plugin {spec} is not a file")
        mod_spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(mod_spec)
        load = lambda: mod_spec.loader.exec_module(module)  # noqa: E731
    else:
        load = lambda: importlib.import_module(spec)  # noqa: E731
    try:
        return load() or module
    except ModuleNotFoundError as err:
        if err.name and spec.startswith(err.name):
            raise ParameterError(f"--plugin {spec}: no module named {err.name!r}",
                                 hint="a module on the Python path, or a file ending in .py"
                                 ) from None
        raise ParameterError(f"--plugin {spec}: {err}") from None
    except (ImportError, ValueError, TypeError) as err:  # "..x", "", a broken module name
        raise ParameterError(f"--plugin {spec}: cannot import it ({err})") from None
    except SyntaxError as err:
        raise ParameterError(f"--plugin {spec}: {err.msg}",
                             where=f"{err.filename}:{err.lineno}") from None


def run(args) -> int:
    from ...truth.valves.diagnose import diagnose
    from ...truth.valves.identify import load_measurements

    load = {"max_rows": args.max_rows}
    if args.gauge:
        load.update(gauge=True, ambient_kpa=args.ambient)
    data = load_measurements(args.data, **load)  # the data checked before any work
    for note in data.notes:
        print(f"pneunet diagnose: note: {note}", file=sys.stderr)
    for spec in args.plugin:
        _load_plugin(spec)
    diag = diagnose(data, effects=args.effects, n_splits=args.folds,
                    max_effects=args.max_effects,
                    progress=not (args.no_progress or args.json or args.quiet))
    if args.plots:
        diag.plots(args.plots)
    if args.model_out:
        with open(args.model_out, "w", encoding="utf-8") as fh:
            fh.write(f"* fitted by pneunet diagnose from {args.data}\n")
            fh.write(diag.model_card(args.name) + "\n")
    if args.json:
        json.dump(diag.to_json(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(diag.report())
        if args.plots:
            print(f"figures written to {args.plots}/")
        if args.model_out:
            print(f"model card written to {args.model_out}")
    return 0
