"""One simulation → the metrics a specification needs (the sweep analysis of a design).

:class:`SpecMeasure` runs a netlist's own analyses (its ``.tran`` and ``.meas``) or, for a
Python builder, a transient of ``t_stop`` seconds; then it measures the built-in
oscillation metrics (:data:`~pneunet.design.spec.BUILTIN`) at the targets' nodes with
:func:`~pneunet.engine.oscillation.analyze_oscillation`.  A metric that cannot be
measured (no oscillation: no period) is NaN.
"""
from __future__ import annotations

import math

from .cycles import steady_transient
from .sweep import DeckMeasure, measured
from ..netlist.builder import NetlistBuilder
from ..common.errors import ParameterError

#: this process's last deck, by (builder, .param values): a yield's samples differ in
#: element parameters only, and read the analyses and .meas lines of one elaboration
_LAST_DECK: dict = {}


def control_node(circuit) -> str:
    """The control node of the circuit's first valve (an oscillator's tank)."""
    for spec in circuit.elements.values():
        if spec.kind == "valve":
            return spec.nodes[2]
    raise ParameterError(f"circuit {circuit.name!r} has no valve: give built-in metrics a "
                         "node", hint="e.g. period@tank=3s")


def builtin_metrics(t, p) -> dict:
    """Period (s), frequency (Hz), duty, swing, p_min, p_max (kPa) of the pressure p(t)."""
    from ..engine.oscillation import analyze_oscillation

    osc = analyze_oscillation(t, p)
    sustained = osc.oscillating
    return {"period": osc.period_s if sustained else math.nan,
            "frequency": osc.frequency_hz if sustained else math.nan,
            "duty": osc.duty_cycle if sustained else math.nan,
            "swing": osc.p_max - osc.p_min, "p_min": osc.p_min, "p_max": osc.p_max}


class SpecMeasure(DeckMeasure):
    """The sweep analysis of a specification: ``{target.key: value}`` for every target.

    ``builder``: a :class:`NetlistBuilder` (its analyses and ``.meas`` run) or None (a
    Python builder: ``t_stop`` s of transient); ``node``: default node of built-ins;
    ``steady``: a circuit with constant sources is simulated until its cycle repeats and
    the rest of the transient is that cycle again (:mod:`~pneunet.design.cycles`; False:
    the whole transient is integrated).
    """

    def __init__(self, targets, builder: NetlistBuilder | None = None, node: str | None = None,
                 t_stop: float | None = None, steady: bool = True):
        super().__init__(builder)
        self.targets, self.node, self.t_stop = list(targets), node, t_stop
        self.steady = steady

    def __call__(self, circuit, point=None):
        if self.builder is not None:
            meas, sol = self._run_deck(circuit, point)
        else:
            if not self.t_stop:
                raise ParameterError("a design of a Python-built circuit needs t_stop (s)")
            sol = steady_transient(circuit, self.t_stop) if self.steady else None
            meas, sol = {}, sol or circuit.tran(self.t_stop)
        out, by_node = {}, {}
        for target in self.targets:
            if target.source == "meas":
                out[target.key] = meas.get(target.metric, math.nan)
                continue
            node = target.node or self.node or control_node(circuit)
            if node not in by_node:
                if sol is None:
                    raise ParameterError(f"target {target.text!r} needs a transient",
                                         hint="add a .tran line to the netlist")
                by_node[node] = builtin_metrics(sol.t, sol.pressure(node))
            out[target.key] = by_node[node][target.metric]
        return out, sol

    def _run_deck(self, circuit, point):
        """The netlist's ``.meas`` values and its transient; a deck of one ``.tran`` on
        its steady cycle when ``steady`` (the whole deck run otherwise)."""
        from ..netlist.deck import Tran
        from ..netlist.runner import evaluate_measures

        key = (self.builder._token,
               sorted((k, v) for k, v in (point or {}).items() if "." not in k))
        last = _LAST_DECK.get("last")  # one read: threads of a dask worker share it
        if last is None or last[0] != key:
            last = _LAST_DECK["last"] = (key, self.builder.deck(point))
        deck = last[1]
        if self.steady and len(deck.analyses) == 1 and isinstance(deck.analyses[0], Tran):
            tran = deck.analyses[0]
            sol = steady_transient(circuit, tran.t_stop, tran.t_step, tran.t_start,
                                   deck.source.limits.max_output_points)
            if sol is not None:
                return measured(*evaluate_measures(deck.measures, [(tran, sol)])), sol
        return super().__call__(circuit, point)

    def __repr__(self):
        return f"SpecMeasure({[t.text for t in self.targets]})"
