"""SUNDIALS IDA through scikits.odes — the only module that imports scikits.odes.

An optional backend (``pip install pneunet[odes]``; scikits.odes 2.7 compiles
against a system SUNDIALS 6, e.g. Debian's ``libsundials-dev``).

scikits.odes 2.7 has no sparse direct solver, and its preconditioned Krylov path
is broken for IDA (the preconditioner-solve callback raises ``AttributeError:
'IDA_data' object has no attribute 'r_vec'`` and GMRES never converges), so this
backend always uses IDA's dense solver with the circuit's analytic Jacobian.
That is fine for small circuits; beyond ``DENSE_WARN`` unknowns it warns that
the cost grows like n³ and the default backend (scikit-sundae, sparse) should
be used.

Three differences to scikit-sundae are handled here: the root function has no
direction (roots crossing upwards are stepped over), the stop time is held in
single precision (a stop within 1e-6 relative of ``tstop`` is reported at
``tstop`` exactly), and positivity constraints are not set (``constraints_idx``
makes ``init_step`` fail with a TypeError in 2.7).
"""
from __future__ import annotations

import numpy as np
from scikits.odes import dae as _dae

from .base import EVENT, FAILED, OK, TSTOP, Integrator, StepResult

DENSE_WARN = 300  # unknowns above which the dense solver is too slow to recommend
_TSTOP_SNAP = 1e-6  # relative distance at which a stop counts as reaching tstop


class OdesIntegrator(Integrator):
    name = "odes"

    def __init__(self, dae, *, rtol, atol, max_step=0.0, events=None):
        self.dae = dae
        self.n_res = 0
        self.n_jac = 0
        self._events = events
        self._g_hist: list[tuple[float, float]] = []
        self._tstop = None
        self._onestep = None
        if dae.n > DENSE_WARN:
            import warnings

            warnings.warn(f"the odes backend solves {dae.n} unknowns with a dense Jacobian "
                          "(cost ~n³); use backend='sksundae' (sparse) for large circuits",
                          RuntimeWarning, stacklevel=3)
        options = dict(rtol=rtol, atol=atol, max_steps=100000, max_step_size=max_step,
                       old_api=False, compute_initcond=None)
        # no positivity constraints: scikits.odes 2.7 fails in init_step when
        # constraints_idx is given (TypeError), so pressures are left unconstrained
        if dae.algebraic_idx.size:
            options.update(algebraic_vars_idx=dae.algebraic_idx)
        options.update(linsolver="dense", jacfn=self._jac_dense)
        if events is not None:
            options.update(rootfn=self._root, nr_rootfns=1)
        self._options = options
        self._solver = _dae("ida", self._res, **options)

    # -- callbacks (each returns 0: success) ------------------------------------------
    def _res(self, t, y, yp, res):
        self.n_res += 1
        res[:] = self.dae.evaluate(t, y, yp)[0]
        return 0

    def _jac_dense(self, t, y, yp, res, cj, jac):
        self.n_jac += 1
        self.dae.dense(self.dae.evaluate(t, y, yp, cj)[1], out=jac)
        return 0

    def _root(self, t, y, yp, g):
        g[0] = self._events(t, y)
        self._g_hist.append((t, g[0]))
        del self._g_hist[:-8]
        return 0

    # -- Integrator -------------------------------------------------------------------
    def init(self, t, y, yp):
        self._g_hist.clear()
        result = self._solver.init_step(t, np.array(y, float), np.array(yp, float))
        if result.flag < 0:
            raise RuntimeError(result.message)

    def _configure(self, tstop, onestep):
        changes = {}
        if tstop != self._tstop:
            changes["tstop"] = tstop
        if onestep != self._onestep:
            changes["one_step_compute"] = onestep
        if changes:
            self._solver.set_options(**changes)
            self._tstop, self._onestep = tstop, onestep

    def step(self, target, tstop, onestep):
        while True:
            self._configure(tstop, onestep)
            r = self._solver.step(target)
            flag = int(r.flag)
            if flag == 2 and not self._crossed_downwards(r.roots.t):
                continue  # the indicator rose through zero: not a fold
            break
        if flag < 0:
            t = float(np.atleast_1d(r.errors.t)[-1]) if r.errors.t is not None else np.nan
            y = np.array(r.errors.y) if r.errors.y is not None else np.full(self.dae.n, np.nan)
            yp = np.array(r.errors.ydot) if r.errors.ydot is not None else np.zeros(self.dae.n)
            return StepResult(FAILED, t, y.reshape(-1, self.dae.n)[-1],
                              yp.reshape(-1, self.dae.n)[-1], str(r.message))
        if flag == 1:
            values = r.tstop
            self._tstop = None  # IDA clears its stop time once reached
        elif flag == 2:
            values = r.roots
        else:
            values = r.values
        t = float(np.atleast_1d(values.t)[-1])
        if flag == 1 or abs(t - tstop) <= _TSTOP_SNAP * max(1.0, abs(tstop)):
            # scikits.odes stores tstop in single precision
            if abs(t - tstop) <= _TSTOP_SNAP * max(1.0, abs(tstop)):
                t = float(tstop)
            status = TSTOP if flag == 1 else (EVENT if flag == 2 else OK)
        else:
            status = {0: OK, 2: EVENT}.get(flag, OK)
        # r.tstop and r.roots accumulate every stop so far: the last row is this one
        y = np.array(values.y, dtype=float).reshape(-1, self.dae.n)[-1]
        yp = np.array(values.ydot, dtype=float).reshape(-1, self.dae.n)[-1]
        return StepResult(status, t, y, yp, str(r.message))

    def _crossed_downwards(self, t_root) -> bool:
        t_root = float(np.atleast_1d(t_root)[-1])
        before = [(t, g) for t, g in self._g_hist if t < t_root]
        return not before or max(before)[1] > 0.0

    def counters(self):
        return {"residual_calls": self.n_res, "jacobian_calls": self.n_jac,
                "linear_solver": "dense"}
