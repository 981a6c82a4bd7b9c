"""``pneunet fit-trace``: fit circuit parameters to a recorded transient."""
from __future__ import annotations

import json


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit-trace", help="fit circuit parameters (R_out, R_vent, V, ...) to a recorded transient",
        description="Least squares through the simulator: vary the named parameters of a "
                    "netlist (or the built-in oscillator) until the simulated signals match a "
                    "recording in the DATA-FORMAT layout (time_s, p_<node>_kPa, "
                    "mdot_<element>_mg_s). Reports 95 %% confidence intervals, residuals over "
                    "time and oscillation phase, the period error, and with --candidates "
                    "ranks circuit-level effects (polytropic volume, tubing dead volume, "
                    "tubing resistance) by their error on the later, held-out cycles.")
    p.add_argument("data", metavar="TRACE.csv", help="recorded transient")
    p.add_argument("netlist", nargs="?", metavar="FILE.pn",
                   help="netlist (its .param values or ELEMENT.PARAM are fitted); default: the "
                        "built-in oscillator (parameters Rout Rvent V pH pL n V_out R_tube)")
    p.add_argument("--fit", action="append", default=[], metavar="NAME=GUESS:LOW:HIGH",
                   help="parameter to fit (repeat); e.g. Rout=1:0.2:5")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="fixed parameter value")
    p.add_argument("--signal", action="append", default=None, metavar="COLUMN",
                   help="recorded column to fit (default: all; pressures of storage nodes fit "
                        "best, algebraic nodes jump)")
    p.add_argument("--node", default="tank", help="node whose period is compared (tank)")
    p.add_argument("--candidates", action="store_true",
                   help="rank circuit-level effects by held-out error (slower: one fit each)")
    p.add_argument("--train-fraction", type=float, default=0.5,
                   help="fraction of the cycles used for fitting with --candidates (0.5)")
    p.add_argument("--max-nfev", type=int, default=40,
                   help="simulation budget of each fit's least-squares stage, Jacobian "
                        "included (40)")
    p.add_argument("--plot", metavar="PNG", default=None, help="fit and residual plot")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--no-progress", action="store_true", help="(fits print no progress bar)")
    p.set_defaults(func=main)


def _kv(items, n):
    from ..errors import ParameterError

    out = {}
    for it in items:
        name, _, spec = it.partition("=")
        try:
            vals = [float(x) for x in spec.split(":")]
        except ValueError:
            vals = []
        if not name or len(vals) != n:
            raise ParameterError(f"bad value {it!r}",
                                 hint="NAME=GUESS:LOW:HIGH" if n == 3 else "NAME=VALUE")
        out[name] = tuple(vals) if n > 1 else vals[0]
    return out


def main(args) -> int:
    from ..analysis import fit_trace as F
    from ..errors import ParameterError

    params = _kv(args.fit, 3)
    fixed = _kv(args.set, 1)
    if not params:
        raise ParameterError("nothing to fit", hint="add --fit NAME=GUESS:LOW:HIGH")
    if args.netlist:
        from ..analysis.sweep import NetlistBuilder

        build = NetlistBuilder(args.netlist)
    else:
        from ..analysis.circuits import oscillator as build
    out = {}
    if args.candidates:
        table, fits = F.rank_effects(build, args.data, params, fixed=fixed, node=args.node,
                                     train_fraction=args.train_fraction, signals=args.signal,
                                     max_nfev=args.max_nfev)
        fit = fits["none"]
        out["ranking"] = json.loads(table.drop(columns=["values"]).to_json(orient="records"))
        out["ranking_values"] = {r["effect"]: r["values"] for _, r in table.iterrows()}
        out["train_window"] = table.attrs["train_window"]
        out["test_window"] = table.attrs["test_window"]
    else:
        fit = F.fit_trace(build, args.data, params, fixed=fixed, signals=args.signal,
                          node=args.node, max_nfev=args.max_nfev)
    out["fit"] = fit.as_dict()
    out["phase_rms"] = json.loads(fit.phase_rms.to_json(orient="records"))
    if args.plot:
        out["plot"] = str(F.plot_fit(fit, args.data, args.plot))
    if args.json:
        print(json.dumps(out, indent=1, default=str))
        return 0
    print(fit.report())
    if args.candidates:
        print("\ncircuit effects ranked by held-out error (fit on the first cycles, tested on the rest):")
        for r in out["ranking"]:
            print(f"  {r['effect']:<20} held-out rms {r['held_out_rms']:.4g} %  "
                  f"period error {r['period_error']:+.3g} s  improvement {100 * r['improvement']:+.1f} %")
    if args.plot:
        print(f"plot -> {out['plot']}")
    return 0
