"""SUNDIALS IDA through scikit-sundae — the only module that imports sksundae.

Linear algebra: small systems use IDA's dense solver with the analytic Jacobian.
Large ones use a direct sparse solve driven through IDA's iterative-solver
interface (scikit-sundae's own sparse direct solver, SuperLU_MT, costs ~15 ms
per factorisation even at a few hundred unknowns — benchmarks/README.md):

* at each Jacobian set-up IDA asks for, the analytic ∂F/∂y and ∂F/∂ẏ are
  evaluated and P = ∂F/∂y + cj·∂F/∂ẏ is factorised
  (:mod:`~pneunet.engine.solvers.sparse_lu`: bordered band or SuperLU);
* GMRES is given the operator A = P/c, with c = 2/(1 + cj/cj_P) the correction
  IDA applies to direct solves when cj has changed since the set-up, and P's
  LU as preconditioner.  P⁻¹A is then c⁻¹·I: GMRES converges in one iteration
  to x = c·P⁻¹·b, exactly IDA's modified Newton step with a direct solver.
  P⁻¹(A·v) is returned as v/c without a second triangular solve.

So each Newton iteration costs one residual, one sparse product and one LU
solve.  IDA re-evaluates the Jacobian only when c_j changes or Newton fails; at a
constant step a stale Jacobian can hold the nodes of a dead-end chain of open valves at
zero flow (the flow band's stiff, strongly curved law) in a period-2 oscillation that
IDA's RMS norm accepts (6-bit demultiplexer: ±0.02 kPa, thousands of equal steps).  So
after :data:`REFRESH_STEPS` steps without a set-up the preconditioner is refreshed at the
current Newton iterate, which an iterative linear solver allows (the demultiplexer:
26,900 → 22,300 steps, 11.1 → 9.9 s).
"""
from __future__ import annotations

import sys

import numpy as np

from .base import EVENT, FAILED, OK, TSTOP, Integrator, Segment, StepResult
from .sparse_lu import sparse_lu


def _import_ida():
    """scikit-sundae's IDA module, without loading all of scipy.optimize.

    scikit-sundae 1.2 imports ``group_columns`` from ``scipy.optimize._numdiff`` when it
    loads, which runs the whole scipy.optimize package (0.2–0.4 s, more than a small
    transient).  If scipy.optimize is not loaded yet, its package is registered without
    running its ``__init__`` just while that one submodule loads, then unregistered with
    it: a later ``import scipy.optimize`` loads everything afresh, as if for the first time.
    """
    if "scipy.optimize" in sys.modules or "sksundae.ida" in sys.modules:
        from sksundae import ida
        return ida
    import importlib.util

    import scipy

    spec = importlib.util.find_spec("scipy.optimize")
    sys.modules["scipy.optimize"] = importlib.util.module_from_spec(spec)  # __init__ not run
    try:
        from sksundae import ida
    finally:
        for name in [m for m in sys.modules if m.split(".")[:2] == ["scipy", "optimize"]]:
            del sys.modules[name]
        scipy.__dict__.pop("optimize", None)
    return ida


ida = _import_ida()

