"""Results of analyses: immutable, labelled signals with units.

Signal names follow the columns of recorded data (docs/diagnose.md, "Circuit
recordings"): ``p_<node>`` for node pressures (kPa absolute), ``mdot_<element>`` for
element flows (mg/s), plus element-specific signals (``dp_<valve>``,
``opening_<valve>``).  Table columns append the unit: ``p_tank_kPa``, ``mdot_Rout_mg_s``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping

import numpy as np

from ..common.errors import PneunetError
from ..common.reprs import Summarized, listed, number


def column_name(signal: str, unit: str) -> str:
    """Table column of a signal: its name and unit (``mg/s`` → ``mg_s``)."""
    if unit in ("", "1"):
        return signal
    return f"{signal}_{unit.replace('/', '_').replace('*', '').replace('·', '')}"


def write_csv(path, table: Mapping[str, Any]) -> None:
    """Columns of equal length as CSV: numbers with 9 significant digits, text as it is."""
    from pathlib import Path

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    columns = list(table.values())
    with open(path, "w") as fh:
        fh.write(",".join(table) + "\n")
        if all(np.asarray(c).dtype.kind in "fiu" for c in columns):
            if columns and len(columns[0]):
                np.savetxt(fh, np.column_stack(columns), fmt="%.9g", delimiter=",")
            return
        for row in zip(*columns):
            fh.write(",".join(f"{v:.9g}" if isinstance(v, (float, int, np.number)) else str(v)
                              for v in row) + "\n")


def _freeze(mapping):
    """Read-only float copies of the signals; arrays already read-only are kept as they are
    (the analyses hand over read-only views of arrays nothing else holds)."""
    frozen = {}
    for k, v in mapping.items():
        if isinstance(v, np.ndarray) and v.dtype == float and not v.flags.writeable:
            frozen[k] = v
            continue
        arr = np.array(v, dtype=float)
        arr.setflags(write=False)
        frozen[k] = arr
    return MappingProxyType(frozen)


class LazySignals(Mapping):
    """Read-only signals, some of them computed in groups on first access and kept.

    ``pending`` maps each deferred signal name to the function that computes its
    whole group (e.g. all flows of one element family) as {name: array}.  Large
    networks store thousands of element signals; most analyses read a few.
    """

    def __init__(self, ready: Mapping[str, np.ndarray],
                 pending: Mapping[str, Callable[[], Mapping[str, np.ndarray]]]):
        self._values = dict(_freeze(ready))
        self._pending = dict(pending)
        self._order = list(ready) + [k for k in pending if k not in ready]

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._values and name in self._pending:
            computed = _freeze(self._pending[name]())
            self._values.update(computed)
            for key in computed:
                self._pending.pop(key, None)
        return self._values[name]

    def __iter__(self):
        return iter(self._order)

    def __len__(self) -> int:
        return len(self._order)

    def __contains__(self, name) -> bool:
        return name in self._values or name in self._pending


@dataclass(frozen=True, repr=False, eq=False)
class Solution(Summarized):
    """A transient result: time points and named signals (read-only arrays).

    ``signals`` is a mapping; element signals of simulated circuits are computed
    when first read (:class:`LazySignals`).

    ``jumps`` lists the times of explicit jumps between solution branches
    (relaxation oscillations); the state before and after a jump are both stored.
    """

    t: np.ndarray
    signals: Mapping[str, np.ndarray]
    units: Mapping[str, str]
    stats: Mapping[str, Any] = field(default_factory=dict)
    title: str = ""
    jumps: tuple = ()

    def __post_init__(self):
        t = np.array(self.t, dtype=float)
        t.setflags(write=False)
        object.__setattr__(self, "t", t)
        if not isinstance(self.signals, LazySignals):
            object.__setattr__(self, "signals", _freeze(self.signals))
        object.__setattr__(self, "units", MappingProxyType(dict(self.units)))
        object.__setattr__(self, "stats", MappingProxyType(dict(self.stats)))

    def __eq__(self, other) -> bool:
        """Equal when the times, the signals (names, units and values; NaN equals NaN), the
        title and the jumps are: what was simulated, not how (``stats`` not compared)."""
        if not isinstance(other, Solution):
            return NotImplemented
        return (self.title == other.title and tuple(self.jumps) == tuple(other.jumps)
                and dict(self.units) == dict(other.units)
                and list(self.signals) == list(other.signals)
                and np.array_equal(self.t, other.t)
                and all(np.array_equal(self.signals[k], other.signals[k], equal_nan=True)
                        for k in self.signals))

    __hash__ = None  # mutable-looking arrays inside: not hashable

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(name, self.signals, n=1)
            raise PneunetError(f"no signal {name!r} in this solution",
                               hint=f"did you mean {close[0]!r}?" if close else
                               "signals: " + ", ".join(self.signals)) from None

    def _summary(self):
        stats = self.stats
        rows = [("time", f"{self.t[0]:g}–{self.t[-1]:g} s" if self.t.size else "empty"),
                ("points", str(self.t.size)),
                ("signals", f"{len(self.signals)} ({listed(self.signals, 4)})")]
        if self.jumps:
            rows.append(("branch jumps", str(len(self.jumps))))
        if "steps" in stats:
            rows.append(("solver", f"{stats.get('backend', 'IDA')}, {stats['steps']} steps in "
                                   f"{number(stats.get('wall_time_s'), 's', 3)}"))
        if stats.get("solver_messages"):
            rows.append(("solver messages", f"{stats['solver_messages']} (stats"
                                            "['solver_diagnostics'])"))
        return (repr(self.title) if self.title else "transient", rows,
                "sol.pressure(node), sol.flow(element), sol.at(t), sol.final(), sol.stats, "
                "sol.to_pandas(), sol.plot(), sol.save(path)")

    def _signal_name(self, name: str) -> str:
        """A signal's name; a bare node or element name means its pressure or flow."""
        for key in (name, f"p_{name}", f"mdot_{name}"):
            if key in self.signals:
                return key
        self[name]  # the error with a did-you-mean
        return name

    def pressure(self, node: str) -> np.ndarray:
        """Absolute pressure of ``node`` over time, kPa."""
        return self[f"p_{node}"]

    def flow(self, element: str) -> np.ndarray:
        """Mass flow through ``element`` (or delivered by a source) over time, mg/s."""
        return self[f"mdot_{element}"]

    def at(self, time: float) -> dict[str, float]:
        """All signals linearly interpolated at ``time``."""
        return {k: float(np.interp(time, self.t, v)) for k, v in self.signals.items()}

    def final(self) -> dict[str, float]:
        """All signals at the last time point."""
        return {k: float(v[-1]) for k, v in self.signals.items()}

    def table(self, select: Callable[[str], bool] | None = None) -> dict[str, np.ndarray]:
        """Columns: ``time_s`` and one per signal named with its unit; with ``select``
        only the columns whose name it accepts (the others are never computed)."""
        data = {"time_s": self.t}
        for k in self.signals:
            name = column_name(k, self.units[k])
            if select is None or select(name):
                data[name] = self.signals[k]
        return data

    def to_pandas(self):
        """:meth:`table` as a DataFrame."""
        import pandas as pd

        return pd.DataFrame(self.table())

    def to_csv(self, path) -> None:
        """Write :meth:`table` as CSV (one row per time point)."""
        write_csv(path, self.table())

    def save(self, path, circuit=None):
        """The whole run in one file (``.json`` or ``.npz``) with ``circuit``'s netlist
        and options; :func:`pneunet.read_run` loads it back (see :mod:`pneunet.interfaces.runfile`)."""
        from ..common.views import view

        return view("run file")(path, self, circuit)

    def plot(self, path=None, signals=None):
        """Pressures (top) and flows (bottom) against time; traces with equal values are
        drawn once (labelled ``a = b``), legends outside the axes.  Saves a PNG when
        ``path`` is given, else returns the figure."""
        from ..common.plotting import draw_traces, pyplot, save

        names = [self._signal_name(n) for n in signals] if signals else list(self.signals)
        pressures = {n[2:]: self[n] for n in names
                     if self.units.get(n) == "kPa" and n.startswith("p_")}
        flows = {n[5:]: self[n] for n in names if self.units.get(n) == "mg/s"}
        plt = pyplot()
        fig, axes = plt.subplots(2 if flows else 1, 1, sharex=True, squeeze=False,
                                 figsize=(8, 6 if flows else 3.5))
        draw_traces(axes[0, 0], self.t, pressures, "pressure (kPa abs)")
        if flows:
            draw_traces(axes[1, 0], self.t, flows, "mass flow (mg/s)")
        axes[-1, 0].set_xlabel("time (s)")
        if self.title:
            fig.suptitle(self.title)
        return save(fig, path) if path is not None else fig


