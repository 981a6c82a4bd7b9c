"""The fold indicator's algebraic block equals the full Jacobian's algebraic part."""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.engine.assembly import AlgebraicBlock, CircuitDAE
from pneunet.physics.valve_params import PAPER_VALVES


def _ladder(cells=6):
    """Valves in series with leaks to the atmosphere, volumes on every other node:
    algebraic and differential nodes side by side, instances on both kinds."""
    c = Circuit("ladder", ambient=96.0)
    c.pressure_source("PS", "n0", 496.0)
    for k in range(cells):
        c.valve(f"X{k}", f"n{k}", f"n{k + 1}", f"n{max(k - 1, 0)}", PAPER_VALVES["axi"])
        c.resistor(f"Rl{k}", f"n{k + 1}", "atm", 3.0 + k)
        if k % 2:
            c.volume(f"V{k}", f"n{k + 1}", 5.0)
    return c


@pytest.mark.parametrize("dense_limit, floats", [(40, True), (40, False), (0, False)])
def test_algebraic_block_matches_the_full_jacobian(dense_limit, floats):
    """Dense on floats (six valves), dense on arrays (the route of larger circuits) and
    sparse, each against the full Jacobian's algebraic rows and columns."""
    dae = CircuitDAE(_ladder())
    alg = dae.algebraic_idx
    assert 1 < alg.size < dae.n
    y = np.random.default_rng(1).uniform(150.0, 450.0, dae.n)
    res, data = dae.evaluate(0.0, y, np.zeros(dae.n), cj=0.0)
    full = dae.dense(data)
    block = AlgebraicBlock(dae, dense_limit=dense_limit)
    assert (block.floats is not None) == (dense_limit > 0)
    if not floats:
        block.floats = None
    res_a, jac, scale_a = block.evaluate(0.0, y)
    jac = jac if isinstance(jac, np.ndarray) else jac.toarray()
    np.testing.assert_allclose(res_a, res[alg], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(jac, full[np.ix_(alg, alg)], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(scale_a, _row_scale(dae, y), rtol=1e-13)
    assert block.evaluate(0.0, y, residual=False)[0] is None


def _row_scale(dae, y):
    """Σ|∂q/∂p| over every element port at an algebraic node and every port of the
    same element at an algebraic node: the scale of each algebraic equation."""
    local = np.full(dae.n + len(dae.fixed_names), -1)
    local[dae.algebraic_idx] = np.arange(dae.algebraic_idx.size)
    p = dae.full_pressures(0.0, y)
    scale = np.zeros(dae.algebraic_idx.size)
    for block in dae._blocks:
        at = local[block.port_node]
        _, dq_dp, _ = block.family.outflows(0.0, p[block.port_node], np.zeros(at.shape))
        for e, i, j in np.argwhere((at[:, :, None] >= 0) & (at[:, None, :] >= 0)):
            scale[at[e, i]] += abs(dq_dp[e, i, j])
    return scale
