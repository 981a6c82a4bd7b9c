"""Many cells of one structure as one array problem, each cell at its own time.

:class:`CellBatch` assembles the cells of a group (see :mod:`~pneunet.engine.partition`)
into one :class:`~pneunet.engine.assembly.CircuitDAE` whose Jacobian is block
diagonal, one (k, k) block per cell.  Every cell has private copies of the pinned
nodes it touches and of the hub nodes (*boundary* nodes, their pressures given by
the driver), so that a cell's sources and boundary can be evaluated at that cell's
own time.  The hub itself is a batch of one cell with the cells' flows injected.

A pass of the integrator only needs the cells that still step: :meth:`CellBatch.rows`
gives an evaluator of a subset of the cells (their element instances as families of
their own), so that the cost of a pass follows the cells that are active in it.
:meth:`CellBatch.evaluate_stages` evaluates a Newton iteration's three Radau stages
with one call of each family (arrays with a leading stage axis).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..common.errors import ParameterError
from ..physics.waveforms import Constant
from .assembly import CircuitDAE
from .partition import time_dependent

SUBSET_FRACTION = 0.75  # active share of a batch's cells below which a pass evaluates them alone
SUBSET_MIN_CELLS = 200  # batches from which that pays (smaller ones: the fixed cost dominates)


class CellBatch:
    """Residuals and Newton blocks of G cells with k unknowns each (kPa, mg/s).

    ``boundary(t) -> (G, c)`` gives hub pressures at the cells' times t (G,), of which
    cell g's boundary node j reads column ``boundary_cols[g, j]`` (default j: the
    boundary nodes in order; cells of one structure may sit on different hub nodes);
    ``injection(t, Y) -> (flows, slopes)`` adds flows (n, k)
    (mg/s) leaving each unknown node (the hub's cells) and their derivatives by the
    node's own pressure (n, k), mg/(s·kPa), at the times t (n,) for the states Y (n, k):
    the G cells' times, or a pass's three stage times of each (n = 3·G).  Either may be
    None.
    """

    def __init__(self, circuit, cells, hub_nodes=(), title="cells"):
        sub = type(circuit)(title, circuit.options)
        self._boundary_names = []
        for k, cell in enumerate(cells):
            rename = {n: f"{n}@{k}" for n in cell.hub_nodes}
            for source in cell.sources:
                spec = circuit.elements[source]
                rename[spec.nodes[0]] = f"{spec.nodes[0]}@{k}"
                sub.elements[f"{source}@{k}"] = replace(
                    spec, name=f"{source}@{k}", nodes=tuple(rename.get(n, n) for n in spec.nodes))
            for name in cell.elements:
                spec = circuit.elements[name]
                if len(cells) > 1 and time_dependent(spec.kind):
                    raise ParameterError(f"element {name} ({spec.kind}) depends on time itself: "
                                         "cells of the multirate method cannot hold it",
                                         where=spec.where, hint=".options method=single")
                sub.elements[name] = replace(spec, nodes=tuple(rename.get(n, n) for n in spec.nodes))
            for hub in cell.hub_nodes:
                name = f"_boundary_{hub}@{k}"
                sub.elements[name] = _placeholder(name, rename[hub], circuit.options.ambient)
            self._boundary_names.append([rename[h] for h in cell.hub_nodes])
            for node in cell.nodes:
                if node in circuit.initial:
                    sub.initial[node] = circuit.initial[node]
        for name in hub_nodes:
            if name in circuit.initial:
                sub.initial[name] = circuit.initial[name]
        self.dae = dae = CircuitDAE(sub, validate=False)
        self.G, self.k = len(cells), len(cells[0].nodes)
        #: (G, k) indices of each cell's unknowns in the batch DAE
        self.idx = np.array([[dae.node_index(n) for n in c.nodes] for c in cells], dtype=int)
        self.names = [list(c.nodes) for c in cells]
        self.nb = len(self._boundary_names[0])
        self._boundary_idx = np.array([[dae.node_index(n) for n in names]
                                       for names in self._boundary_names], dtype=int).reshape(
                                           self.G, self.nb)
        self.boundary = None
        self.boundary_cols = np.broadcast_to(np.arange(self.nb), (self.G, self.nb))
        self.injection = None
        self._build_maps(cells)
        self._whole = _Rows(self, np.arange(self.G))  # every cell
        self._view = None  # the last subset evaluator (see rows)

    def _build_maps(self, cells):
        dae = self.dae
        n_all = dae.n + len(dae.fixed_names)
        cell_of = np.full(n_all, -1)
        cell_of[self.idx] = np.arange(self.G)[:, None]
        cell_of[self._boundary_idx] = np.arange(self.G)[:, None]
        source_cell = {f"{s}@{k}": k for k, c in enumerate(cells) for s in c.sources}
        for name, k in source_cell.items():
            cell_of[dae.node_index(dae.circuit.elements[name].nodes[0])] = k
        self._pinned = []
        for family, nodes in dae._pinned:
            self._pinned.append((family, nodes, np.maximum(cell_of[nodes[:, 0]], 0)))
        self._n_all = n_all
        # CSC data position of each (cell, row, column) entry of the blocks (nnz: zero)
        pos = np.full((self.G, self.k, self.k), dae.nnz)
        local = np.empty(dae.n, dtype=int)
        local[self.idx] = np.arange(self.k)[None, :]
        owner = np.empty(dae.n, dtype=int)
        owner[self.idx] = np.arange(self.G)[:, None]
        rows, cols = dae.entries()
        if np.any(owner[rows] != owner[cols]):
            raise AssertionError("cells of a batch are coupled")  # partition guarantees not
        pos[owner[rows], local[rows], local[cols]] = np.arange(dae.nnz)
        self._pos = pos
        self.differential = dae.differential[self.idx[0]]
        # the cell of each instance of each family with a port at an unknown node
        self._instance_cell = [cell_of[b.port_node].max(axis=1) for b in dae._active]

    def evaluate(self, t, Y, Yd, jacobian=False):
        """R (G, k) and the boundary outflows (G, nb), mg/s; with ``jacobian`` also the
        blocks ∂F/∂y and ∂F/∂ẏ (G, k, k).  ``t`` (G,): each cell's time (s)."""
        result = self._whole.evaluate(t, Y, Yd, jacobian)
        if self.injection is None:
            return result
        flows, slopes = self.injection(t, Y)
        if not jacobian:
            return result[0] + flows, result[1]
        res, out, jac, mass = result
        if slopes is not None:
            jac[:, np.arange(self.k), np.arange(self.k)] += slopes
        return res + flows, out, jac, mass

    def evaluate_stages(self, times, Y, Yd):
        """R (3, G, k) and boundary outflows (3, G, nb) at the three stage times ``times``
        (three (G,) arrays) with Y, Yd (3, G, k): one evaluation of each family for all
        three (:meth:`_Rows.evaluate_stages`), and of the injection at the 3·G times."""
        res, out = self._whole.evaluate_stages(times, Y, Yd)
        if self.injection is not None:
            res += self.injection(np.concatenate(times), Y.reshape(-1, self.k))[0] \
                .reshape(res.shape)
        return res, out

    def rows(self, active: np.ndarray):
        """An evaluator of (at least) the cells ``active`` (sorted indices) and the cells
        it holds, or (None, None) when the whole batch is as cheap.  A subset evaluator
        is kept while the active cells stay within it and fill at least half of it."""
        if self.injection is not None or self.G < SUBSET_MIN_CELLS or \
                active.size > SUBSET_FRACTION * self.G:
            return None, None
        view = self._view
        if view is None or active.size * 2 < view.rows.size or \
                not view.holds[active].all():
            view = self._view = _Rows(self, active)
        return view.rows, view

    def rates(self, t, Y, Yd_guess):
        return consistent_rates(self, t, Y, Yd_guess)


class _Inputs:
    """The pressures cells do not solve for — their pinned nodes (sources at each
    cell's own time) and boundary nodes (the driver's ``boundary(t)``) — at one set of
    cell times or at a Radau iteration's three, kept for the last read-only first time
    array by identity: a pass evaluates its three stage times (which it makes read-only)
    once per Newton iteration."""

    def __init__(self, pinned, boundary_idx, boundary_cols, width):
        self.pinned, self.boundary_idx, self._cols = pinned, boundary_idx, boundary_cols
        nodes = [n for _, n, _ in pinned] + ([boundary_idx] if boundary_idx is not None else [])
        #: the input nodes, flat, in the order of :meth:`values`'s columns
        self.nodes = np.concatenate([n.ravel() for n in nodes] + [np.empty(0, int)])
        #: (3, L) their positions in flattened (3, ``width``) stage buffers
        self.stage_nodes = width * np.arange(3)[:, None] + self.nodes[None, :]
        self._kept = None  # (first time array, boundary function, values)

    def fill(self, batch, idx, t, Y, Yd):
        """The batch DAE's shared pressure and rate buffers with the cells' unknowns
        ``idx`` at Y, Yd and their inputs at times t."""
        dae = batch.dae
        p, pdot = dae._p, dae._pdot
        p[idx] = Y
        pdot[idx] = Yd
        p[self.nodes] = self.values([t], batch.boundary)[0]
        dae._pinned_at = None  # the shared buffer no longer holds one time's pressures
        return p, pdot

    def fill_stages(self, batch, buffers, flat_idx, times, Y, Yd):
        """As :meth:`fill` for three stages at once, into the rows of ``buffers`` (3, n);
        ``flat_idx`` (3, m, k): the unknowns' positions in the flattened buffers."""
        P, Pdot = buffers
        P.reshape(-1)[flat_idx] = Y  # 4× faster than P[:, idx] = Y
        Pdot.reshape(-1)[flat_idx] = Yd
        P.reshape(-1)[self.stage_nodes] = self.values(times, batch.boundary)
        return P, Pdot

    def values(self, times, boundary):
        """The inputs (len(times), L) at each of the cell-time arrays ``times`` (m,), in
        the order of :attr:`nodes`: each source once per time array, the boundary once
        for all of them."""
        kept = self._kept
        if kept is not None and kept[0] is times[0] and kept[1] is boundary \
                and len(kept[2]) == len(times):
            return kept[2]
        n, m = len(times), times[0].size
        values = [np.stack([family.pinned_pressure_each(t[cell]) for t in times])
                  .reshape(n, -1) for family, _, cell in self.pinned]
        if self.boundary_idx is not None:
            cols = np.tile(self._cols(), (n, 1))
            values.append(boundary(np.concatenate(times))[np.arange(n * m)[:, None], cols]
                          .reshape(n, -1))
        values = np.concatenate(values + [np.empty((n, 0))], axis=1)
        if not times[0].flags.writeable:  # cannot change while kept
            self._kept = (times[0], boundary, values)
        return values


def consistent_rates(problem, t, Y, Yd_guess):
    """ẏ consistent with Y at times t: the mass blocks solved for −F(ẏ = guess)."""
    res, _, _, mass = problem.evaluate(t, Y, Yd_guess, jacobian=True)
    d = problem.differential
    out = Yd_guess.copy()
    sub = mass[:, d][:, :, d]
    out[:, d] = Yd_guess[:, d] - np.linalg.solve(sub, res[:, d, None])[..., 0]
    return out


class _Rows:
    """Residuals and Newton blocks of the cells ``rows`` of a batch (all of them, or a
    subset: the same numbers for those cells, from their element instances only)."""

    def __init__(self, batch: CellBatch, rows: np.ndarray):
        self.batch, self.rows, self.G = batch, rows, rows.size
        self.holds = np.zeros(batch.G, dtype=bool)
        self.holds[rows] = True
        self.differential, self.names = batch.differential, batch.names
        dae, m, k, nb = batch.dae, rows.size, batch.k, batch.nb
        self.idx, self.boundary_idx = batch.idx[rows], batch._boundary_idx[rows]
        # local numbering: the cells' unknowns, then their boundary nodes, then a sink
        local = np.full(batch._n_all, m * (k + nb))
        local[self.idx] = np.arange(m * k).reshape(m, k)
        local[self.boundary_idx] = m * k + np.arange(m * nb).reshape(m, nb)
        self.size = m * (k + nb) + 1
        # local position of each Newton-block entry (m·k·k: absent from the pattern)
        where = batch._pos[rows].ravel()
        remap = np.full(dae.nnz + 1, m * k * k)
        remap[where] = np.arange(m * k * k)
        remap[dae.nnz] = m * k * k
        self.blocks, flow_to, partial_to = [], [], []
        for block, cells in zip(dae._active, batch._instance_cell):
            inst = np.flatnonzero(self.holds[cells])
            if not inst.size:
                continue
            family = block.family if inst.size == block.family.n else \
                type(block.family)([block.family.specs[i] for i in inst], block.family.context)
            nodes = block.port_node[inst]
            self.blocks.append((family, nodes))
            flow_to.append(local[nodes].ravel())
            ports = nodes.shape[1]
            pairs = dae._partial_to[block.partials].reshape(-1, ports * ports)[inst]
            partial_to.append(remap[pairs].ravel())
        self.flow_to, self.partial_to = np.concatenate(flow_to), np.concatenate(partial_to)
        # the same for three stages' flows at once, family by family stage-major
        self._flow_to_stages = np.concatenate([(to[None, :] + self.size * np.arange(3)[:, None])
                                               .ravel() for to in flow_to])
        # (3, n) pressures and rates of three stages, and the unknowns' flat positions
        self._stage_buffers = (np.tile(dae._p, (3, 1)), np.zeros((3, dae._p.size)))
        self._stage_idx = dae._p.size * np.arange(3)[:, None, None] + self.idx[None]
        pinned = []
        for family, nodes, cell in batch._pinned:
            inst = np.flatnonzero(self.holds[cell])
            if inst.size:
                sub = family if inst.size == family.n else \
                    type(family)([family.specs[i] for i in inst], family.context)
                pinned.append((sub, nodes[inst], np.searchsorted(rows, cell[inst])))
        self._inputs = _Inputs(pinned, self.boundary_idx if nb else None,
                               lambda: batch.boundary_cols[rows], dae._p.size)

    def evaluate(self, t, Y, Yd, jacobian=False):
        """As :meth:`CellBatch.evaluate` for the cells ``rows``: t (m,), Y, Yd (m, k)."""
        batch = self.batch
        m, k, nb = self.rows.size, batch.k, batch.nb
        p, pdot = self._inputs.fill(batch, self.idx, t, Y, Yd)
        # the hub (a batch of one) may hold elements that depend on time; cells do not
        time = float(t[0]) if batch.G == 1 else np.nan
        flows, by_p, by_pdot = [], [], []
        for family, nodes in self.blocks:
            if not jacobian:
                flows.append(family.flows(time, p[nodes], pdot[nodes]).ravel())
                continue
            q, dq_dp, dq_dpdot = family.outflows(time, p[nodes], pdot[nodes])
            flows.append(q.ravel())
            by_p.append(dq_dp.ravel())
            by_pdot.append(np.zeros(dq_dp.size) if dq_dpdot is None else dq_dpdot.ravel())
        total = np.bincount(self.flow_to, weights=np.concatenate(flows), minlength=self.size)
        res = total[:m * k].reshape(m, k)
        out = total[m * k:m * (k + nb)].reshape(m, nb)
        if not jacobian:
            return res, out
        return res, out, self._blocks_of(by_p), self._blocks_of(by_pdot)

    def evaluate_stages(self, times, Y, Yd):
        """As :meth:`CellBatch.evaluate_stages` for the cells ``rows``."""
        batch = self.batch
        m, k, nb = self.rows.size, batch.k, batch.nb
        P, Pdot = self._inputs.fill_stages(batch, self._stage_buffers, self._stage_idx, times,
                                           Y, Yd)
        # the hub (a batch of one) may hold elements that depend on time; cells do not
        time = np.array([t[0] for t in times]) if batch.G == 1 else _NO_TIMES
        flows = [family.flows(time, np.take(P, nodes, axis=1),
                              np.take(Pdot, nodes, axis=1)).ravel()
                 for family, nodes in self.blocks]  # (np.take: 4× faster than P[:, nodes])
        total = np.bincount(self._flow_to_stages, weights=np.concatenate(flows),
                            minlength=3 * self.size).reshape(3, self.size)
        return total[:, :m * k].reshape(3, m, k), total[:, m * k:m * (k + nb)].reshape(3, m, nb)

    def rates(self, t, Y, Yd_guess):
        return consistent_rates(self, t, Y, Yd_guess)

    def _blocks_of(self, partials):
        m, k = self.rows.size, self.batch.k
        return np.bincount(self.partial_to, weights=np.concatenate(partials),
                           minlength=m * k * k + 1)[:m * k * k].reshape(m, k, k)


_NO_TIMES = np.full(3, np.nan)  # cells' elements do not depend on time


def _placeholder(name, node, ambient):
    from ..physics.elements.base import ElementSpec

    return ElementSpec("pressure_source", name, (node,), {"value": Constant(ambient)})