@dataclass(frozen=True, repr=False)
class OperatingPoint(Summarized):
    """A steady state: node pressures (kPa), element flows (mg/s), the flow imbalance
    left by Newton (mg/s) and whether the circuit settles there
    (:class:`~pneunet.engine.stability.Stability`: ``op.stability.stable``)."""

    pressures: Mapping[str, float]
    flows: Mapping[str, float]
    residual: float = 0.0
    stability: Any = None

    def __post_init__(self):
        object.__setattr__(self, "pressures", MappingProxyType(dict(self.pressures)))
        object.__setattr__(self, "flows", MappingProxyType(dict(self.flows)))

    def _summary(self):
        rows = [("pressures", listed((f"{k} {v:.4g} kPa" for k, v in self.pressures.items()),
                                     4)),
                ("flows", f"{len(self.flows)} elements")]
        if self.stability is not None and self.stability.stable is not None:
            lam = self.stability.slowest
            rows.append(("stability", ("stable" if self.stability.stable else "UNSTABLE") +
                         (f" (slowest eigenvalue {lam.real:+.3g} 1/s)" if lam is not None
                          else "")))
        return ("", rows, "op.pressures, op.flows, op.stability.describe(), print(op), "
                          "op.to_pandas()")

    def table(self) -> dict[str, list]:
        """Columns ``signal``, ``value`` (kPa or mg/s) and ``unit``."""
        rows = [("p_" + k, v, "kPa") for k, v in self.pressures.items()]
        rows += [("mdot_" + k, v, "mg/s") for k, v in self.flows.items()]
        return {"signal": [r[0] for r in rows], "value": [r[1] for r in rows],
                "unit": [r[2] for r in rows]}

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.table())

    def __str__(self) -> str:
        lines = [f"  p({k}) = {v:.4f} kPa" for k, v in self.pressures.items()]
        lines += [f"  mdot({k}) = {v:.4f} mg/s" for k, v in self.flows.items()]
        if self.stability is not None:
            lines.append("  " + self.stability.describe())
        return "operating point\n" + "\n".join(lines)


