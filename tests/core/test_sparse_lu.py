"""Direct solves of the Newton matrix: bordered band and SuperLU agree with dense LU."""
import numpy as np
import pytest
import scipy.sparse as sp

from pneunet.engine.solvers.sparse_lu import BorderedBand, SuperLU, sparse_lu


def _chains_with_border(chains=20, length=6, border=3, seed=0):
    """Independent tridiagonal chains plus a few unknowns coupled to every chain node
    (a demultiplexer's cells and control lines), in a scrambled order."""
    rng = np.random.default_rng(seed)
    m = chains * length
    n = m + border
    dense = np.zeros((n, n))
    for c in range(chains):
        for i in range(c * length, (c + 1) * length):
            dense[i, i] = 4.0 + rng.random()
            if i + 1 < (c + 1) * length:
                dense[i, i + 1], dense[i + 1, i] = -rng.random(), -rng.random()
    dense[:m, m:] = rng.normal(size=(m, border)) * (rng.random((m, border)) < 0.7)
    dense[m:, m:] = np.diag(3.0 + rng.random(border))
    scramble = rng.permutation(n)
    return dense[np.ix_(scramble, scramble)]


def _check(solver, dense, seed=1):
    pattern = sp.csc_matrix(dense)
    lu = solver.factor(pattern.data.copy())
    b = np.random.default_rng(seed).normal(size=dense.shape[0])
    np.testing.assert_allclose(lu.solve(b), np.linalg.solve(dense, b), rtol=1e-10, atol=1e-12)


def test_bordered_band_is_chosen_for_chains_and_solves_exactly():
    dense = _chains_with_border()
    solver = sparse_lu(sp.csc_matrix(dense))
    assert isinstance(solver, BorderedBand)
    assert (solver.k, solver.kl, solver.ku) == (3, 1, 1)
    _check(solver, dense)
    dense[5, 5] *= 2.0  # new values, same pattern
    _check(solver, dense, seed=2)


def test_a_plain_band_needs_no_border():
    dense = _chains_with_border(border=0)
    solver = sparse_lu(sp.csc_matrix(dense))
    assert isinstance(solver, BorderedBand) and solver.k == 0
    _check(solver, dense)


def test_a_scattered_pattern_goes_to_superlu():
    rng = np.random.default_rng(3)
    n = 300
    dense = sp.random(n, n, density=0.05, random_state=4).toarray() + np.diag(5 + rng.random(n))
    solver = sparse_lu(sp.csc_matrix(dense))
    assert isinstance(solver, SuperLU)
    _check(solver, dense)


def test_a_singular_band_falls_back_to_superlu():
    dense = _chains_with_border()
    solver = sparse_lu(sp.csc_matrix(dense))
    data = sp.csc_matrix(dense).data.copy()
    first_chain = np.zeros(dense.shape[0], bool)
    first_chain[solver.order[:6]] = True
    pattern = sp.csc_matrix(dense)
    rows = pattern.indices
    cols = np.repeat(np.arange(dense.shape[0]), np.diff(pattern.indptr))
    data[first_chain[rows] & first_chain[cols]] = 0.0  # one chain's block vanishes
    with pytest.raises(RuntimeError, match="singular"):
        solver.factor(data)


def test_sparse_path_of_a_transient_matches_the_dense_one(monkeypatch):
    """demux3 (27 unknowns) through the sparse path (bordered band, then SuperLU, then
    with the LU refreshed at every step's Newton iteration instead of when IDA asks)
    gives the dense path's pressures up to the integration tolerance."""
    from pathlib import Path

    from pneunet.engine.simulate import transient
    from pneunet.engine.solvers import sparse_lu as module, sundae
    from pneunet.netlist import parse_file

    circuit = parse_file(Path(__file__).resolve().parents[2] / "netlists/demux3.pn").circuit
    dense = transient(circuit, 8.0, t_step=0.01)
    assert dense.stats["linear_solver"] == "dense"
    monkeypatch.setattr(sundae, "DENSE_LIMIT", 10)
    for name, limit, refresh in (("bordered band", module.BAND_WORK_LIMIT, 10),
                                 ("SuperLU", 0, 10), ("bordered band", module.BAND_WORK_LIMIT, 1)):
        monkeypatch.setattr(module, "BAND_WORK_LIMIT", limit)
        monkeypatch.setattr(sundae, "REFRESH_STEPS", refresh)
        sparse = transient(circuit, 8.0, t_step=0.01)
        assert name in sparse.stats["linear_solver"]
        for node in ("act[0]", "act[5]", "act[7]"):
            np.testing.assert_allclose(sparse.pressure(node), dense.pressure(node), rtol=5e-4)
