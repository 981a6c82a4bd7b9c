"""SUNDIALS IDA through scikit-sundae — the only module that imports sksundae.

Linear algebra: small systems use IDA's dense solver with the analytic Jacobian.
Large ones use GMRES preconditioned by an exact sparse LU factorisation of the
analytic Jacobian (scipy's SuperLU), refactorised whenever IDA asks for a new
Jacobian.  GMRES multiplies by the same analytic Jacobian (∂F/∂y and ∂F/∂ẏ kept
apart, so the product uses IDA's current cj) instead of differencing the
residual: each Newton iteration then costs one residual, one or two sparse
products and one or two triangular solves — a modified Newton method with the
Jacobian IDA decided to keep, as with a direct solver.  This measured several
times faster than scikit-sundae's SuperLU_MT direct solver, whose set-up costs
~15 ms per factorisation even at a few hundred unknowns (benchmarks/README.md).
"""
from __future__ import annotations

import numpy as np
from sksundae import ida

from .base import EVENT, FAILED, OK, TSTOP, Integrator, StepResult

DENSE_LIMIT = 40  # unknowns up to which the dense linear solver is faster
PIVOT_THRESHOLD = 0.1  # SuperLU keeps a diagonal pivot ≥ 0.1 × the column's largest entry


class SundaeIntegrator(Integrator):
    name = "sksundae"

    def __init__(self, dae, *, rtol, atol, max_step=0.0, events=None):
        self.dae = dae
        self.n_res = 0
        self.n_jac = 0
        self.dense = dae.n <= DENSE_LIMIT
        options = dict(rtol=rtol, atol=atol, max_num_steps=100000, max_step=max_step,
                       constraints_idx=np.arange(dae.n), constraints_type=np.full(dae.n, 2),
                       algebraic_idx=dae.algebraic_idx if dae.algebraic_idx.size else None)
        if self.dense:
            options.update(linsolver="dense", jacfn=self._jac_dense)
        else:
            # one matrix object per part, refilled in place: building a scipy
            # matrix validates its indices, which costs more than the data
            self._jac_y = dae.csc(np.zeros(dae.nnz))
            self._jac_ydot = dae.csc(np.zeros(dae.nnz))
            self._matrix = dae.csc(np.zeros(dae.nnz))
            self._lu = None
            options.update(linsolver="gmres", krylov_dim=10,
                           precond=ida.IDAPrecond(self._lu_setup, self._lu_solve),
                           jactimes=ida.IDAJacTimes(None, self._jac_times))
        if events is not None:
            def eventsfn(t, y, yp, out):
                out[0] = events(t, y)
            eventsfn.terminal = [True]
            eventsfn.direction = [-1]
            options.update(eventsfn=eventsfn, num_events=1)
        self._solver = ida.IDA(self._res, **options)

    def _res(self, t, y, yp, res):
        self.n_res += 1
        res[:] = self.dae.evaluate(t, y, yp)[0]

    def _jac_dense(self, t, y, yp, res, cj, jj):
        self.n_jac += 1
        jj[:, :] = self.dae.csc(self.dae.evaluate(t, y, yp, cj)[1]).toarray()

    def _lu_setup(self, t, y, yp, res, cj):
        from scipy.sparse.linalg import splu

        self.n_jac += 1
        _, self._jac_y.data[:], self._jac_ydot.data[:] = self.dae.jacobian_parts(t, y, yp)
        self._matrix.data[:] = self._jac_y.data + cj * self._jac_ydot.data
        self._lu = splu(self._matrix, diag_pivot_thresh=PIVOT_THRESHOLD,
                        options=dict(SymmetricMode=True))

    def _lu_solve(self, t, y, yp, res, rvec, zvec, cj, delta):
        zvec[:] = self._lu.solve(np.asarray(rvec))

    def _jac_times(self, t, y, yp, res, v, jv, cj):
        jv[:] = self._jac_y @ v + cj * (self._jac_ydot @ v)

    def init(self, t, y, yp):
        result = self._solver.init_step(t, y, yp)
        if result.status < 0:
            raise RuntimeError(result.message)

    def step(self, target, tstop, onestep):
        r = self._solver.step(target, method="onestep" if onestep else "normal", tstop=tstop)
        status = {0: OK, 1: TSTOP, 2: EVENT}.get(r.status, FAILED)
        t = float(np.atleast_1d(r.t)[-1])
        y = np.array(r.y).reshape(-1, self.dae.n)[-1]
        yp = np.array(r.yp).reshape(-1, self.dae.n)[-1]
        return StepResult(status, t, y, yp, r.message)

    def counters(self):
        return {"residual_calls": self.n_res, "jacobian_calls": self.n_jac,
                "linear_solver": "dense" if self.dense else
                "GMRES with the analytic Jacobian + sparse LU preconditioner"}
