"""Folds of the algebraic equations and explicit jumps between solution branches.

With the differential states frozen, the algebraic equations F_a(y_d, y_a) = 0
of a relaxation oscillator have a fold (impasse point): their Jacobian J_aa
becomes singular and the branch ends; a pure DAE has no continuation there.

*Fold indicator.*  Each row of J_aa is divided by the sum of the absolute
contributions to it before they cancel (so that a stiff link of 10⁵ mg/(s·kPa)
and a valve node of 1 weigh alike under pivoting), then LU-factorised.  The
smallest pivot is ~1 for a well-posed node and tends to 0 at a fold.  The
transient driver stops (an IDA root) where it falls below ``fold_threshold``
times its value at the last restart.

*Jump.*  The physically right landing point is the limit of vanishing dead
volumes: with y_d frozen the algebraic nodes relax along
dy_a/dτ = −F_a(y_d, y_a)/s_a (s_a: the row scale), which leaves the fold and
settles on the other stable branch.  The differential state is first pushed a
tiny time δ past the fold along ẏ_d (δ grows until the landing point is no
longer at a fold), then the relaxation is integrated and polished by Newton.
"""
from __future__ import annotations

import math

import numpy as np

from ...common.errors import SolverError


class FoldMonitor:
    """Fold indicator and jump for one :class:`~pneunet.engine.assembly.CircuitDAE`."""

    def __init__(self, dae, threshold: float):
        self.dae = dae
        self.alg = dae.algebraic_idx
        self.threshold = threshold
        self.reference = 1.0
        self.restarted = 0.0  # time of the last restart, s
        self._went_on_at = None  # time of the last near-fold passed on the branch, s
        self._block = dae.algebraic_block()
        # one algebraic node on Python floats: the indicator and relaxation without arrays
        self._one = self._block.floats if self._block.size == 1 else None
        # a few on floats: the indicator's LU on lists (a heat-exchanging tank's inlets)
        self._few = self._block.floats if 1 < self._block.size <= FEW_ON_FLOATS else None

    def indicator(self, t, y) -> float:
        """Smallest normalised LU pivot of J_aa (0 at a fold, ~1 far from one)."""
        if self._one is not None:
            _, jac, scale = self._one.lists(t, y, residual=False)
            return abs(jac[0]) / scale[0]
        if self._few is not None:
            _, jac, scale = self._few.lists(t, y, residual=False)
            n = len(scale)
            rows = [[jac[i * n + j] / scale[i] for j in range(n)] for i in range(n)]
            return min(map(abs, _pivots_on_lists(rows)))
        _, jac, scale = self._block.evaluate(t, y, residual=False)
        if isinstance(jac, np.ndarray):
            if jac.shape[0] == 1:
                return float(abs(jac[0, 0]) / scale[0])
            jac = jac / scale[:, None]
        else:
            from scipy.sparse import diags

            jac = (diags(1.0 / scale) @ jac).tocsc()
        return float(np.min(np.abs(_lu_pivots(jac))))

    def restart(self, t, y) -> None:
        """Remember the indicator at a restart: folds are judged relative to it."""
        self.reference = max(self.indicator(t, y), 1e-12)
        self.restarted = t

    def event(self, t, y) -> float:
        """Root function for the integrator: crosses zero downwards at a fold."""
        return self.indicator(t, y) - self.threshold * self.reference

    def near_fold(self, t, y) -> bool:
        """Whether the state is well on its way to a fold (for stalled integrations)."""
        return self.indicator(t, y) < 0.3 * self.reference

    def jump(self, t, y, yp, previous):
        """Land on the other branch: returns ``(t_new, y_new, True)``, or ``(t, y, False)``
        at a near-fold, where the branch goes on (:meth:`goes_on`) from the state ``(t,
        y)`` the approach reached.

        ``previous`` = (t, y) of an earlier state on the branch.  The branch is first
        followed to the fold (:meth:`approach`); there the indicator κ falls like
        √(t* − t), so κ² extrapolates linearly to the fold time t*; the first push δ
        goes :data:`PUSH_PAST` times the estimated distance, growing by
        :data:`PUSH_GROWTH` (:data:`PUSH_FINE` times, then by 4) while the state lands
        back on its own branch, or on a mirror root with a pressure at or below zero (a
        line of 2 kPa·s/mg into the oscillator's tank: pushed 111 s on, its tank at
        −201 kPa, and the run went on from there).
        """
        d = self.dae.differential
        t, y, yp, previous = self.approach(t, y, yp, previous)
        t_prev, y_prev = previous
        k_now, k_prev = self.indicator(t, y), self.indicator(t_prev, y_prev)
        if t != self._went_on_at and self.goes_on(t, y, yp, k_now):
            self._went_on_at = t  # the integrator failing here again: a jump after all
            return t, y, False
        slope = (k_now ** 2 - k_prev ** 2) / max(t - t_prev, 1e-300)
        estimate = k_now ** 2 / -slope if slope < 0 else 0.0
        delta = max(PUSH_PAST * estimate, 1e-12 * max(abs(t), 1.0))
        for attempt in range(30):
            pushed = y.copy()
            pushed[d] += yp[d] * delta
            landed = (self._relax if self._one is None else self._relax_one)(t + delta, pushed)
            if landed is not None and (landed > 0).all() and \
                    self.indicator(t + delta, landed) > 3 * self.threshold * self.reference:
                return t + delta, landed, True
            delta *= PUSH_GROWTH if estimate and attempt < PUSH_FINE else 4.0
        raise SolverError("could not jump to another solution branch after a fold", time=t,
                          hint="set a small dead volume instead (.options dead_volume=0.05mL)")

    def goes_on(self, t, y, yp, kappa) -> bool:
        """Whether the branch goes on past ``(t, y)``, where the approach stopped with
        the indicator ``kappa`` above :data:`FOLD_RESOLVED`: a step along it of
        :data:`NEAR_FOLD_STEP` × the time since the last restart finds it, with κ no
        smaller.  Then κ has a positive minimum or a plateau there (a near-fold), not a
        fold: near the end of an oscillation the tank settles just short of the valve's
        fold (κ stalled at 0.3 %), and pushing the state on linearly until it landed
        away from there skipped 0.5–1.1 s on each cycle and kept it oscillating."""
        if kappa <= FOLD_RESOLVED * self.reference:
            return False
        step = self._branch_step(t, y, yp, NEAR_FOLD_STEP * max(t - self.restarted, 0.0))
        return step is not None and self.indicator(step[0], step[1]) >= (1 - 1e-3) * kappa

    def approach(self, t, y, yp, previous):
        """``(t, y, ẏ, previous)`` followed along the branch until the indicator is below
        :data:`FOLD_RESOLVED` times its reference or the next step finds no branch.

        The integrator stops at κ = ``threshold`` (1 %), where the time left to the fold
        is ~10⁻⁴ of the branch's time scale but, near a slow turning point, ~1 ms: the
        oscillator's vent fold was 1.4 ms away and κ² bends there (the tank decelerates),
        so a jump extrapolated from it came 1 ms late on every cycle and the period was
        5e-4 long, more than a recording's standard errors resolve.  Here the branch is
        followed as the DAE defines it: the differential states by Heun steps of ẏ_d, the
        algebraic nodes solved by Newton's method at each, every step
        :data:`APPROACH_FRACTION` of the time κ² extrapolates to the fold; a step whose
        Newton finds no branch is halved.
        """
        target = (FOLD_RESOLVED * self.reference) ** 2
        k2 = self.indicator(t, y) ** 2
        t_prev, y_prev = previous
        rate = (k2 - self.indicator(t_prev, y_prev) ** 2) / max(t - t_prev, 1e-300)
        h = APPROACH_FRACTION * k2 / -rate if rate < 0 else 0.0
        if h < APPROACH_FROM * (t - self.restarted):  # the push's error is negligible
            return t, y, yp, previous
        floor = 1e-13 * max(abs(t), 1.0)
        for _ in range(APPROACH_STEPS):
            if k2 <= target or h < floor:
                break
            step = self._branch_step(t, y, yp, h)
            k2_new = self.indicator(step[0], step[1]) ** 2 if step is not None else math.inf
            if not k2_new < k2:  # past the fold, or not approaching it: a shorter step
                h *= 0.5
                continue
            previous = (t, y)
            rate = (k2_new - k2) / h
            t, y, yp = step
            k2 = k2_new
            h = APPROACH_FRACTION * k2 / -rate
        return t, y, yp, previous

    def _branch_step(self, t, y, yp, h):
        """One Heun step of length ``h`` along the branch: ``(t + h, y, ẏ)`` or None
        where Newton's method finds no stable root near the predicted one."""
        d = self.dae.differential
        predicted = y.copy()
        predicted[d] += h * yp[d]
        first = self._on_branch(t + h, predicted)
        if first is None:
            return None
        rate = self.dae.derivative(t + h, first)
        corrected = first.copy()
        corrected[d] = y[d] + 0.5 * h * (yp[d] + rate[d])
        landed = self._on_branch(t + h, corrected)
        if landed is None:
            return None
        return t + h, landed, self.dae.derivative(t + h, landed)

    def _on_branch(self, t, y):
        """``y`` with its algebraic nodes solved by Newton's method from their values,
        or None: no convergence, a step beyond a fifth of a pressure, or an unstable
        root (the relaxation's criterion)."""
        if self._one is not None:
            return self._on_branch_one(t, y)
        full = y.copy()
        alg = self.alg
        for _ in range(BRANCH_NEWTON_STEPS):
            res, jac, scale = self._system(t, full)
            ya = full[alg]
            if np.abs(res / scale).max() <= 1e-10 * ya.max():
                return full if self._stable(jac) else None
            step = _solve_newton(jac, res)
            if step is None or not (np.abs(step) <= 0.2 * ya).all():
                return None
            full[alg] = ya + step
        return None

    def _on_branch_one(self, t, y):
        """:meth:`_on_branch` for one algebraic node, on Python floats."""
        k = int(self.alg[0])
        full = y.copy()
        for _ in range(BRANCH_NEWTON_STEPS):
            (res,), (jac,), (scale,) = self._one.lists(t, full)
            ya = float(full[k])
            if abs(res / scale) <= 1e-10 * ya:
                return full if jac > 0 else None
            step = -res / jac if jac else math.nan
            if not abs(step) <= 0.2 * ya:  # NaN too
                return None
            full[k] = ya + step
        return None

    def _relax(self, t, y):
        """Relax the algebraic nodes to a stable branch with y_d frozen, or None.

        Follows dy_a/dτ = f = −F_a/s_a (τ dimensionless, s_a the row scale) by
        linearly implicit Euler steps (I + Δτ·J_aa/s_a)·Δy = Δτ·f that go along f,
        with Δτ set by the Euler error estimate Δτ/2·|f(y+Δy) − f(y)| ≤ 3 % of the
        pressure (the first step an Euler step of that size): slow through the ghost
        of the vanished branch, then growing until each step is Newton's and
        converges quadratically onto the branch the relaxation leads to.  A step
        costs one residual and one J_aa.
        """
        full = y.copy()
        res, jac, scale = self._system(t, full)
        dtau = RELAX_TOL * (full[self.alg] * scale / np.maximum(np.abs(res), 1e-300)).min()
        for _ in range(RELAX_STEPS):
            ya = full[self.alg]
            rate = -res / scale
            step = _solve(jac, scale, dtau, rate)
            # along the flow (a large Δτ reverses the step where J_aa/s_a < −1/Δτ)
            if step is not None and (np.abs(step) <= 0.2 * ya).all() and step @ rate > 0:
                trial = full.copy()
                trial[self.alg] = ya + step
                res1, jac1, scale1 = self._system(t, trial)
                err = (0.5 * dtau * np.abs(-res1 / scale1 - rate) / (RELAX_TOL * ya)).max()
                if np.isfinite(res1).all() and err <= 1.0:
                    full, res, jac, scale = trial, res1, jac1, scale1
                    if np.abs(res / scale).max() <= 1e-10 * ya.max():
                        return full if self._stable(jac) else None
                    dtau *= min(4.0, 0.9 / np.sqrt(max(err, 1e-6)))
                    continue
                dtau *= max(0.2, 0.9 / np.sqrt(err)) if np.isfinite(err) else 0.2
            else:
                dtau *= 0.25
            if dtau < 1e-14:
                return None
        return None

    def _relax_one(self, t, y):
        """:meth:`_relax` for one algebraic node on Python floats: the same operations in
        the same order, so the same bits (a 1×1 solve is a division and its eigenvalue the
        entry), without the ~30 one-element array operations of each step."""
        k = int(self.alg[0])
        full = y.copy()
        ya = float(full[k])
        (res,), (jac,), (scale,) = self._one.lists(t, full)
        dtau = RELAX_TOL * (ya * scale / max(abs(res), 1e-300))
        for _ in range(RELAX_STEPS):
            rate = -res / scale
            pivot = dtau * jac / scale + 1.0
            step = dtau * rate / pivot if pivot else math.nan
            if math.isfinite(step) and abs(step) <= 0.2 * ya and step * rate > 0:
                full[k] = ya + step
                (res1,), (jac1,), (scale1,) = self._one.lists(t, full)
                err = 0.5 * dtau * abs(-res1 / scale1 - rate) / (RELAX_TOL * ya)
                if math.isfinite(res1) and err <= 1.0:
                    ya, res, jac, scale = float(full[k]), res1, jac1, scale1
                    if abs(res / scale) <= 1e-10 * ya:
                        return full if jac > 0 else None
                    dtau *= min(4.0, 0.9 / math.sqrt(max(err, 1e-6)))
                    continue
                dtau *= max(0.2, 0.9 / math.sqrt(err)) if math.isfinite(err) else 0.2
            else:
                dtau *= 0.25
            if dtau < 1e-14:
                return None
        return None

    def _system(self, t, y):
        """F_a, J_aa and the row scale s_a at (t, y), with ẏ = 0."""
        return self._block.evaluate(t, y)

    @staticmethod
    def _stable(jac) -> bool:
        """Whether the relaxation is stable here: J_aa's eigenvalues have positive real
        parts (checked for dense blocks; large sparse blocks are trusted)."""
        if not isinstance(jac, np.ndarray):
            return True
        return bool(np.all(np.linalg.eigvals(jac).real > 0))


