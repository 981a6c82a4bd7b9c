"""``pneunet fit DATA.csv``: identify a valve's six parameters from bench data."""
from __future__ import annotations

import argparse
import json
import sys

from ...common.errors import DataError
from ...common.csvdata import BENCH_MAX_ROWS
from . import netlist_args
from .numbers import real, whole, within
from .outputs import output_file, output_folder


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit", help="identify valve parameters from measured data (two-stage fit)",
        description="Fit the six-parameter membrane valve model to static bench data "
                    "(CSV: time_s, p_in_kPa, p_out_kPa, p_ctrl_kPa, mdot_mg_s) and print a "
                    "fit report; see docs/identify.md.")
    p.add_argument("data", help="CSV file of measurements")
    p.add_argument("--ambient", type=real(above=0, unit=" kPa"), metavar="KPA",
                   help="barometric pressure in kPa (needed with --gauge; paper: 96)")
    p.add_argument("--gauge", action="store_true", help="pressures in the file are gauge")
    p.add_argument("--pressure-unit", metavar="UNIT", help="unit of the pressure columns (bar, psi...)")
    p.add_argument("--flow-unit", metavar="UNIT",
                   help="unit of the flow column (mg/s, g/s, L/min = normal litres...)")
    p.add_argument("--map", action="append", default=[], metavar="FILE=CANONICAL",
                   help="column mapping, e.g. --map Pin=p_in_kPa (repeatable)")
    p.add_argument("--valve", metavar="ID", help="fit only the rows of this valve id")
    p.add_argument("--remove-bias", metavar="min|MG_S",
                   help="subtract a flow-sensor bias: 'min' (smallest reading, as the paper) "
                        "or a value in mg/s")
    p.add_argument("--exclude-invalid", action="store_true",
                   help="drop invalid rows (NaN, p_in <= p_out, duplicates...) with a report "
                        "instead of stopping")
    p.add_argument("--max-rows", type=whole(1), default=BENCH_MAX_ROWS, metavar="N",
                   help=f"read at most N data rows; a longer file is thinned evenly with a "
                        f"notice (default {BENCH_MAX_ROWS})")
    p.add_argument("--mdot-min", default="1", metavar="X|auto",
                   help="open/closed flow threshold in mg/s, or 'auto' from the closed-point "
                        "noise (default 1, the paper's)")
    p.add_argument("--C", type=real(above=0), default=0.1, help="SVM slack weight in kPa^-2, at most 1000 (default 0.1)")
    p.add_argument("--paper", action="store_true",
                   help="no threshold correction of stage 1 (the paper's exact procedure)")
    p.add_argument("--bootstrap", type=whole(0), default=100, metavar="N",
                   help="sweep-resampling replicates for the parameter uncertainties (default 100; 0: sandwich only)")
    p.add_argument("--name", default="VFIT", help="model name for the .model card")
    p.add_argument("--model-out", metavar="FILE", type=output_file(), help="write the .model card to FILE")
    p.add_argument("--plots", metavar="DIR", type=output_folder, help="write Figs. 6-8 as PNG into DIR")
    p.add_argument("--json", action="store_true", help="print parameters and metrics as JSON")
    netlist_args.add_limit(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ...truth.valves.identify import fit_valve, load_measurements

    within(args.bootstrap, "--bootstrap", netlist_args.limits(args), "max_samples")
    units = {}
    if args.pressure_unit:
        units["pressure"] = args.pressure_unit
    if args.flow_unit:
        units["flow"] = args.flow_unit
    columns = {}
    for item in args.map:
        if "=" not in item:
            raise DataError(f"--map needs FILE_COLUMN=CANONICAL_COLUMN, got {item!r}")
        old, new = item.split("=", 1)
        columns[old.strip()] = new.strip()
    bias = args.remove_bias
    if bias is not None and bias != "min":
        try:
            bias = real()(bias)
        except argparse.ArgumentTypeError:
            raise DataError(f"--remove-bias takes 'min' or a finite number, got {bias!r}") from None
    mdot_min = args.mdot_min
    if mdot_min != "auto":
        try:
            mdot_min = real(0)(mdot_min)
        except argparse.ArgumentTypeError:
            raise DataError(f"--mdot-min takes a number >= 0 (mg/s) or 'auto', got "
                            f"{mdot_min!r}") from None
    data = load_measurements(args.data, ambient_kpa=args.ambient, gauge=args.gauge,
                             units=units or None, columns=columns or None, flow_bias=bias,
                             on_invalid="exclude" if args.exclude_invalid else "raise",
                             valve=args.valve, max_rows=args.max_rows)
    for note in data.notes:
        print(f"pneunet fit: note: {note}", file=sys.stderr)
    fit = fit_valve(data, mdot_min=mdot_min, C=args.C, correct_threshold=not args.paper,
                    n_boot=args.bootstrap)
    card = fit.model_card(args.name)
    if args.model_out:
        with open(args.model_out, "w", encoding="utf-8") as handle:
            handle.write(f"* fitted by pneunet fit from {args.data}: RMSE "
                         f"{fit.metrics['rmse']:.4g} mg/s, {fit.metrics['misclassified']} of "
                         f"{fit.metrics['n']} misclassified\n{card}\n")
    figures = []
    if args.plots:
        from ...truth.valves.identify.plots import all_figures

        figures = [str(p) for p in all_figures(fit, args.plots)]
    if args.json:
        out = fit.to_json()
        out["model_card"] = card
        out["excluded"] = int(len(data.excluded))
        out["figures"] = figures
        json.dump(out, sys.stdout, indent=2)
        print()
    else:
        print(fit.report(args.name))
        print(card)
        if args.model_out:
            print(f"wrote {args.model_out}")
        for f in figures:
            print(f"wrote {f}")
    return 0