DENSE_LIMIT = 40  # unknowns up to which the dense linear solver is faster
REFRESH_STEPS = 10  # steps without a Jacobian set-up after which the LU is refreshed
_STATUS = {0: OK, 1: TSTOP, 2: EVENT}  # IDA's return flags; any other is a failure


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
            # one matrix object, refilled in place: building a scipy matrix
            # validates its indices, which costs more than the data
            self._matrix = dae.csc(np.zeros(dae.nnz))
            self._factors = sparse_lu(self._matrix)
            self._lu, self._cj_setup, self._last_product = None, 1.0, (None, None)
            self._steps_since_setup = 0
            options.update(linsolver="gmres", krylov_dim=5,
                           precond=ida.IDAPrecond(self._lu_setup, self._lu_solve),
                           jactimes=ida.IDAJacTimes(None, self._operator))
        self._eventsfn = None
        if events is not None:
            def eventsfn(t, y, yp, out):
                out[0] = events(t, y)
            eventsfn.terminal = [True]
            eventsfn.direction = [-1]
            options.update(eventsfn=eventsfn, num_events=1)
            self._eventsfn = eventsfn
        self._solver = ida.IDA(self._res, **options)

    def _res(self, t, y, yp, res):
        self.n_res += 1
        res[:] = self.dae.evaluate(t, y, yp)[0]

    def _jac_dense(self, t, y, yp, res, cj, jj):
        self.n_jac += 1
        self.dae.dense(self.dae.evaluate(t, y, yp, cj)[1], out=jj)

    def _lu_setup(self, t, y, yp, res, cj):
        self.n_jac += 1
        self._matrix.data[:] = self.dae.evaluate(t, y, yp, cj)[1]
        self._lu = self._factors.factor(self._matrix.data)
        self._cj_setup = cj
        self._steps_since_setup = 0

    def _operator(self, t, y, yp, res, v, av, cj):
        """A·v with A = P/c (see the module docstring); remembers v for _lu_solve."""
        scale = 0.5 * (1.0 + cj / self._cj_setup)  # 1/c
        av[:] = scale * (self._matrix @ v)
        self._last_product = (av.copy(), v / scale)

    def _lu_solve(self, t, y, yp, res, rvec, zvec, cj, delta):
        product, solution = self._last_product
        if product is not None and np.array_equal(rvec, product):
            zvec[:] = solution  # P⁻¹(P·v/c) = v/c
            return
        if self._steps_since_setup >= REFRESH_STEPS:
            self._lu_setup(t, y, yp, None, cj)
        zvec[:] = self._lu.solve(rvec)

    def init(self, t, y, yp):
        result = self._solver.init_step(t, y, yp)
        if result.status < 0:
            raise RuntimeError(result.message)

    def step(self, target, tstop, onestep):
        if not self.dense:
            self._steps_since_setup += 1
        r = self._solver.step(target, method="onestep" if onestep else "normal", tstop=tstop)
        status = _STATUS.get(r.status, FAILED)
        if status == EVENT:
            self._forget_events()
        return StepResult(status, float(r.t), r.y, r.yp, r.message)  # y, yp: fresh copies

    def segment(self, t0, y0, yp0, t_end, outputs=None, restart=True, final=False):
        """A restarted, final segment storing every step on the dense path is run by
        scikit-sundae's ``solve``: IDA's same one-step loop to the stop (or a root), in
        Cython, without a result object per step (an oscillator: 1426 steps, ~10 % less
        CPU; identical rows).  IDA cannot continue after it (``step`` wants a new
        ``init_step``), hence ``final``; the sparse path counts steps (REFRESH_STEPS)."""
        if not (restart and final and outputs is None and self.dense):
            return super().segment(t0, y0, yp0, t_end, outputs, restart)
        r = self._solver.solve(np.array([t0, t_end]), y0, yp0)
        status = _STATUS.get(r.status, FAILED)
        if status == EVENT:
            self._forget_events()
        # row 0 is the start; rows whose t does not pass the previous one's are dropped,
        # as Integrator.segment does: steps too small to move t, and a failure's row
        # (it repeats the last good step)
        t = r.t[1:]
        keep = np.flatnonzero(np.diff(t, prepend=-np.inf) > 0)
        return Segment(status, t[keep], r.y[1:][keep], r.yp[1:][keep], r.message)

    def _forget_events(self):
        """Empty the roots scikit-sundae keeps on the event function: it turns all of
        them into arrays after every step, so each step would cost more with each
        fold passed (a long oscillation: 100+ folds)."""
        for found in ("_i", "_t", "_y", "_yp"):
            getattr(self._eventsfn, found, []).clear()

    def counters(self):
        return {"residual_calls": self.n_res, "jacobian_calls": self.n_jac,
                "linear_solver": "dense" if self.dense else
                f"sparse LU ({self._factors.name}) through GMRES, one iteration"}