#: the branch is followed to the fold until the indicator is this fraction of its value
#: at the last restart (the time left then ~10⁻⁸ of a branch's time scale), in at most
#: APPROACH_STEPS Heun steps, each with BRANCH_NEWTON_STEPS Newton iterations at most
FOLD_RESOLVED = 1e-3
#: no approach where the estimated time to the fold is below this fraction of the time
#: since the last restart (the push's error, a fraction of that time, is then negligible)
APPROACH_FROM = 1e-5
PUSH_PAST = 1.1
PUSH_GROWTH = 1.5
PUSH_FINE = 6
#: algebraic nodes up to which the fold indicator factorises J_aa on Python floats
FEW_ON_FLOATS = 4
APPROACH_FRACTION = 0.5
APPROACH_STEPS = 60
#: the step (a fraction of the time since the last restart) that tells a near-fold from a
#: fold: past a fold the branch has ended and Newton's method finds no root
NEAR_FOLD_STEP = 1e-3
BRANCH_NEWTON_STEPS = 8
RELAX_STEPS = 400  # relaxation steps (accepted or not) before a jump attempt gives up
RELAX_TOL = 3e-2  # relaxation path error per step, relative to the pressure
RELAX_GROWTH = 1000  # largest growth of Δτ after an accepted step


def _solve(jac, scale, dtau, rate):
    """Δy of one relaxation step: (I + Δτ·S⁻¹J)·Δy = Δτ·rate, None if singular."""
    rhs = dtau * rate
    if isinstance(jac, np.ndarray):
        matrix = dtau * jac / scale[:, None]
        matrix.flat[::len(rhs) + 1] += 1.0
        try:
            if len(rhs) == 1:  # one algebraic node: a division, no LAPACK call
                if not matrix[0, 0]:
                    return None
                step = rhs / matrix[0]
            else:
                step = np.linalg.solve(matrix, rhs)
        except np.linalg.LinAlgError:
            return None
    else:
        from scipy.sparse import diags, identity
        from scipy.sparse.linalg import splu

        try:
            step = splu((identity(len(rhs)) + diags(dtau / scale) @ jac).tocsc()).solve(rhs)
        except RuntimeError:
            return None
    return step if np.isfinite(step).all() else None


