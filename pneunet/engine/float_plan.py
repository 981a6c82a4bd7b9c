"""Small circuits evaluated on Python floats: the residual and Jacobian of
:class:`~pneunet.engine.assembly.CircuitDAE` and its algebraic block, when every family
evaluated has ``float_outflows`` (a few instances each: valves, resistors, volumes,
thermal volumes, chambers and inlets).

On a circuit of a few elements numpy's per-call overhead is most of the cost (the
oscillator: ~14 µs per residual, of which its laws take ~2 µs), and IDA asks for a
residual, a Jacobian or the fold indicator several times per step.  Here each family's
laws run on Python floats and their flows and partials are summed in the order of the
vectorised path's bincounts over the same buffers: the same operations on the same
values, so the same bits (tests/core/test_float_plan.py; a polytropic volume's power
within a few ulps: numpy's on an array runs SIMD code on some processors).
"""
from __future__ import annotations

import numpy as np


def on_floats(families) -> bool:
    """Whether all these families can be evaluated on Python floats."""
    return all(fam.on_floats for fam in families)


class FloatPlan:
    """F(t, y, ẏ) and the CSC data of ∂F/∂y + cj·∂F/∂ẏ on floats, as ``dae.evaluate``."""

    def __init__(self, dae):
        self.dae = dae
        self._parts = []
        for block in dae._active:
            free = block.port_node.ravel() < dae.n
            flow_to = list(zip(np.flatnonzero(free).tolist(),
                               block.port_node.ravel()[free].tolist()))
            pair_to = list(zip(block.jac_flat.tolist(), block.jac_pos.tolist()))
            self._parts.append((block.family, block.port_node.tolist(), flow_to, pair_to))

    def evaluate(self, t, y, ydot, cj):
        p, pdot = self.dae._pressures_at(t, y, ydot)
        p, pdot = p.tolist(), pdot.tolist()
        res = [0.0] * self.dae.n
        data = None if cj is None else [0.0] * self.dae.nnz
        for family, rows, flow_to, pair_to in self._parts:
            q, dq_dp, dq_dpdot = family.float_outflows(t, p, pdot, rows, cj is not None)
            for k, node in flow_to:
                res[node] += q[k]
            if data is None:
                continue
            if dq_dpdot is None:
                for k, pos in pair_to:
                    data[pos] += dq_dp[k]
            else:
                for k, pos in pair_to:
                    data[pos] += dq_dp[k] + cj * dq_dpdot[k]
        return np.array(res), None if data is None else np.array(data)


class FloatAlgebraicBlock:
    """F_a, the dense J_aa and the row scale s_a on floats, as
    :meth:`~pneunet.engine.assembly.AlgebraicBlock.evaluate`."""

    def __init__(self, dae, parts, size):
        """``parts``: per family (family, port nodes, flat flow index → algebraic row,
        flat pair index → (dense position, row)) in the block's buffer order."""
        self.dae, self.size = dae, size
        self._parts = [(fam, nodes.tolist(), flows, pairs) for fam, nodes, flows, pairs in parts]
        self._zeros = [0.0] * len(dae._pdot)  # ẏ = 0 at every node

    def evaluate(self, t, y, residual):
        res, data, scale = self.lists(t, y, residual)
        return (np.array(res) if residual else None, np.array(data).reshape(self.size, self.size),
                np.array(scale))

    def lists(self, t, y, residual=True):
        """(F_a or None, J_aa row-major, s_a floored at 1e-300) as lists of floats."""
        p = self.dae._pressures_at(t, y)[0].tolist()
        na = self.size
        res, data, scale = [0.0] * na, [0.0] * (na * na), [0.0] * na
        for fam, rows, flow_to, pair_to in self._parts:
            q, dq_dp, _ = fam.float_outflows(t, p, self._zeros, rows, True)
            if residual:
                for k, row in flow_to:
                    res[row] += q[k]
            for k, pos, row in pair_to:
                d = dq_dp[k]
                data[pos] += d
                scale[row] += abs(d)
        return res if residual else None, data, [max(s, 1e-300) for s in scale]
