"""Multirate transient of cells that only read the hub: the hub first, then the cells.

When no cell passes flow at a hub node — the cells touch the hub only through ports
that are dead ends, such as the control ports of membrane valves (a demultiplexer's
address lines, each driving many valves) — the hub does not depend on the cells.
Waveform relaxation (:mod:`~pneunet.engine.multirate`) would sweep each window twice
only to find that nothing changed.  Instead:

1. the hub is integrated once, alone, by single-rate IDA, storing every step
   (t, p, ṗ);
2. the cubic Hermite through those steps (the single-rate solver's dense output)
   pins each hub node as a pressure source of the cells
   (:class:`~pneunet.physics.waveforms.SampleTable`), with the hub's corners (where its own
   inputs kink) as the source's corners;
3. the cells, no longer coupled at all, are integrated as independent circuits by
   :mod:`~pneunet.engine.multirate`: cells of one structure as arrays, each on its own
   steps; a cell with nodes without volume on its own, with fold jumps.

Nothing is iterated: the only coupling error is the hub's own error and that of the
cubic between its steps, both the single-rate solver's.  (Integrating the hub's
independent pieces on their own Radau steps instead was measured: the 6-bit
demultiplexer's six inverters took 2,821 passes, 2.2–2.6 s, against 1.2 s.)
"""
from __future__ import annotations

import time as _time

import numpy as np

from ..physics.elements.base import ElementSpec
from ..common.errors import SolverError
from ..physics.waveforms import SampleTable, Sampled
from .assembly import CircuitDAE
from .multirate import transient as multirate
from .partition import Partition, partition
from .single_rate import integrate
from .solution import Solution, build_solution


def transient(circuit, dae: CircuitDAE, part: Partition, t_stop: float, t_step: float | None,
              t_start: float, y0: np.ndarray, algebraic: set[str], single_rate) -> Solution:
    """As :func:`pneunet.engine.multirate.transient`, for a partition whose hub no cell
    draws from (``part.read_only_hub``)."""
    wall = _time.perf_counter()
    table, hub_nodes, corners, hub_steps = _integrate_hub(
        circuit.subcircuit(part.hub_sources + part.hub_elements, part.hub_nodes,
                           f"{circuit.title} (hub)"),
        {n: y0[dae.node_index(n)] for n in part.hub_nodes},
        t_start, t_stop)
    cells = _cells_circuit(circuit, part, table, hub_nodes, corners)
    cells_dae = CircuitDAE(cells, validate=False)
    index = [dae.node_index(n) for n in cells_dae.node_names]
    hub_index = [dae.node_index(n) for n in hub_nodes]
    try:
        sol = multirate(cells, cells_dae, partition(cells), t_stop, t_step, t_start, y0[index],
                        algebraic - set(hub_nodes), single_rate)
    except SolverError as err:
        partial = None if err.partial is None else _whole(dae, err.partial, index, hub_index,
                                                          table, dict(err.partial.stats))
        raise SolverError(err.message, time=err.time, where=err.where, hint=err.hint,
                          partial=partial) from None
    stats = dict(sol.stats, method="multirate (hub first)", hub_nodes=len(hub_nodes),
                 hub_steps=hub_steps, steps=int(sol.stats.get("steps", 0)) + hub_steps,
                 unknowns=dae.n, algebraic=len(algebraic),
                 wall_time_s=_time.perf_counter() - wall)
    return _whole(dae, sol, index, hub_index, table, stats)


def _integrate_hub(hub, y0, t_start, t_stop):
    """Integrate the hub (single-rate IDA) from its pressures ``y0`` {node: kPa}; return
    the table of its nodes' pressures and rates (kPa, kPa/s) at every step, the nodes
    (its columns), its corners (s) and the IDA steps.  At a jump of a source the time
    repeats: the rate before it, then the rate after it."""
    hub_dae = CircuitDAE(hub, validate=False)
    y = np.array([y0[n] for n in hub_dae.node_names])
    record, steps, _ = integrate(hub_dae, t_start, t_stop, y, hub_dae.derivative(t_start, y),
                                 rates=True)
    t, states = record.arrays()
    table = SampleTable(t, states, record.rates())
    return table, hub_dae.node_names, hub_dae.breakpoints(t_start, t_stop), steps


def _cells_circuit(circuit, part, table, hub_nodes, corners):
    """The cells' elements and sources, each of the ``hub_nodes`` pinned by a source
    that follows its column of ``table``, with the hub's ``corners`` (s)."""
    cells = circuit.subcircuit(
        list(dict.fromkeys(n for cell in part.cells for n in cell.sources + cell.elements)),
        [n for cell in part.cells for n in cell.nodes])
    for column, node in enumerate(hub_nodes):
        name = f"{node}@hub"
        cells.elements[name] = ElementSpec("pressure_source", name, (node,),
                                           {"value": Sampled(table, column, corners)})
    return cells


def _whole(dae, sol, index, hub_index, table, stats) -> Solution:
    """The whole circuit's solution: the cells' unknowns from ``sol``, the hub's from
    ``table`` at the same times."""
    states = np.empty((sol.t.size, dae.n))
    states[:, index] = np.column_stack([sol.pressure(dae.node_names[i]) for i in index])
    for column, i in enumerate(hub_index):
        states[:, i] = table.at(sol.t, np.full(sol.t.size, column))
    return build_solution(dae, sol.t, states, stats, ())
