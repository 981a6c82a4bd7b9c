"""Assemble a circuit into the DAE F(t, y, ẏ) = 0 with a sparse analytic Jacobian.

Unknowns y are the pressures of all nodes whose pressure no source or reference
imposes.  The residual of node i is the sum, over the element ports at that
node, of the mass flow leaving the node into the element (mg/s):

    F_i = Σ q_port                     (zero: conservation of mass)

A node with a storage port (a volume) is *differential*; the others are
*algebraic* (index-1 DAE).  Element families are evaluated for all their
instances at once; their partials are scattered into a CSC matrix through
index arrays computed once, so each Jacobian costs a few numpy calls.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics import elements
from ..physics.elements.base import ElementSpec, FamilyContext
from .float_plan import FloatAlgebraicBlock, FloatPlan, on_floats
from .solvers.newton import DENSE_LIMIT


def _cat(arrays) -> np.ndarray:
    """Integer arrays joined end to end (empty for none)."""
    return np.concatenate([np.empty(0, int), *arrays])


@dataclass
class _FamilyBlock:
    family: elements.ElementFamily
    port_node: np.ndarray      # (n, P) global node index of each port
    jac_pos: np.ndarray        # CSC data position of each free (i, j) port pair, flattened
    jac_flat: np.ndarray       # flat (n·P·P) index of each port pair that is both free
    free_flat: np.ndarray      # flat (n·P) index of each port at an unknown node
    free_nodes: np.ndarray     # the unknown's index at each of those ports
    flows: slice = None        # this family's port flows in the evaluation buffer
    partials: slice = None     # its port-pair partials in the partials buffer


class CircuitDAE:
    """The residual, Jacobian and bookkeeping of one circuit (immutable once built)."""

    def __init__(self, circuit, validate: bool = True):
        from ..common.gcpause import collector_paused

        if validate:  # a part of a validated circuit (a multirate cell) may not stand alone
            circuit.validate()
        with collector_paused():
            self._assemble(circuit)

    def _assemble(self, circuit) -> None:
        self.circuit = circuit
        self.options = circuit.options
        self._corners = {}  # (t_start, t_stop) → instance_corners
        context = FamilyContext(circuit.options)
        specs = list(circuit.elements.values())
        pinned_by = {}
        storage_nodes = set()
        self.state_nodes = set()  # elements' own states (state_ports): no pressures
        for spec in specs:
            fam = elements.family(spec.kind)
            pinned_by.update({spec.nodes[p]: spec.name for p in fam.pinned_ports})
            storage_nodes.update(spec.nodes[p] for p in fam.storage_ports)
            self.state_nodes.update(spec.nodes[p] for p in fam.state_ports)
        nodes = circuit.nodes
        references = [n for n in nodes if circuit.is_reference(n)]
        fixed = set(pinned_by) | set(references)
        self.node_names = [n for n in nodes if n not in fixed]
        self.fixed_names = [n for n in nodes if n in fixed]
        if self.options.dead_volume > 0:
            specs += [ElementSpec("volume", f"_dead_{n}", (n,),
                                  {"V": self.options.dead_volume, "n": 1.0, "p0": np.nan})
                      for n in self.node_names
                      if n not in storage_nodes and n not in self.state_nodes]
            storage_nodes.update(n for n in self.node_names if n not in self.state_nodes)
        self.n = len(self.node_names)
        index = {name: i for i, name in enumerate(self.node_names + self.fixed_names)}
        self._index = index
        self.differential = np.array([n in storage_nodes for n in self.node_names], dtype=bool)
        self.algebraic_idx = np.flatnonzero(~self.differential)
        self._reference_idx = np.array([index[n] for n in references], dtype=int)

        grouped: dict[type, list[ElementSpec]] = {}
        for spec in specs:
            grouped.setdefault(elements.family(spec.kind), []).append(spec)
        self.families = [cls(group, context) for cls, group in grouped.items()]
        self._build_pattern()

    # -- structure ------------------------------------------------------------------
    def _build_pattern(self) -> None:
        rows, cols, owners = [], [], []
        blocks = []
        for fam in self.families:
            port_node = np.array([[self._index[n] for n in s.nodes] for s in fam.specs], dtype=int)
            free = port_node < self.n
            mask = free[:, :, None] & free[:, None, :]
            r = np.broadcast_to(port_node[:, :, None], mask.shape)[mask]
            c = np.broadcast_to(port_node[:, None, :], mask.shape)[mask]
            rows.append(r)
            cols.append(c)
            owners.append(len(r))
            free_flat = np.flatnonzero(free.ravel())
            blocks.append(_FamilyBlock(fam, port_node, None,  # jac_pos: set below
                                       np.flatnonzero(mask.ravel()), free_flat,
                                       port_node.ravel()[free_flat]))
        rows = _cat(rows)
        cols = _cat(cols)
        # every unknown gets a diagonal entry, so the pattern is structurally regular
        diag = np.arange(self.n)
        keys = np.unique(np.concatenate([cols * self.n + rows, diag * self.n + diag]))
        self._csc_indices = (keys % self.n).astype(np.int32)
        # keys are sorted by column: column j starts at the first key ≥ j·n
        self._csc_indptr = np.searchsorted(keys, np.arange(self.n + 1) * self.n).astype(np.int32)
        self.nnz = len(keys)
        self._diagonal_at = np.searchsorted(keys, diag * self.n + diag)  # CSC data positions
        pos = np.searchsorted(keys, cols * self.n + rows)
        start = 0
        for block, count in zip(blocks, owners):
            block.jac_pos = pos[start:start + count]
            start += count
        self._blocks = blocks
        self._pinned = [(b.family, b.port_node[:, list(b.family.pinned_ports)])
                        for b in blocks if b.family.pinned_ports]
        # every port flow and port-pair partial of every family goes to one buffer; one
        # bincount sums them per node / per CSC entry, cut at n / nnz: the bins of fixed
        # nodes (index ≥ n) and of pairs with a fixed port (index nnz) are dropped.  Every
        # unknown and every stored entry (the diagonal too) gets a term, so the bincounts
        # are never shorter than the cut
        flow_to, partial_to = [], []
        for block in blocks:
            flow_to.append(block.port_node.ravel())
            pair = np.full(block.port_node.size * block.port_node.shape[1], self.nnz)
            pair[block.jac_flat] = block.jac_pos
            partial_to.append(pair)
            block.flows = slice(sum(map(len, flow_to[:-1])), sum(map(len, flow_to)))
            block.partials = slice(sum(map(len, partial_to[:-1])), sum(map(len, partial_to)))
        self._flow_to = _cat(flow_to)
        self._partial_to = _cat(partial_to)
        self._flow_buffer = np.zeros(self._flow_to.size)
        self._partial_buffer = np.zeros(self._partial_to.size)
        # families with no port at an unknown node (pressure sources) add nothing
        self._active = [b for b in blocks if b.free_flat.size]
        self._floats = FloatPlan(self) if on_floats(b.family for b in self._active) else None
        # pressures and rates of all nodes at one time, refilled in place
        self._p = np.empty(self.n + len(self.fixed_names))
        self._p[self._reference_idx] = self.options.ambient
        self._pdot = np.zeros_like(self._p)
        self._pinned_at = None  # time of the pinned pressures now in self._p
        cols = np.repeat(np.arange(self.n), np.diff(self._csc_indptr))
        self._dense_at = (self._csc_indices.astype(np.intp), cols)

    def sparsity(self):
        """The Jacobian's sparsity pattern as a scipy CSC matrix of ones."""
        from scipy.sparse import csc_matrix

        return csc_matrix((np.ones(self.nnz), self._csc_indices, self._csc_indptr),
                          shape=(self.n, self.n))

    def entries(self):
        """(row, column) of every stored Jacobian entry, in CSC data order."""
        cols = np.repeat(np.arange(self.n), np.diff(self._csc_indptr))
        return self._csc_indices.astype(int), cols

    def csc(self, data):
        """A CSC matrix with this pattern and the given data."""
        from scipy.sparse import csc_matrix

        return csc_matrix((data, self._csc_indices, self._csc_indptr), shape=(self.n, self.n))

    # -- evaluation -----------------------------------------------------------------
    def full_pressures(self, t, y: np.ndarray) -> np.ndarray:
        """Pressures of all nodes (unknowns first, then fixed ones), kPa.

        ``t`` a float and ``y`` (n,), or ``t`` (n_t,) and ``y`` (n_t, n) for a
        whole history at once.
        """
        full = np.empty(np.shape(y)[:-1] + (self.n + len(self.fixed_names),))
        full[..., :self.n] = y
        full[..., self._reference_idx] = self.options.ambient
        for family, nodes in self._pinned:
            full[..., nodes] = family.pinned_pressure(t)
        return full

    def _pressures_at(self, t, y, ydot=None):
        """The shared pressure and rate buffers of all nodes at one time (kPa, kPa/s);
        without ``ydot`` the rate buffer is left as it is."""
        p = self._p
        p[:self.n] = y
        if t != self._pinned_at:
            for family, nodes in self._pinned:
                p[nodes] = family.pinned_pressure(t)
            self._pinned_at = t
        if ydot is not None:
            self._pdot[:self.n] = ydot
        return p, self._pdot

    def evaluate(self, t, y, ydot, cj=None):
        """Residual F(t, y, ẏ); with ``cj`` also the CSC data of ∂F/∂y + cj·∂F/∂ẏ.

        Contributions of all families are summed by one bincount each (on Python
        floats for a small circuit: :mod:`~pneunet.engine.float_plan`).
        """
        if self._floats is not None:
            return self._floats.evaluate(t, y, ydot, cj)
        p, pdot = self._pressures_at(t, y, ydot)
        flows, partials = self._flow_buffer, self._partial_buffer
        for block in self._active:
            nodes = block.port_node
            if cj is None:
                q = block.family.flows(t, p[nodes], pdot[nodes])
            else:
                q, dq_dp, dq_dpdot = block.family.outflows(t, p[nodes], pdot[nodes])
                partials[block.partials] = (dq_dp if dq_dpdot is None
                                            else dq_dp + cj * dq_dpdot).ravel()
            flows[block.flows] = q.ravel()
        res = np.bincount(self._flow_to, weights=flows)[:self.n]
        if cj is None:
            return res, None
        return res, np.bincount(self._partial_to, weights=partials)[:self.nnz]

    def algebraic_block(self) -> "AlgebraicBlock":
        """F_a and ∂F_a/∂y_a with ẏ = 0, from only the elements at algebraic nodes."""
        return AlgebraicBlock(self)

    def dense(self, data, out=None) -> np.ndarray:
        """The Jacobian with CSC ``data`` as a dense (n, n) array (written into ``out``)."""
        if out is None:
            out = np.zeros((self.n, self.n))
        else:
            out[:, :] = 0.0
        out[self._dense_at] = data
        return out

    def jacobian(self, t, y, ydot, cj=0.0):
        """∂F/∂y + cj·∂F/∂ẏ as a scipy CSC matrix."""
        return self.csc(self.evaluate(t, y, ydot, cj)[1])

    def _mass_data(self, t, y, ydot=None):
        """F(t, y, ẏ) and the CSC data of ∂F/∂ẏ there (ẏ = 0 if not given; mg/s, mg/kPa)."""
        ydot = np.zeros(self.n) if ydot is None else ydot
        f, stiff = self.evaluate(t, y, ydot, cj=0.0)
        stiff = stiff.copy()
        return f, self.evaluate(t, y, ydot, cj=1.0)[1] - stiff

    def mass_matrix(self, t, y):
        """∂F/∂ẏ at (t, y) as a CSC matrix, mg/kPa."""
        return self.csc(self._mass_data(t, y)[1])

    def capacitance(self, t, y) -> np.ndarray:
        """The diagonal of ∂F/∂ẏ: the capacitance (mg/kPa) at each unknown node."""
        return self._mass_data(t, y)[1][self._diagonal_at]

    def derivative(self, t, y) -> np.ndarray:
        """ẏ consistent with y: F_d(t, y, ẏ) = 0, ẏ_a = 0 (kPa/s), by three steps of Newton's
        method on ẏ_d (ẏ ← ẏ − M_dd⁻¹·F_d): exact after one where F is linear in ẏ, after
        two where it is piecewise linear (a thermal volume: its gas enters at the wall
        temperature and leaves at its own); a step that moves no rate by more than 1e-12
        of the largest ends them.  A later step is first taken with the mass matrix M of
        the step before (M does not depend on ẏ where F is linear in it, so the same
        step); only where that step is not negligible is M evaluated again (two residual
        and Jacobian evaluations a step: a fold's approach asks for ẏ at every step)."""
        d = np.flatnonzero(self.differential)
        ydot = np.zeros(self.n)
        if not d.size:
            return ydot
        f, mass = self._mass_data(t, y, ydot)
        for i in range(3):
            if i:
                f = self.evaluate(t, y, ydot)[0]
                step = self._solve_mass(mass, f, d)
                if np.abs(step).max() <= 1e-12 * np.abs(ydot[d] - step).max():
                    ydot[d] -= step
                    break
                f, mass = self._mass_data(t, y, ydot)
            step = self._solve_mass(mass, f, d)
            ydot[d] -= step
            if i and np.abs(step).max() <= 1e-12 * np.abs(ydot[d]).max():
                break
        return ydot

    def _solve_mass(self, mass, f, d) -> np.ndarray:
        """x with M_dd·x = f_d, M the CSC data ``mass`` of ∂F/∂ẏ (kPa/s)."""
        diagonal = mass[self._diagonal_at]
        if np.count_nonzero(mass) == np.count_nonzero(diagonal):  # M diagonal: divide
            return f[d] / diagonal[d]
        if self.n <= DENSE_LIMIT:  # LAPACK: scipy.sparse's slicing costs ~1 ms a call
            return np.linalg.solve(self.dense(mass)[np.ix_(d, d)], f[d])
        from scipy.sparse.linalg import spsolve

        return spsolve(self.csc(mass)[d][:, d].tocsc(), f[d])

    # -- breakpoints and reporting --------------------------------------------------------
    def jumps(self, t_start, t_stop) -> np.ndarray:
        return distinct_times([b.family.jumps(t_start, t_stop) for b in self._blocks])

    def breakpoints(self, t_start, t_stop) -> np.ndarray:
        return distinct_times([b.family.breakpoints(t_start, t_stop) for b in self._blocks])

    def instance_corners(self, t_start, t_stop) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """{element name: (its input's corners, the jumps among them)} in (t_start, t_stop)
        for every element with time-varying inputs, s."""
        key = (float(t_start), float(t_stop))
        if key not in self._corners:  # asked for by the method's choice and by the method
            out = self._corners[key] = {}
            for block in self._blocks:
                corners = block.family.instance_corners(t_start, t_stop)
                if corners:
                    out.update(zip(block.family.names, corners))
        return self._corners[key]

    def initial_state(self, t0: float) -> np.ndarray:
        """Initial guess: ``.ic`` values, then volumes' p0, then ambient pressure (kPa)."""
        y = np.full(self.n, self.options.ambient)
        for block in self._blocks:
            p0 = block.family.initial_pressure()  # (n,), or (n, storage ports)
            for k, port in enumerate(block.family.storage_ports):
                nodes = block.port_node[:, port]
                start = p0[:, k] if p0.ndim == 2 else p0
                ok = (nodes < self.n) & ~np.isnan(start)
                y[nodes[ok]] = start[ok]
        for name, value in self.circuit.initial.items():
            if name in self._index and self._index[name] < self.n:
                y[self._index[name]] = value
        return y

    def source_flows(self, times: np.ndarray, full_p: np.ndarray) -> dict[str, np.ndarray]:
        """Mass flow each pressure source delivers over time, {name: (n_t,)}, mg/s.

        It is the net flow from the source's node into all other elements, from
        the pressures alone (rates of change taken as zero).
        """
        from scipy.sparse import csr_matrix

        sources = self.pinned_sources()
        columns = {node: k for k, node in enumerate(dict.fromkeys(sources.values()))}
        node_cols = np.full(len(self._index), -1)
        for node, k in columns.items():
            node_cols[self._index[node]] = k
        total = np.zeros((len(times), len(columns)))
        for block in self._blocks:
            col = node_cols[block.port_node].ravel()
            hit = np.flatnonzero(col >= 0)
            if not hit.size:
                continue
            p = full_p[:, block.port_node]
            q = block.family.flows(times, p, np.broadcast_to(0.0, p.shape)).reshape(len(times), -1)
            gather = csr_matrix((np.ones(hit.size), (np.arange(hit.size), col[hit])),
                                shape=(hit.size, len(columns)))
            total += (gather.T @ q[:, hit].T).T
        return {name: total[:, columns[node]] for name, node in sources.items()}

    def element_signals(self, block, t: np.ndarray, full_p: np.ndarray) -> dict[str, tuple[str, np.ndarray]]:
        """One family's per-element signals over time: {'mdot_Rout': ('mg/s', array)}."""
        fam = block.family
        out = {}
        for suffix, (unit, values) in fam.signals(t, full_p[:, block.port_node]).items():
            values = np.asarray(values, dtype=float)
            values.setflags(write=False)  # the solution keeps read-only views uncopied
            undefined = fam.undefined_signals(suffix)
            for k, name in enumerate(fam.names):
                if not name.startswith("_dead_") and k not in undefined:
                    out[f"{suffix}_{name}"] = (unit, values[:, k])
        return out

    def element_signal_groups(self, t: np.ndarray, states: np.ndarray, history):
        """Per family: (signal names, units, function computing {name: array}).

        ``history()`` returns the full pressure history (:meth:`full_pressures`);
        names and units come from the family's signals at the first time point.
        """
        first = self.full_pressures(t[:1], states[:1])
        groups = []
        for block in self._blocks:
            probe = self.element_signals(block, t[:1], first)
            if not probe:
                continue

            def compute(block=block):
                return {k: v for k, (_, v) in self.element_signals(block, t, history()).items()}
            groups.append((list(probe), [unit for unit, _ in probe.values()], compute))
        return groups

    def pinned_sources(self) -> dict[str, str]:
        """{source element name: node} for the elements that pin a pressure."""
        out = {}
        for block in self._blocks:
            for k, name in enumerate(block.family.names):
                for port in block.family.pinned_ports:
                    out[name] = block.family.specs[k].nodes[port]
        return out

    def node_index(self, name: str) -> int:
        return self._index[name]

    @property
    def stored_pressure_nodes(self) -> list[str]:
        """Nodes whose pressure is a stored state (a volume at them), elements' own
        states left out."""
        return [n for n, d in zip(self.node_names, self.differential)
                if d and n not in self.state_nodes]


