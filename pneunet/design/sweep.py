"""Parameter sweeps: one table row per point, in parallel, resumable.

Points
    :func:`lin`, :func:`log`, :func:`values` make axes; :func:`grid` their product;
    :func:`latin_hypercube` and :func:`monte_carlo` sample distributions such as
    ``tolerance(96.42, 5)`` (p_close ± 5 kPa).  A point is a dict ``{name: value}``.
Circuits
    ``build(point) -> Circuit`` (a picklable function, e.g.
    :func:`pneunet.design.circuits.oscillator`), or :class:`NetlistBuilder` for a
    netlist whose ``.param`` values the point overrides.  Names of the form
    ``ELEMENT.PARAM`` (``Rvent.R``, ``X1.pclose``, ``V1.V``) set an element or valve
    model parameter of the built circuit directly, so any parameter can be swept.
Analyses
    ``analysis(circuit) -> dict`` of measurements; :class:`OscillationMeasure`
    (default) classifies and times the oscillation at a node, :class:`DeckMeasure`
    runs a netlist's own analyses and ``.meas`` statements.
Execution
    a local process pool over all cores by default; ``executor=`` any
    ``concurrent.futures.Executor`` or a ``dask.distributed.Client`` (same results; on
    dask the points go in batches, :mod:`~pneunet.design.sweep_dask`);
    ``workers=1`` runs in this process.  A failing point is recorded with its error.
    With ``store=PATH`` every finished point is appended to a JSON-lines file keyed
    by the point, and a rerun computes only the points not yet in it.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from ..common.errors import ParameterError, PneunetError
from ..common.reprs import Summarized
from ..netlist.builder import NetlistBuilder, apply_overrides, require_builder
from .store import append, fingerprint, open_store, read_store


# -- points ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    """One swept parameter and its values."""

    name: str
    values: tuple

    def __post_init__(self):
        # 12 significant digits: 1.8, not linspace's 1.7999999999999998
        object.__setattr__(self, "values", tuple(
            float(f"{v:.12g}") if isinstance(v, float) else v for v in map(_plain, self.values)))


def lin(name: str, start: float, stop: float, num: int) -> Axis:
    """``num`` values evenly spaced from ``start`` to ``stop`` (inclusive)."""
    return Axis(name, tuple(np.linspace(start, stop, int(num))))


def log(name: str, start: float, stop: float, num: int) -> Axis:
    """``num`` values evenly spaced in log from ``start`` to ``stop`` (both > 0)."""
    if start <= 0 or stop <= 0:
        raise ParameterError(f"a log sweep of {name} needs positive bounds, got {start}, {stop}")
    return Axis(name, tuple(np.geomspace(start, stop, int(num))))


def values(name: str, seq: Iterable) -> Axis:
    """An explicit list of values."""
    return Axis(name, tuple(seq))


def grid(*axes: Axis) -> list[dict]:
    """All combinations of the axes (the first varies slowest)."""
    import itertools

    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise ParameterError(f"a parameter appears twice in the grid: {names}")
    return [dict(zip(names, combo)) for combo in itertools.product(*(a.values for a in axes))]


@dataclass(frozen=True)
class Uniform:
    low: float
    high: float

    def ppf(self, u):
        return self.low + (self.high - self.low) * np.asarray(u)


@dataclass(frozen=True)
class Normal:
    mean: float
    sd: float

    def ppf(self, u):
        from scipy.stats import norm

        return norm.ppf(np.asarray(u), self.mean, self.sd)


def tolerance(nominal: float, plus_minus: float, dist: str = "uniform"):
    """A fabrication tolerance nominal ± plus_minus: uniform over the interval, or normal
    with the interval as ±2σ."""
    if dist == "uniform":
        return Uniform(nominal - plus_minus, nominal + plus_minus)
    if dist == "normal":
        return Normal(nominal, plus_minus / 2.0)
    raise ParameterError(f"unknown distribution {dist!r}", hint="'uniform' or 'normal'")


def latin_hypercube(dists: dict, n: int, seed: int = 0) -> list[dict]:
    """``n`` points stratified in every parameter (scipy's Latin hypercube)."""
    from scipy.stats import qmc

    names = list(dists)
    u = qmc.LatinHypercube(d=len(names), seed=seed).random(int(n))
    cols = {k: dists[k].ppf(u[:, i]) for i, k in enumerate(names)}
    return [{k: _plain(cols[k][j]) for k in names} for j in range(int(n))]


def monte_carlo(dists: dict, n: int, seed: int = 0) -> list[dict]:
    """``n`` independent random points."""
    rng = np.random.default_rng(seed)
    names = list(dists)
    cols = {k: dists[k].ppf(rng.random(int(n))) for k in names}
    return [{k: _plain(cols[k][j]) for k in names} for j in range(int(n))]


def _plain(v):
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


def point_key(point: dict) -> str:
    """A stable key of a point (hash of its sorted items, floats at full precision)."""
    text = json.dumps({k: _plain(v) for k, v in sorted(point.items())}, sort_keys=True,
                      default=repr)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def check_points(build, points: list) -> None:
    """Before any work: every value is finite, and building the first point (without
    simulating it) knows every name (a plain name that is no ``.param``, ``X1.pclos``: an
    error with a did-you-mean)."""
    import math

    for point in points:
        for key, value in point.items():
            if isinstance(value, float) and not math.isfinite(value):
                raise ParameterError(f"sweep parameter {key} = {value}: not a finite number")
    if points:
        apply_overrides(build(points[0]), points[0])




# -- analyses -----------------------------------------------------------------------------
class OscillationMeasure:
    """Oscillation at ``node``: kind, period, duty cycle, extremes.

    With ``t_stop`` a single transient of that length is analysed; without it,
    :func:`~pneunet.engine.oscillation.oscillator_period` runs until the cycle has
    converged (``rtol``) or ``t_max`` is reached.
    """

    def __init__(self, node: str = "tank", t_stop: float | None = None, rtol: float = 1e-4,
                 t_initial: float = 20.0, t_max: float = 320.0, keep_trace: bool = False):
        self.node, self.t_stop, self.rtol = node, t_stop, rtol
        self.t_initial, self.t_max = t_initial, t_max

    def __call__(self, circuit):
        from ..engine.oscillation import analyze_oscillation, oscillator_period

        if self.t_stop:
            sol = circuit.tran(self.t_stop)
            osc = analyze_oscillation(sol.t, sol.pressure(self.node), rtol=self.rtol)
            t_sim = self.t_stop
        else:
            try:
                res = oscillator_period(circuit, self.node, rtol=self.rtol,
                                        t_initial=self.t_initial, t_max=self.t_max)
            except PneunetError as err:
                if getattr(err, "partial", None) is None:
                    raise
                res = err.partial
            sol, osc, t_sim = res.solution, res.oscillation, res.t_simulated
        out = osc.as_dict()
        out["regime"] = ("oscillation" if osc.oscillating else
                         "equilibrium" if osc.kind in ("equilibrium", "decaying") else "undetermined")
        out["t_simulated"] = t_sim
        return out, sol

    def __repr__(self):
        return f"OscillationMeasure(node={self.node!r}, t_stop={self.t_stop})"


class DeckMeasure:
    """Run a netlist's analyses and ``.meas`` statements (needs a :class:`NetlistBuilder`)."""

    def __init__(self, builder: NetlistBuilder):
        self.builder = builder

    def __call__(self, circuit, point=None):
        from ..netlist.runner import run_deck

        deck = self.builder.deck(point)
        deck.circuit = circuit
        result = run_deck(deck)
        sol = next((r for a, r in result.results if hasattr(r, "pressure")), None)
        return measured(result.measures, result.failures), sol


def measured(values: dict, failures: dict) -> dict:
    """A sweep row's measurements: ``.meas`` values (NaN where not measured) and, if any
    failed, ``meas_failures`` (JSON of their reasons)."""
    out = {k: (float(v) if v is not None else float("nan")) for k, v in values.items()}
    if failures:
        out["meas_failures"] = json.dumps(failures)
    return out


# -- running --------------------------------------------------------------------------
def evaluate_point(build: Callable, analysis: Callable, point: dict, keep_trace: bool = False) -> dict:
    """Build and analyse one point; never raises: errors are returned in the record."""
    from ..common.solver_messages import collect

    start = time.perf_counter()
    record = {"key": point_key(point), "params": point, "result": {}, "error": None}
    with collect() as heard:
        try:
            circuit = build(point) if not isinstance(build, NetlistBuilder) else build(point)
            if not isinstance(build, NetlistBuilder):
                apply_overrides(circuit, point)
            if isinstance(analysis, DeckMeasure):
                out = analysis(circuit, point)
            else:
                out = analysis(circuit)
            result, sol = out if isinstance(out, tuple) else (out, None)
            record["result"] = {k: _plain(v) for k, v in result.items()}
            if keep_trace and sol is not None:
                record["trace"] = sol.to_pandas().to_dict(orient="list")
        except Exception as exc:  # noqa: BLE001 - a failed point is data, not a crash
            record["error"] = f"{type(exc).__name__}: {exc}"
            if not isinstance(exc, PneunetError):
                record["traceback"] = traceback.format_exc(limit=4)
    record["solver_messages"] = sum(len(d.messages) for d in heard)
    stopped = [d for d in heard if not d.recovered]
    if stopped and record["error"] is None:  # the analysis went on with a cut-short run
        record["error"] = "SolverError: a simulation stopped early: " + \
            "; ".join(stopped[0].sentences())
    record["elapsed_s"] = time.perf_counter() - start
    return record


@dataclass(repr=False)
class SweepResult(Summarized):
    """A sweep's table (one row per point, input order), traces and run statistics."""

    table: Any
    traces: dict = field(default_factory=dict)
    computed: int = 0
    reused: int = 0
    failed: int = 0
    wall_time_s: float = 0.0
    workers: int = 1
    with_solver_messages: int = 0  # points whose simulations drew integrator messages
    stale: int = 0  # stored points recomputed: made by another circuit, analysis or version

    def _summary(self):
        rows = [("points", f"{len(self.table)} ({self.computed} computed, {self.reused} "
                           "reused)"), ("failed", str(self.failed)),
                ("with solver messages", str(self.with_solver_messages)),
                ("workers", str(self.workers)), ("wall time", f"{self.wall_time_s:.3g} s")]
        return "", rows, ".table (one row per point), .traces, .to_csv(path)"

    def to_csv(self, path):
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        self.table.to_csv(path, index=False)
        return path


def _is_dask(executor) -> bool:
    return type(executor).__module__.split(".")[0] == "distributed"


def run_sweep(build: Callable, points: Sequence[dict], analysis: Callable | None = None, *,
              executor=None, workers: int | None = None, store=None, progress: bool = True,
              keep_traces: bool = False, retry_failed: bool = False) -> SweepResult:
    """Evaluate ``analysis(build(point))`` for every point; see the module docstring.

    ``workers``: local processes (default: all cores; 1 = in this process);
    ``executor``: a ``concurrent.futures`` executor or a ``dask.distributed.Client``;
    ``store``: JSON-lines file for incremental results and resuming;
    ``keep_traces``: keep each point's transient (as a DataFrame in ``result.traces``);
    ``retry_failed``: recompute points recorded as failed in the store.
    """
    import pandas as pd

    require_builder(build, "run_sweep")
    if isinstance(points, (dict, Axis, str)) or not all(isinstance(p, dict) for p in points):
        raise PneunetError(f"run_sweep takes a list of points (dicts {{name: value}}), got "
                           f"{type(points).__name__}",
                           hint="grid(lin('Rout', 0.2, 3, 10)) makes one from axes; "
                                "[{'Rout': 1.0}] is a single point")
    analysis = analysis or OscillationMeasure()
    points = [{k: _plain(v) for k, v in p.items()} for p in points]
    keys = [point_key(p) for p in points]
    if len(set(keys)) != len(keys):
        raise ParameterError("the sweep has duplicate points")
    done = read_store(store) if store else {}
    stamp = fingerprint(build, analysis) if store else None
    stale = sum(1 for k in keys if k in done and done[k].get("fingerprint") != stamp)
    done = {k: r for k, r in done.items() if r.get("fingerprint") == stamp}
    if retry_failed:
        done = {k: r for k, r in done.items() if r.get("error") is None}
    todo = [(k, p) for k, p in zip(keys, points) if k not in done
            or (keep_traces and "trace" not in done[k] and not store)]
    records = {k: done[k] for k in keys if k in done}
    wall = time.perf_counter()
    fd = open_store(store) if store else None  # before any work: a torn tail cut off
    from ..common.progress import progress_bar

    bar = progress_bar(progress, total=len(points), initial=len(points) - len(todo), unit="pt",
                       desc="sweep")
    traces = {}

    def finish(rec):
        rec["fingerprint"] = stamp
        trace = rec.pop("trace", None)
        if trace is not None:
            traces[rec["key"]] = pd.DataFrame(trace)
        records[rec["key"]] = rec
        if fd is not None:
            append(fd, rec, _json_default)
        bar.update(1)

    n_workers = 1
    own_pool = None
    finished_all = False
    try:
        if executor is None and (workers or os.cpu_count() or 1) > 1 and len(todo) > 1:
            from ..common.workers import process_pool

            own_pool = process_pool(min(workers or os.cpu_count() or 1, len(todo)))
            executor = own_pool
        if executor is None:
            for _, p in todo:
                finish(evaluate_point(build, analysis, p, keep_traces))
        elif _is_dask(executor):  # points in batches, a few per worker thread
            from .sweep_dask import run_on_dask

            n_workers = run_on_dask(executor, evaluate_point, build, analysis,
                                    [p for _, p in todo], keep_traces, finish)
        else:
            from concurrent.futures import as_completed

            n_workers = getattr(executor, "_max_workers", n_workers)
            futures = [executor.submit(evaluate_point, build, analysis, p, keep_traces)
                       for _, p in todo]
            try:
                for fut in as_completed(futures):
                    finish(fut.result())
            except BaseException:
                if own_pool is None:  # our own pool is stopped below, which fails them
                    for f in futures:
                        f.cancel()
                raise
        finished_all = True
    finally:
        if own_pool is not None:
            if finished_all:
                own_pool.shutdown(wait=True)
            else:  # Ctrl-C or an error: finished points are stored, the rest is dropped
                from ..common.workers import stop

                stop(own_pool)
        bar.close()
        if fd is not None:
            os.close(fd)
    table = records_table([records[k] for k in keys if k in records])
    return SweepResult(table, traces, computed=len(todo), reused=len(points) - len(todo),
                       stale=stale,
                       failed=int(table["error"].notna().sum()) if len(table) else 0,
                       wall_time_s=time.perf_counter() - wall, workers=n_workers,
                       with_solver_messages=int((table.get("solver_messages", 0) > 0).sum())
                       if len(table) else 0)


def records_table(records: list[dict]):
    """One row per record: parameters, measurements, error, elapsed time, key."""
    import pandas as pd

    rows = []
    for rec in records:
        row = dict(rec["params"])
        row.update(rec.get("result") or {})
        row["error"] = rec.get("error")
        row["solver_messages"] = rec.get("solver_messages", 0)
        row["elapsed_s"] = rec.get("elapsed_s")
        row["key"] = rec["key"]
        rows.append(row)
    return pd.DataFrame(rows)


def _json_default(o):
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, float) and not math.isfinite(o):
        return None
    return repr(o)