def build_solution(dae, times, states, stats, branch_jumps) -> Solution:
    """Pressures of the unknown nodes now (the states); the pressures sources impose,
    source flows and element signals when first read (:class:`LazySignals`)."""
    import functools

    from ..physics import elements

    states = states.reshape(len(times), dae.n)
    states.setflags(write=False)  # the pressure signals are views of it, handed over uncopied
    inputs_at = left_limits(times)
    history = functools.cache(lambda: dae.full_pressures(inputs_at, states))
    ready, units, pending = {}, {}, {}
    for i, name in enumerate(dae.node_names):
        if name not in dae.state_nodes:  # an element's own state: in its signals
            ready[f"p_{name}"] = states[:, i]
    fixed = [f"p_{name}" for name in dae.fixed_names if not dae.circuit.is_reference(name)]

    def fixed_pressures():
        return {key: history()[:, dae.node_index(key[2:])] for key in fixed}
    pending.update(dict.fromkeys(fixed, fixed_pressures))
    units.update(dict.fromkeys(list(ready) + fixed, "kPa"))
    sources = [f"mdot_{name}" for name in dae.pinned_sources()]

    def source_flows():
        return {f"mdot_{name}": flow for name, flow in dae.source_flows(inputs_at, history()).items()}
    pending.update(dict.fromkeys(sources, source_flows))
    units.update(dict.fromkeys(sources, "mg/s"))
    checked = []  # one signal of each family that checks a run (its warnings)
    for names, signal_units, compute in dae.element_signal_groups(inputs_at, states, history):
        pending.update(dict.fromkeys(names, compute))
        units.update(zip(names, signal_units))
        spec = dae.circuit.elements.get(names[0].split("_", 1)[1])
        if spec is not None and elements.family(spec.kind).checks_run:
            checked.append(names[0])
    ordered = {k: pending[k] for k in fixed}  # node pressures first, as before
    ordered.update((k, v) for k, v in pending.items() if k not in ordered)
    signals = LazySignals(ready, ordered)
    if len(times) > 1:
        for name in checked:
            signals[name]  # noqa: B018 - computed now: the family's run warnings, once
    return Solution(times, signals, units, stats, dae.circuit.title, branch_jumps)


def left_limits(times: np.ndarray) -> np.ndarray:
    """The times at which the sources are evaluated for each row: a row followed by one at
    the same time (the two sides of a jump) takes the inputs just before it (the next
    float below), so that both sides of every source discontinuity are kept."""
    times = np.asarray(times, dtype=float)
    if times.size < 2:
        return times
    before = np.append(times[1:] == times[:-1], False)
    if not before.any():
        return times
    out = times.copy()
    out[before] = np.nextafter(times[before], -np.inf)
    return out