class AlgebraicBlock:
    """The algebraic equations F_a(y) (ẏ = 0) and their block J_aa = ∂F_a/∂y_a.

    Only the element instances with a port at an algebraic node are evaluated
    (each family restricted to them once, here), and only the flows into and
    partials between algebraic nodes are summed: the fold indicator and the
    branch jump need nothing else.  J_aa is dense (na, na) up to ``dense_limit``
    unknowns, else CSC with a pattern fixed here.
    """

    def __init__(self, dae, dense_limit: int = 40):
        self.dae = dae
        alg = dae.algebraic_idx
        self.size = na = alg.size
        self.dense = na <= dense_limit
        local = np.full(dae.n + len(dae.fixed_names), -1)
        local[alg] = np.arange(na)
        self._parts, flow_to, pair_to = [], [], []
        n_flows = n_pairs = 0
        for block in dae._active:
            on = local[block.port_node] >= 0
            members = np.flatnonzero(on.any(axis=1))
            if not members.size:
                continue
            fam = block.family  # the same family over those instances only
            fam = type(fam)([fam.specs[k] for k in members], fam.context)
            at, on = local[block.port_node[members]], on[members]
            pairs = on[:, :, None] & on[:, None, :]
            flow_at, pair_at = np.flatnonzero(on.ravel()), np.flatnonzero(pairs.ravel())
            flows_end, pairs_end = n_flows + flow_at.size, n_pairs + pair_at.size
            self._parts.append((fam, block.port_node[members], flow_at, pair_at,
                                np.zeros(block.port_node[members].shape),
                                slice(n_flows, flows_end), slice(n_pairs, pairs_end)))
            n_flows, n_pairs = flows_end, pairs_end
            flow_to.append(at[on])
            pair_to.append((np.broadcast_to(at[:, :, None], pairs.shape)[pairs],
                            np.broadcast_to(at[:, None, :], pairs.shape)[pairs]))
        self._flows, self._partials = np.zeros(n_flows), np.zeros(n_pairs)
        self._flow_to = _cat(flow_to)
        rows = _cat(r for r, _ in pair_to)
        cols = _cat(c for _, c in pair_to)
        self._rows = rows
        keys, self._pair_to = np.unique(cols * na + rows, return_inverse=True)
        self.floats = None  # the block on Python floats (small circuits), if it has one
        if self.dense:
            self._pair_to = rows * na + cols  # row-major position in the dense block
            if on_floats(part[0] for part in self._parts):
                self.floats = FloatAlgebraicBlock(dae, [
                    (fam, nodes, list(zip(flow_at.tolist(), to.tolist())),
                     list(zip(pair_at.tolist(), (r * na + c).tolist(), r.tolist())))
                    for (fam, nodes, flow_at, pair_at, *_), to, (r, c)
                    in zip(self._parts, flow_to, pair_to)], na)
        else:
            from scipy.sparse import csc_matrix

            # duplicate (row, column) pairs summed: one stored entry per key, in key order
            self._matrix = csc_matrix((np.ones(rows.size), (rows, cols)), shape=(na, na))
            self._matrix.sort_indices()

    def evaluate(self, t, y, residual=True):
        """(F_a or None, J_aa, s_a): s_a the row scale Σ|contribution| of each algebraic
        equation over its algebraic columns (mg/(s·kPa)), floored at 1e-300."""
        if self.floats is not None:
            return self.floats.evaluate(t, y, residual)
        p, _ = self.dae._pressures_at(t, y)
        flows, partials = self._flows, self._partials
        for fam, nodes, flow_at, pair_at, zeros, flow_slice, pair_slice in self._parts:
            q, dq_dp, _ = fam.outflows(t, p[nodes], zeros)
            if residual:
                flows[flow_slice] = q.ravel()[flow_at]
            partials[pair_slice] = dq_dp.ravel()[pair_at]
        res = np.bincount(self._flow_to, weights=flows, minlength=self.size) if residual else None
        data = np.bincount(self._pair_to, weights=partials)  # each entry's last bin is hit
        scale = np.bincount(self._rows, weights=np.abs(partials), minlength=self.size)
        if self.dense:
            jac = data.reshape(self.size, self.size)
        else:
            jac = self._matrix.copy()
            jac.data = data
        return res, jac, np.maximum(scale, 1e-300)


def distinct_times(times: list[np.ndarray]) -> np.ndarray:
    """Sorted times (s) with those equal up to rounding (1e-12 relative) merged: sources
    whose corners coincide in exact arithmetic (16 + 0.01 and 2·8 + 0.01) give one stop."""
    t = np.unique(np.concatenate([np.empty(0), *times]))
    keep = np.diff(t) > 1e-12 * np.maximum(np.abs(t[1:]), 1.0)
    return np.concatenate([t[:1], t[1:][keep]])
