"""Run a Deck's analyses and its ``.meas`` statements (used by ``pneunet run``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..engine import measure as M
from ..common.errors import PneunetError
from ..physics.units import SLOTS
from .deck import DC, Deck, Measure, Op, Tran
from .measures import SIGNAL_SLOTS


@dataclass
class DCResult:
    """Operating points of a swept source: ``values`` and one signal array per name."""

    source: str
    values: np.ndarray
    signals: dict
    units: dict

    def __getitem__(self, key):
        return self.signals[key]

    def table(self, select=None) -> dict[str, np.ndarray]:
        """Columns: the swept source's values, then one per signal named with its unit
        (with ``select``, only those whose name it accepts)."""
        from ..engine.solution import column_name

        data = {f"{self.source}_{self.units.get('_sweep', '')}".rstrip("_"): self.values}
        data.update({name: v for name, v in ((column_name(k, self.units[k]), v)
                                              for k, v in self.signals.items())
                     if select is None or select(name)})
        return data

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.table())


@dataclass
class RunResult:
    """Results of one deck (one .step point): analysis results and measurements."""

    deck: Deck
    results: list = field(default_factory=list)  # (analysis, result object)
    measures: dict = field(default_factory=dict)  # name -> float or None
    failures: dict = field(default_factory=dict)  # name -> reason


def run_deck(deck: Deck, progress: bool = False) -> RunResult:
    """Run every analysis of ``deck`` (in file order) and evaluate its measurements."""
    out = RunResult(deck)
    for analysis in deck.analyses:
        out.results.append((analysis, run_analysis(deck, analysis, progress)))
    out.measures, out.failures = evaluate_measures(deck.measures, out.results)
    return out


def run_analysis(deck: Deck, analysis, progress=False):
    circuit = deck.circuit
    if isinstance(analysis, Tran):
        # its output points (and the sources' corners) count against the deck's limits
        return circuit.tran(analysis.t_stop, t_step=analysis.t_step, t_start=analysis.t_start,
                            progress=progress,
                            max_output_points=deck.source.limits.max_output_points)
    if isinstance(analysis, Op):
        return circuit.op()
    if isinstance(analysis, DC):
        return _dc(circuit, analysis)
    raise TypeError(analysis)  # pragma: no cover


def check_finite(table: dict, analysis: str) -> None:
    """A result holding NaN or inf is a :class:`~pneunet.common.errors.SolverError` naming the
    signal and the time (or sweep value) — never a result written with exit code 0."""
    from ..common.errors import SolverError

    if "signal" in table and "value" in table:  # an operating point: one row per signal
        x_name, x = None, None
        columns = {n: [v] for n, v in zip(table["signal"], table["value"])}
    else:
        x_name = next(iter(table))
        x, columns = np.asarray(table[x_name], dtype=float), dict(list(table.items())[1:])
    for name, values in columns.items():
        values = np.asarray(values, dtype=float)
        bad = ~np.isfinite(values)
        if bad.any():
            i = int(np.argmax(bad))
            at = f" at {x_name} = {x[i]:g}" if x_name else ""
            raise SolverError(f".{analysis} result: {name} is {values[i]}{at}",
                              time=float(x[i]) if x_name == "time_s" else None,
                              hint="the model left its valid range there (a pressure at or "
                                   "below zero, a vanishing volume or resistance); check the "
                                   "parameters of the elements at that node")


def _dc(circuit, analysis: DC) -> DCResult:
    from ..physics import elements
    from ..physics.waveforms import Constant

    spec = circuit.elements[analysis.source]
    saved = spec.params["value"]
    unit = "kPa" if spec.kind == "pressure_source" else "mg_s"
    rows: dict[str, list] = {}
    units: dict[str, str] = {"_sweep": unit}
    try:
        for v in analysis.values:
            elements.family(spec.kind).params["value"].check(v, spec.where, "value")
            spec.params["value"] = Constant(float(v))
            op = circuit.op()
            for k, p in op.pressures.items():
                rows.setdefault(f"p_{k}", []).append(p)
                units[f"p_{k}"] = "kPa"
            for k, q in op.flows.items():
                rows.setdefault(f"mdot_{k}", []).append(q)
                units[f"mdot_{k}"] = "mg/s"
    finally:
        spec.params["value"] = saved
    return DCResult(analysis.source, np.array(analysis.values, dtype=float),
                    {k: np.array(v) for k, v in rows.items()}, units)


def _arrays(result, signal):
    """(x, y) arrays of a signal in a transient or dc result."""
    from ..engine.solution import Solution

    if isinstance(result, Solution):
        return result.t, result[signal.key]
    if isinstance(result, DCResult):
        if signal.key not in result.signals:
            raise M.MeasureError(f"no signal {signal} in the .dc result")
        return result.values, result.signals[signal.key]
    raise M.MeasureError(f"{signal} is not a time signal")  # pragma: no cover


def _op_value(result, signal):
    table = result.pressures if signal.quantity == "p" else result.flows \
        if signal.quantity == "mdot" else None
    if table is None or signal.target not in table:
        raise M.MeasureError(f"no value {signal} in the operating point")
    return float(table[signal.target])


def evaluate_measures(measures: list[Measure], results) -> tuple[dict, dict]:
    from .expr import Scope, evaluate

    values: dict[str, float | None] = {}
    failures: dict[str, str] = {}
    by_kind: dict[str, Any] = {}
    for analysis, result in results:
        by_kind.setdefault(analysis.kind, result)  # the first analysis of each kind
    for m in measures:
        try:
            if m.kind == "param":
                word = m.args["expr"]
                scope = Scope({k: v for k, v in values.items() if v is not None})
                text = word.text[1:-1] if word.text.startswith("{") else word.text
                values[m.name] = float(evaluate(text, scope, word.span, word.span.column + 1))
                continue
            result = by_kind.get(m.analysis)
            if result is None:
                raise M.MeasureError(f"the netlist has no .{m.analysis} analysis")
            values[m.name] = _measure(m, result)
        except PneunetError as err:
            values[m.name] = None
            failures[m.name] = err.message
    return values, failures


def _measure(m: Measure, result) -> float:
    a = m.args
    if m.analysis == "op":
        if m.kind != "find":
            raise M.MeasureError(f"{m.kind.upper()} needs a .tran or .dc result; use FIND with .op")
        return _op_value(result, m.signal)
    if m.kind == "trig_targ":
        trig, targ = a["trig"], a["targ"]
        t1, y1 = _arrays(result, trig.signal)
        t2, y2 = _arrays(result, targ.signal)
        return M.trig_targ(t1, y1, _cross(trig.args), t2, y2, _cross(targ.args))
    t, y = _arrays(result, m.signal)
    window = dict(t_from=a.get("from"), t_to=a.get("to"))
    if m.kind == "find":
        return M.value_at(t, y, a["at"])
    if m.kind == "find_when":
        t2, y2 = _arrays(result, a["when"])
        return M.find_when(t, y, t2, y2, a["level"], a.get("edge", "cross"), a.get("n", 1),
                           **window)
    if m.kind == "when":
        return M.when(t, y, a["level"], a.get("edge", "cross"), a.get("n", 1), **window)
    simple = {"min": M.minimum, "max": M.maximum, "avg": M.average, "pp": M.peak_to_peak,
              "rms": M.rms, "integ": M.integral}
    if m.kind in simple:
        return simple[m.kind](t, y, **window)
    if m.kind in ("risetime", "falltime", "filltime"):
        low, high = a["low"], a["high"]
        if m.kind == "falltime":
            low, high = high, low  # from the high level down to the low level
        return M.transition_time(t, y, low, high, **window)
    if m.kind in ("period", "freq"):
        fn = M.period if m.kind == "period" else M.frequency
        return fn(t, y, a.get("level"), cycles=a.get("cycles"), **window)
    raise M.MeasureError(f"unknown measurement {m.kind}")  # pragma: no cover


def _cross(args):
    return {"val": args["val"], "edge": args.get("edge", "cross"), "n": args.get("n", 1),
            "from": args.get("from")}


MEAS_UNITS = {quantity: SLOTS[slot] for quantity, slot in SIGNAL_SLOTS.items()}


def measure_unit(m: Measure) -> str:
    """Unit of a measurement's value, for printing."""
    if m.kind in ("when", "trig_targ", "period", "risetime", "falltime", "filltime"):
        return "s" if m.analysis != "dc" else ""
    if m.kind == "freq":
        return "Hz"
    if m.kind == "param" or m.signal is None:
        return ""
    unit = MEAS_UNITS.get(m.signal.quantity, "")
    if m.kind == "integ" and unit:
        return {"kPa": "kPa*s", "mg/s": "mg"}.get(unit, f"{unit}*s")
    return unit
