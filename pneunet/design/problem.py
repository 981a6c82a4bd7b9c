"""A design problem: circuit builder, targets and the shared simulation runner.

:class:`Problem` reads a netlist (or takes a Python builder), turns target strings into
:class:`~pneunet.design.spec.Target` objects with the netlist's ``.meas`` units, checks
that every parameter name exists before anything is simulated, and evaluates batches of
points on the sweep machinery (:func:`~pneunet.design.sweep.run_sweep`) with one process
pool (or dask client) for the whole design, counting the simulations.
"""
from __future__ import annotations

import math
from pathlib import Path

from ..netlist.builder import name_hint
from . import sweep as S
from .metrics import SpecMeasure
from .spec import check_meas_targets, parse_targets

#: batches larger than this draw a progress bar (not the Jacobian's few points)
BAR_MIN_POINTS = 8


class Problem:
    """``build``: a netlist path, a :class:`NetlistBuilder` or a picklable
    ``build(point) -> Circuit``; ``targets``: strings or Targets; ``fixed``: parameter
    values set at every point; ``workers``/``executor``: as for ``run_sweep``."""

    def __init__(self, build, targets, *, node: str | None = None, t_stop: float | None = None,
                 fixed: dict | None = None, workers: int | None = None, executor=None,
                 progress: bool = False):
        if isinstance(build, (str, Path)):
            build = S.NetlistBuilder(build)
        S.require_builder(build, "design")
        self.build, self.fixed = build, dict(fixed or {})
        measures, ambient = {}, 96.0
        if isinstance(build, S.NetlistBuilder):
            from ..netlist.runner import measure_unit

            deck = build.deck()
            measures = {m.name: measure_unit(m) for m in deck.measures}
            ambient = deck.circuit.options.ambient
        self.targets = parse_targets(list(targets or ()), measures, ambient)
        if isinstance(build, S.NetlistBuilder):
            check_meas_targets(self.targets, {m.name: m.kind for m in deck.measures})
        if not self.targets:
            from ..common.errors import ParameterError

            raise ParameterError("no target given", hint="e.g. --target period=3s")
        self.analysis = SpecMeasure(self.targets, build if isinstance(build, S.NetlistBuilder)
                                    else None, node=node, t_stop=t_stop)
        self.workers, self.executor, self.progress = workers, executor, progress
        self._pool, self._depth = None, 0
        self.simulations = self.failed = 0
        self._cache: dict = {}

    def check(self, point: dict) -> None:
        """Every name of ``point`` exists (did-you-mean otherwise), before simulating; a
        plain name that is no ``.param`` but an element parameter names ELEMENT.PARAM."""
        from ..common.errors import PneunetError

        try:
            S.check_points(self.build, [dict(self.fixed, **point)])
        except PneunetError as err:
            plain = [k for k in point if "." not in k]
            if not plain or not isinstance(self.build, S.NetlistBuilder):
                raise
            circuit = self.build.deck().circuit
            for name in plain:
                owners = [f"{e}.{name}" for e, spec in circuit.elements.items()
                          if name in spec.params]
                if owners and f"{name!r}" in err.message:
                    raise type(err)(err.message, where=err.where,
                                    hint=f"an element parameter is ELEMENT.PARAM: "
                                         f"{', '.join(owners)}") from None
            raise
        self._check_nodes(point)

    def _check_nodes(self, point: dict) -> None:
        """The nodes of the built-in metrics exist (did-you-mean otherwise)."""
        from ..common.errors import ParameterError
        from .metrics import control_node

        builtin = [t for t in self.targets if t.source == "builtin"]
        if not builtin:
            return
        full = dict(self.fixed, **point)
        circuit = S.apply_overrides(self.build(full), full)
        for t in builtin:
            node = t.node or self.analysis.node or control_node(circuit)
            if node not in circuit.nodes:
                raise ParameterError(f"target {t.text!r}: no node {node!r}",
                                     hint=name_hint(node, circuit.nodes, "nodes"))

    def __enter__(self):
        """One process pool for every batch until the outermost ``with`` ends."""
        import os

        from ..common.workers import process_pool

        self._depth += 1
        if self._depth == 1 and self.executor is None and \
                (self.workers or os.cpu_count() or 1) > 1:
            self._pool = process_pool(self.workers or os.cpu_count() or 1)
        return self

    def __exit__(self, kind, *rest):
        self._depth -= 1
        if self._pool is not None and (self._depth == 0 or kind is not None):
            if kind is None:
                self._pool.shutdown(wait=True)
            else:
                from ..common.workers import stop

                stop(self._pool)
            self._pool = None

    def evaluate(self, points: list[dict]) -> list[dict]:
        """Records (``params``, ``result``, ``error``) of ``points`` in order; a point
        evaluated before comes from the cache."""
        full = [dict(self.fixed, **p) for p in points]
        keys = [S.point_key(p) for p in full]
        todo = list({k: p for k, p in zip(keys, full) if k not in self._cache}.items())
        if todo:
            executor = self.executor or self._pool
            result = S.run_sweep(self.build, [p for _, p in todo], self.analysis,
                                 executor=executor, workers=1 if executor is None else None,
                                 progress=self.progress and len(todo) > BAR_MIN_POINTS)
            rows = result.table.to_dict(orient="records")
            for (k, p), row in zip(todo, rows):
                self._cache[k] = row
            self.simulations += len(todo)
            self.failed += result.failed
        return [self._cache[k] for k in keys]

    def metrics(self, row: dict) -> dict:
        """``{target key: value}`` of an evaluated row (NaN where not measured)."""
        out = {}
        for t in self.targets:
            v = row.get(t.key)
            out[t.key] = float(v) if v is not None and row.get("error") is None \
                and not (isinstance(v, float) and math.isnan(v)) else math.nan
        return out

    def met(self, metrics: dict) -> bool:
        return all(t.met(metrics[t.key]) for t in self.targets)
