"""SUNDIALS IDA through scikit-sundae — the only module that imports sksundae.

Sparse systems use SuperLU_MT with the circuit's analytic CSC Jacobian (data in
the pattern's order, filled in place); small systems use the dense solver.
"""
from __future__ import annotations

import numpy as np
from sksundae import ida

from .base import EVENT, FAILED, OK, TSTOP, Integrator, StepResult

DENSE_LIMIT = 40  # unknowns up to which the dense linear solver is faster


class SundaeIntegrator(Integrator):
    name = "sksundae"

    def __init__(self, dae, *, rtol, atol, max_step=0.0, events=None):
        self.dae = dae
        self.n_res = 0
        self.n_jac = 0
        self._last = None
        dense = dae.n <= DENSE_LIMIT
        options = dict(rtol=rtol, atol=atol, max_num_steps=100000, max_step=max_step,
                       constraints_idx=np.arange(dae.n), constraints_type=np.full(dae.n, 2),
                       algebraic_idx=dae.algebraic_idx if dae.algebraic_idx.size else None)
        if dense:
            options.update(linsolver="dense", jacfn=self._jac_dense)
        else:
            options.update(linsolver="sparse", sparsity=dae.sparsity(), jacfn=self._jac_sparse)
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

    def _jac_sparse(self, t, y, yp, res, cj, jj):
        self.n_jac += 1
        jj[:] = self.dae.evaluate(t, y, yp, cj)[1]

    def _jac_dense(self, t, y, yp, res, cj, jj):
        self.n_jac += 1
        jj[:, :] = self.dae.csc(self.dae.evaluate(t, y, yp, cj)[1]).toarray()

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
                "linear_solver": "dense" if self.dae.n <= DENSE_LIMIT else "sparse (SuperLU_MT)"}
