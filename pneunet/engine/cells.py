"""Many cells of one structure as one array problem, each cell at its own time.

:class:`CellBatch` assembles the cells of a group (see :mod:`~pneunet.engine.partition`)
into one :class:`~pneunet.engine.assembly.CircuitDAE` whose Jacobian is block
diagonal, one (k, k) block per cell.  Every cell has private copies of the pinned
nodes it touches and of the hub nodes (*boundary* nodes, their pressures given by
the driver), so that a cell's sources and boundary can be evaluated at that cell's
own time.  The hub itself is a batch of one cell with the cells' flows injected.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import ParameterError
from ..waveforms import Constant
from .assembly import CircuitDAE
from .circuit import Circuit
from .partition import time_dependent


class CellBatch:
    """Residuals and Newton blocks of G cells with k unknowns each (kPa, mg/s).

    ``boundary(t) -> (G, nb)`` gives the pressures of each cell's boundary nodes at
    the cells' times t (G,); ``injection(t, Y) -> (flows, slopes)`` adds flows (G, k)
    (mg/s) leaving each unknown node (the hub's cells) and their derivatives by the
    node's own pressure (G, k), mg/(s·kPa).  Either may be None.
    """

    def __init__(self, circuit, cells, hub_nodes=(), title="cells"):
        sub = Circuit(title, circuit.options)
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
        self.injection = None
        self._build_maps(cells)

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
        self._flow_to = np.concatenate([b.port_node.ravel() for b in dae._blocks]) \
            if dae._blocks else np.empty(0, int)
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
        self._data = np.zeros(dae.nnz + 1)
        self.differential = dae.differential[self.idx[0]]

    def _pressures(self, t, Y, Yd):
        dae = self.dae
        p, pdot = dae._p, dae._pdot
        p[self.idx] = Y
        pdot[self.idx] = Yd
        for family, nodes, cell in self._pinned:
            p[nodes] = family.pinned_pressure_each(t[cell])
        if self.nb:
            p[self._boundary_idx] = self.boundary(t)
        dae._pinned_at = None  # the shared buffer no longer holds one time's pressures
        return p, pdot

    def evaluate(self, t, Y, Yd, jacobian=False):
        """R (G, k) and the boundary outflows (G, nb), mg/s; with ``jacobian`` also the
        blocks ∂F/∂y and ∂F/∂ẏ (G, k, k).  ``t`` (G,): each cell's time (s)."""
        dae = self.dae
        p, pdot = self._pressures(t, Y, Yd)
        flows, by_p = dae._flow_buffer, dae._partial_buffer
        if jacobian:
            by_pdot = np.zeros_like(by_p)
        t_scalar = float(t[0]) if self.G == 1 else np.nan
        for block in dae._active:
            nodes = block.port_node
            if not jacobian:
                q = block.family.flows(t_scalar, p[nodes], pdot[nodes])
            else:
                q, dq_dp, dq_dpdot = block.family.outflows(t_scalar, p[nodes], pdot[nodes])
                by_p[block.partials] = dq_dp.ravel()
                if dq_dpdot is not None:
                    by_pdot[block.partials] = dq_dpdot.ravel()
            flows[block.flows] = q.ravel()
        total = np.bincount(self._flow_to, weights=flows, minlength=self._n_all)
        res = total[self.idx]
        slopes = None
        if self.injection is not None:
            flows, slopes = self.injection(t, Y)
            res = res + flows
        out = total[self._boundary_idx]
        if not jacobian:
            return res, out
        jac = self._blocks_of(by_p)
        if slopes is not None:
            jac[:, np.arange(self.k), np.arange(self.k)] += slopes
        return res, out, jac, self._blocks_of(by_pdot)

    def _blocks_of(self, partials):
        nnz = self.dae.nnz
        self._data[:-1] = np.bincount(self.dae._partial_to, weights=partials,
                                      minlength=nnz + 1)[:nnz]
        return self._data[self._pos]

    def rates(self, t, Y, Yd_guess):
        """ẏ consistent with Y at times t: the mass blocks solved for −F(ẏ = guess)."""
        res, _, _, mass = self.evaluate(t, Y, Yd_guess, jacobian=True)
        d = self.differential
        out = Yd_guess.copy()
        sub = mass[:, d][:, :, d]
        out[:, d] = Yd_guess[:, d] - np.linalg.solve(sub, res[:, d, None])[..., 0]
        return out


def _placeholder(name, node, ambient):
    from ..elements.base import ElementSpec

    return ElementSpec("pressure_source", name, (node,), {"value": Constant(ambient)})