def parse_axis(text: str, max_points: int | None = None) -> Axis:
    """Parse a CLI axis ``NAME=lin:START:STOP:N``, ``log:..``, ``list:a,b,c`` or ``a,b,c``;
    ``N`` is checked against ``max_points`` (the ``max_sweep_points`` limit) before any
    value is made."""
    if "=" not in text:
        raise ParameterError(f"bad sweep axis {text!r}", hint="NAME=lin:0.2:2.5:20, NAME=log:1:10:5 "
                                                               "or NAME=list:1,2,3")
    name, spec = text.split("=", 1)
    kind, _, rest = spec.partition(":")
    try:
        if kind in ("lin", "log"):
            a, b, n = rest.split(":")
            count = float(n)
            if not (count >= 1 and count == int(count)):
                raise ParameterError(f"sweep axis {text!r}: N must be a whole number >= 1")
            if max_points is not None and count > max_points:
                raise ParameterError(f"sweep axis {text!r} asks for {count:.6g} points (limit "
                                     f"max_sweep_points = {max_points})",
                                     hint="if it is meant, raise the limit with --limit "
                                          "max_sweep_points=N")
            return (lin if kind == "lin" else log)(name, float(a), float(b), int(count))
        if kind == "list":
            return values(name, [float(x) for x in rest.split(",")])
        return values(name, [float(x) for x in spec.split(",")])
    except ValueError:
        raise ParameterError(f"bad sweep axis {text!r}",
                             hint="NAME=lin:START:STOP:N, NAME=log:START:STOP:N or NAME=list:a,b,c") from None
