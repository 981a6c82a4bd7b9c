"""Fluid-logic checks: truth tables with settle times and pressure margins.

For every combination of logic inputs (pressure sources set to ``low`` or ``high``)
the circuit starts from its settled state with all inputs low (a transient of
``t_settle`` from the initial conditions), the inputs step to the
combination at t = 0, and a transient runs until the outputs settle.  Reported per row:
the input bits, each output's final pressure and logic value (above ``threshold``), its
settle time (last time it was outside ±``settle_band`` of its final value) and, per
output over the table, the margin between the lowest "high" and the highest "low"
pressure (positive = the levels are distinguishable) and the margins to the threshold.

Works for circuits built in Python (``build(point)``, inputs as ``ELEMENT.value``) and
for netlists through :class:`~pneunet.netlist.builder.NetlistBuilder` (e.g.
``netlists/inverter.pn`` with input source ``Pin``, ``netlists/demux3.pn`` with
``PA[0]``..``PA[2]``): waveform sources are replaced by constant levels.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..common.errors import PneunetError
from ..common.reprs import Summarized, listed


@dataclass(repr=False)
class TruthTable(Summarized):
    """``table``: one row per input combination; ``margins``: one row per output."""

    table: object
    margins: object
    inputs: dict
    outputs: list
    threshold: float

    def _summary(self):
        rows = [("inputs", listed(self.inputs)), ("outputs", listed(self.outputs)),
                ("rows", str(len(self.table))), ("threshold", f"{self.threshold:.4g} kPa")]
        if "ok" in self.table:
            rows.append(("as expected", f"{int(self.table['ok'].sum())} of {len(self.table)}"))
        if len(self.margins):
            rows.append(("smallest margin", f"{self.margins['margin_kPa'].min():.4g} kPa"))
        return "", rows, ".table, .margins, .ok(), plot_truth_table(tt)"

    def ok(self) -> bool:
        return bool(self.table["ok"].all()) if "ok" in self.table else True


def _settle_time(t, y, band):
    final = y[-1]
    outside = np.nonzero(np.abs(y - final) > band)[0]
    if outside.size == 0:
        return 0.0
    i = outside[-1]
    return float(t[min(i + 1, len(t) - 1)])


def truth_table(build, inputs: dict, outputs: list, *, low: float = 96.0, high: float = 496.0,
                threshold: float | None = None, expected=None, t_settle: float = 5.0,
                settle_band: float = 0.02, fixed: dict | None = None) -> TruthTable:
    """Truth table of a fluid-logic circuit.

    ``inputs``: {logic name: pressure-source element}; ``outputs``: node names;
    ``expected(bits) -> tuple of output bits`` adds an ``ok`` column; ``t_settle``: the
    transient length (s) after the input step; ``settle_band``: fraction of
    (high − low) defining "settled".
    """
    import pandas as pd

    from ..netlist.builder import apply_overrides, require_builder

    require_builder(build, "truth_table")
    if not isinstance(inputs, dict) or not inputs:
        raise PneunetError(f"truth_table inputs must be a dict {{logic name: pressure source "
                           f"element}}, e.g. {{'A': 'Pin'}}, got {inputs!r}")
    if isinstance(outputs, str) or not all(isinstance(o, str) for o in outputs):
        raise PneunetError(f"truth_table outputs must be a list of node names, e.g. ['out'], "
                           f"got {outputs!r}")
    threshold = 0.5 * (low + high) if threshold is None else threshold
    band = settle_band * (high - low)
    names = list(inputs)

    def circuit(bits):
        point = dict(fixed or {})
        point.update({f"{inputs[n]}.value": (high if b else low) for n, b in zip(names, bits)})
        c = build(point)
        apply_overrides(c, point)
        return c

    # the state with all inputs low, settled by a transient (an operating-point solve can
    # land anywhere on a node isolated by closed valves)
    first = circuit((0,) * len(names))
    missing = [node for node in outputs if node not in first.nodes]
    if missing:
        raise PneunetError(f"truth_table outputs {missing} are not nodes of the circuit",
                           hint="nodes: " + ", ".join(first.nodes))
    settled = first.tran(t_settle).final()
    base_p = {k[2:]: v for k, v in settled.items() if k.startswith("p_")}
    rows = []
    for bits in itertools.product((0, 1), repeat=len(names)):
        c = circuit(bits)
        for node, p in base_p.items():
            if node in c.nodes and not c.is_reference(node):
                c.set_initial(node, p)
        try:
            sol = c.tran(t_settle)
        except PneunetError as err:
            rows.append({**dict(zip(names, bits)), "error": str(err)})
            continue
        row = dict(zip(names, bits))
        out_bits = []
        for node in outputs:
            y = sol.pressure(node)
            row[f"p_{node}"] = float(y[-1])
            bit = int(y[-1] > threshold)
            out_bits.append(bit)
            row[node] = bit
            row[f"settle_{node}_s"] = _settle_time(sol.t, y, band)
        row["settle_s"] = max(row[f"settle_{n}_s"] for n in outputs)
        if expected is not None:
            want = tuple(int(b) for b in np.atleast_1d(expected(bits)))
            row["ok"] = tuple(out_bits) == want
        rows.append(row)
    table = pd.DataFrame(rows)
    margins = []
    for node in outputs:
        col = table.get(f"p_{node}")
        if col is None:
            continue
        hi = col[col > threshold]
        lo = col[col <= threshold]
        margins.append({"output": node, "min_high_kPa": float(hi.min()) if len(hi) else np.nan,
                        "max_low_kPa": float(lo.max()) if len(lo) else np.nan,
                        "margin_kPa": float(hi.min() - lo.max()) if len(hi) and len(lo) else np.nan,
                        "high_margin_to_threshold": float(hi.min() - threshold) if len(hi) else np.nan,
                        "low_margin_to_threshold": float(threshold - lo.max()) if len(lo) else np.nan,
                        "max_settle_s": float(table[f"settle_{node}_s"].max())})
    return TruthTable(table, pd.DataFrame(margins), dict(inputs), list(outputs), threshold)


def demux_expected(bits):
    """Expected outputs of the 3-bit demultiplexer: only act[k] high, k = Σ bit_i 2^i
    (``bits`` ordered a0, a1, a2)."""
    k = sum(b << i for i, b in enumerate(bits))
    return tuple(int(j == k) for j in range(8))


def plot_truth_table(tt: TruthTable, path=None, title=None):
    """Output pressures per input combination (bars) with the threshold line."""
    from ..common.plotting import legend_outside, pyplot, save

    plt = pyplot()
    tab = tt.table
    labels = ["".join(str(int(r[n])) for n in tt.inputs) for _, r in tab.iterrows()]
    fig, ax = plt.subplots(figsize=(max(5, 0.5 * len(labels) * len(tt.outputs) ** 0.5 + 3), 3.8))
    w = 0.8 / len(tt.outputs)
    for j, node in enumerate(tt.outputs):
        ax.bar(np.arange(len(labels)) + j * w - 0.4 + w / 2, tab[f"p_{node}"], w, label=node)
    ax.axhline(tt.threshold, color="k", ls="--", lw=0.8, label="threshold")
    ax.set_xticks(np.arange(len(labels)))
    ax.set_xticklabels(labels)
    ax.set_xlabel("inputs " + "".join(tt.inputs))
    ax.set_ylabel("output pressure (kPa abs)")
    legend_outside(ax, fontsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    return save(fig, path) if path is not None else fig