def _solve_newton(jac, res):
    """Newton's step −J⁻¹·F (dense or sparse J), None if singular or not finite."""
    try:
        if isinstance(jac, np.ndarray):
            step = -res / jac[0, 0] if jac.shape == (1, 1) else -np.linalg.solve(jac, res)
        else:
            from scipy.sparse.linalg import splu

            step = -splu(jac.tocsc()).solve(res)
    except (np.linalg.LinAlgError, RuntimeError, ZeroDivisionError):
        return None
    return step if np.isfinite(step).all() else None


def _pivots_on_lists(rows):
    """Diagonal of U in an LU factorisation of the small matrix ``rows`` (lists of
    floats) with partial pivoting, the pivots LAPACK's dgetrf chooses (equal to its
    within rounding: a few units in the last place)."""
    rows = [list(r) for r in rows]
    n = len(rows)
    pivots = []
    for k in range(n):
        best = max(range(k, n), key=lambda i: abs(rows[i][k]))
        rows[k], rows[best] = rows[best], rows[k]
        pivot = rows[k][k]
        pivots.append(pivot)
        if pivot == 0.0:
            continue
        for i in range(k + 1, n):
            factor = rows[i][k] / pivot
            if factor:
                row_i, row_k = rows[i], rows[k]
                for j in range(k + 1, n):
                    row_i[j] -= factor * row_k[j]
    return pivots


def _lu_pivots(jac):
    """Diagonal of U in an LU factorisation of ``jac`` (dense or CSC)."""
    if isinstance(jac, np.ndarray):
        from scipy.linalg.lapack import dgetrf

        lu, _, _ = dgetrf(jac)  # LAPACK directly: an exactly singular block has a zero
        return np.diag(lu)      # pivot, without lu_factor's warning (and its filter's cost)
    from scipy.sparse.linalg import splu

    try:
        lu = splu(jac)
    except RuntimeError:  # exactly singular
        return np.zeros(jac.shape[0])
    return lu.U.diagonal()
