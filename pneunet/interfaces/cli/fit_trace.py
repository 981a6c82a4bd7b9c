"""``pneunet fit-trace``: fit circuit parameters to a recorded transient, and with
``--candidates`` diagnose which circuit effect the recording shows."""
from __future__ import annotations

import contextlib
import json
import math
import os
import sys

from ...common.csvdata import TRACE_MAX_ROWS
from . import netlist_args
from .executors import MAX_WORKERS
from .numbers import real, whole, within
from .outputs import output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit-trace", help="fit a circuit to a recorded transient; find the physics it lacks",
        description="Least squares through the simulator: vary the named parameters of a "
                    "netlist (or the built-in oscillator) until the simulated signals match a "
                    "recording (CSV columns time_s, p_<node>_kPa, "
                    "mdot_<element>_mg_s, and any signal `pneunet run` writes: "
                    "contraction_<muscle>_mm, force_<muscle>_N, volume_<el>_mL, T_<volume>_K, "
                    "...; other units of the same quantity converted); every recorded column "
                    "is compared, each in units of its own noise when units differ (a few samples "
                    "around the jumps of an algebraic node are left out). With --candidates: "
                    "the noise floor from the data, every circuit effect (heat exchange in "
                    "volumes, dead volumes, tubes on lines, your own) fitted and ranked by the "
                    "error on the later, held-out cycles, and a verdict: adequate, explained "
                    "or unexplained (with where).")
    p.add_argument("data", metavar="TRACE.csv", help="recorded transient")
    p.add_argument("netlist", nargs="?", metavar="FILE.pn",
                   help="netlist (its .param values or ELEMENT.PARAM are fitted); default: the "
                        "built-in oscillator (parameters Rout Rvent V pH pL n V_out R_tube)")
    p.add_argument("--fit", action="append", default=[], metavar="NAME=GUESS:LOW:HIGH",
                   help="parameter to fit (repeat); e.g. Rout=1:0.2:5")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="fixed parameter value")
    p.add_argument("--signal", action="append", default=None, metavar="COLUMN",
                   help="recorded column to fit (default: all)")
    p.add_argument("--node", default="tank", help="node whose cycles set the phase, the period "
                                                  "and the fit/held-out split (tank)")
    p.add_argument("--start", choices=("auto", "rest", "record", "settled"), default="auto",
                   help="the circuit's state at the first sample: rest (the netlist's: a "
                        "recording from switch-on), record (read from the first samples; "
                        "unrecorded storage fitted), settled (an oscillator's settled cycle, "
                        "aligned in phase); auto: rest when the first samples are at rest, "
                        "else record (a driven record off rest: fitted from both record and "
                        "rest driven to the first sample, rest kept unless record fits 10 %% "
                        "better)")
    p.add_argument("--time-offset", type=float, default=None, metavar="S",
                   help="netlist time of the first sample, s (default: the file's first time "
                        "stamp for a circuit driven by its sources, else 0)")
    p.add_argument("--ambient", type=float, default=None, metavar="KPA",
                   help="barometric pressure during the recording, kPa absolute: gauge "
                        "columns (p_<node>_kPag, _barg, _psig) are made absolute with it "
                        "(default: the netlist's .options ambient, which its vents see)")
    p.add_argument("--candidates", action="store_true",
                   help="diagnose: rank circuit effects by held-out error, give a verdict")
    p.add_argument("--effect", action="append", default=None, metavar="NAME",
                   help="candidate effect (kind or bound name such as tube@X1.ctrl; repeat; "
                        "default: all registered)")
    p.add_argument("--effects-module", action="append", default=[], metavar="MODULE",
                   help="import this Python module (file path or dotted name) first: it "
                        "registers your own circuit effects")
    p.add_argument("--train-fraction", type=real(above=0, below=1), default=0.5,
                   help="fraction of the cycles used for fitting with --candidates (0.5)")
    p.add_argument("--max-nfev", type=whole(1), default=40,
                   help="simulation budget of each fit's least-squares stage, Jacobian "
                        "included (40; a candidate effect's fit gets 4x: raise it when the "
                        "best candidate's fit stops short of the noise floor)")
    p.add_argument("--workers", type=whole(1, MAX_WORKERS), default=None,
                   help="processes for parallel finite differences (default: 2 if 2 cores)")
    p.add_argument("--plot", metavar="PNG", default=None, type=output_file(plot=True),
                   help="fit and residual plot")
    p.add_argument("--netlist-out", metavar="FILE", default=None, type=output_file(),
                   help="write the fitted circuit as a netlist: yours with the fitted values "
                        "and (with --candidates) the accepted effects written in; run it "
                        "with pneunet run")
    p.add_argument("--waterfall", metavar="PNG", default=None, type=output_file(plot=True),
                   help="error waterfall plot (with --candidates)")
    p.add_argument("--json", action="store_true",
                   help="print only the result as JSON on stdout (solver messages: stderr)")
    p.add_argument("--max-rows", type=whole(5), default=TRACE_MAX_ROWS, metavar="N",
                   help=f"read at most N samples; a longer recording is thinned evenly with a "
                        f"notice (default {TRACE_MAX_ROWS})")
    p.add_argument("--no-progress", action="store_true", help="no progress messages on stderr")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no warnings or progress on stderr (errors only)")
    netlist_args.add(p)
    p.set_defaults(func=main)


def _kv(items, n):
    from ...common.errors import ParameterError

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


@contextlib.contextmanager
def stdout_to_stderr(active: bool):
    """Send everything written to file descriptor 1 (C libraries included: SUNDIALS
    prints its warnings there) to stderr while active."""
    if not active:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def _load_effects(modules):
    import importlib
    import importlib.util
    from pathlib import Path

    from ...common.errors import ParameterError

    for m in modules:
        try:
            if m.endswith(".py") or Path(m).exists():
                spec = importlib.util.spec_from_file_location(Path(m).stem, m)
                if spec is None:
                    raise ImportError(m)
                mod = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(mod)
            else:
                importlib.import_module(m)
        except (ImportError, OSError, SyntaxError) as err:
            raise ParameterError(f"cannot import effects module {m}: {err}") from None


def main(args) -> int:
    from ...common.errors import ParameterError

    params = _kv(args.fit, 3)
    fixed = _kv(args.set, 1)
    if args.time_offset is not None and not math.isfinite(args.time_offset):
        raise ParameterError(f"--time-offset {args.time_offset}: not a finite time",
                             hint="the netlist time of the first sample, in seconds")
    if not params:
        raise ParameterError("nothing to fit", hint="add --fit NAME=GUESS:LOW:HIGH")
    within(args.max_nfev, "--max-nfev", netlist_args.limits(args), "max_samples")
    if args.netlist:
        from ...netlist.builder import NetlistBuilder

        build = NetlistBuilder(args.netlist, parse=netlist_args.parse_options(args))
        circuit = build.deck().circuit
        netlist_args.check_nodes(circuit, args.strict)
    else:
        from ...design.circuits import oscillator as build

        circuit = build({})
    if args.ambient is not None and not (math.isfinite(args.ambient) and args.ambient > 0):
        raise ParameterError(f"--ambient {args.ambient}: not a pressure",
                             hint="the barometric pressure in kPa absolute, e.g. 101.3")
    data = _recording(args, circuit.options.ambient if args.ambient is None else args.ambient)
    _load_effects(args.effects_module)
    quiet = args.no_progress or args.quiet

    def say(msg):
        if not quiet:
            print(f"fit-trace: {msg}", file=sys.stderr, flush=True)

    from ...common.solver_messages import collect, summarize

    with stdout_to_stderr(args.json), collect() as heard:
        out, text = _run(args, data, build, params, fixed, say)
    out["solver_messages"] = summarize(heard)  # the workers' simulations included
    if args.json:
        print(json.dumps(_finite(out), indent=1, default=_json_default, allow_nan=False))
    else:
        print(text)
    return 0


def _recording(args, ambient_kpa):
    """The recording read and checked before any work (its notes on stderr): the
    columns (gauge ones made absolute with ``ambient_kpa``), and the column of the cycle
    node ``--node``."""
    from ...common.errors import DataError
    from ...truth.circuits.data import read_trace

    data = read_trace(args.data, args.signal, max_rows=args.max_rows, ambient_kpa=ambient_kpa)
    column = f"p_{args.node}_kPa"
    if column not in data:
        pressures = [c[2:-4] for c in data.columns if c.startswith("p_")]
        raise DataError(f"column {column} is missing: the cycle node --node {args.node} sets the "
                        f"phase, the period and the fit/held-out split", where=data.attrs["source"],
                        hint=("choose the node with --node (recorded pressures: "
                              + ", ".join(pressures) + ")") if pressures else
                        "record the pressure of the oscillating node")
    for note in data.attrs["notes"]:
        print(f"fit-trace: note: {note}", file=sys.stderr, flush=True)
    return data


def _finite(o):
    """``o`` with every non-finite float as None (JSON null: an unbounded interval end,
    a quantity not computed); JSON has no inf or NaN."""
    import math

    import numpy as np

    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite(v) for v in o]
    if isinstance(o, np.ndarray):
        return _finite(o.tolist())
    if isinstance(o, (float, np.floating)):
        return float(o) if math.isfinite(o) else None
    return o


def _json_default(o):
    import numpy as np

    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def _run(args, data, build, params, fixed, say):
    from ...truth.circuits import diagnose_trace, fit_trace
    from ...truth.circuits.plots import plot_fit

    out = {}
    if args.candidates:
        diag = diagnose_trace(build, data, params, fixed=fixed,
                              node=args.node, effects=args.effect,
                              train_fraction=args.train_fraction, max_nfev=args.max_nfev,
                              workers=args.workers, progress=say, start_state=args.start,
                              time_offset=args.time_offset)
        out = diag.to_json()
        fit = diag.final
        text = diag.report()
        if args.waterfall:
            from ...truth.circuits.plots import plot_waterfall

            out["waterfall_plot"] = str(plot_waterfall(diag, args.waterfall))
            text += f"\nwaterfall -> {out['waterfall_plot']}"
    else:
        say("fitting")
        from ...truth.circuits.model import process_pool

        pool = process_pool(args.workers)
        try:
            fit = fit_trace(build, data, params, fixed=fixed,
                            node=args.node, max_nfev=args.max_nfev, pool=pool,
                            start_state=args.start, time_offset=args.time_offset)
        finally:
            if pool is not None:
                pool.shutdown()
        out["fit"] = fit.as_dict()
        text = fit.report()
    out["phase_rms"] = json.loads(fit.phase_rms.to_json(orient="records"))
    if args.netlist_out:
        netlist = diag.corrected_netlist() if args.candidates else fit.corrected_netlist()
        with open(args.netlist_out, "w", encoding="utf-8") as fh:
            fh.write(netlist)
        out["netlist_out"] = str(args.netlist_out)
        text += f"\ncorrected netlist -> {args.netlist_out}"
    if args.plot:
        out["plot"] = str(plot_fit(fit, data, args.plot))
        text += f"\nplot -> {out['plot']}"
    return out, text
