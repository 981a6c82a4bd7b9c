"""Sparse Newton with pseudo-transient continuation for steady states.

Solves F(y) = 0 for the unknowns listed in ``active`` (the others stay fixed);
the unknowns are absolute pressures and are kept positive (the quadrature law
is even in p, so p → −p would otherwise be a spurious root).
Plain damped Newton is tried first; if it stalls (closed valves make parts of the
Jacobian vanish), pseudo-transient continuation solves (J + C/Δτ)·Δy = −F with Δτ
growing as the residual falls (switched evolution relaxation), which follows the
physical relaxation of the circuit towards its steady state.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class NewtonResult:
    y: np.ndarray
    converged: bool
    iterations: int
    residual: float


DENSE_LIMIT = 40  # unknowns up to which Jacobians are dense arrays (LAPACK, no scipy.sparse)


def _solve(matrix, rhs):
    """matrix⁻¹·rhs for a dense array or a scipy sparse matrix; None if singular."""
    if isinstance(matrix, np.ndarray):
        try:
            return np.linalg.solve(matrix, rhs)
        except np.linalg.LinAlgError:
            return None
    from scipy.sparse.linalg import splu

    try:
        return splu(matrix.tocsc()).solve(rhs)
    except RuntimeError:  # exactly singular
        return None


def _block(jac, active):
    """The rows and columns ``active`` of a dense or sparse Jacobian."""
    if isinstance(jac, np.ndarray):
        return jac[np.ix_(active, active)]
    return jac.tocsr()[np.ix_(active, active)]


def newton(residual_jac, y0, active, *, scale=None, capacitance=None, tol=1e-9,
           max_iter=60, max_ptc_iter=2000) -> NewtonResult:
    """Find y with F(y)[active] = 0.

    residual_jac(y, jacobian) -> (F, J): residual (n,) and, when ``jacobian``, the
    Jacobian (n, n) as a dense array or scipy sparse matrix (else None); trial
    points of the line search only need F.
    scale: typical magnitude of y (kPa), for the step criterion.
    capacitance: per-unknown pseudo capacitance for continuation (mg/kPa).
    """
    y = np.array(y0, dtype=float)
    active = np.asarray(active, dtype=int)
    if active.size == 0:
        return NewtonResult(y, True, 0, 0.0)
    scale = np.maximum(np.abs(y[active]), 1.0) if scale is None else scale
    f, jac = residual_jac(y, True)
    norm = np.max(np.abs(f[active]))
    flow_scale = max(norm, 1.0)
    for it in range(max_iter):
        step = _solve(_block(jac, active), -f[active])
        if step is None or not np.all(np.isfinite(step)):
            break
        lam = 1.0
        while lam > 1e-4:
            trial = y.copy()
            trial[active] += lam * step
            f_trial = residual_jac(trial, False)[0]
            norm_trial = np.max(np.abs(f_trial[active]))
            if np.isfinite(norm_trial) and np.all(trial[active] > 0) and \
                    norm_trial < norm * (1 - 1e-4 * lam) + 1e-14:
                break
            lam *= 0.5
        else:
            break
        y, norm = trial, norm_trial
        if np.max(np.abs(lam * step) / scale) < tol and norm < 1e-6 * flow_scale:
            return NewtonResult(y, True, it + 1, norm)
        f, jac = residual_jac(y, True)
    if capacitance is None:
        return NewtonResult(y, False, max_iter, norm)
    return _continuation(residual_jac, y, active, scale, capacitance, tol, max_ptc_iter, flow_scale)


def _continuation(residual_jac, y, active, scale, capacitance, tol, max_iter, flow_scale):
    cap = np.asarray(capacitance, dtype=float)[active]
    f, jac = residual_jac(y, True)
    norm0 = norm = np.max(np.abs(f[active]))
    dtau = 1e-4
    for it in range(max_iter):
        block = _block(jac, active)
        if isinstance(block, np.ndarray):
            block[np.diag_indices_from(block)] += cap / dtau
        else:
            from scipy.sparse import diags

            block = block + diags(cap / dtau)
        step = _solve(block, -f[active])
        if step is None or not np.all(np.isfinite(step)):
            dtau *= 0.1
            continue
        trial, norm_trial = _ptc_trial(residual_jac, y, active, step, norm)
        if not np.isfinite(norm_trial) or np.any(trial[active] <= 0):
            dtau *= 0.25
            continue
        y = trial
        # the growth capped before it multiplies: a residual that falls to ~0 gives a
        # ratio near 1e300, whose product overflowed (a raw numpy warning)
        dtau = min(dtau * min(max(norm / max(norm_trial, 1e-300), 0.5), 1e12) * 1.5, 1e12)
        norm = norm_trial
        if np.max(np.abs(step) / scale) < tol and norm < 1e-6 * max(flow_scale, norm0):
            return NewtonResult(y, True, it + 1, norm)
        f, jac = residual_jac(y, True)
    return NewtonResult(y, False, max_iter, norm)


#: halvings of a continuation step tried where the full step does not lower the residual
PTC_HALVINGS = 4


def _ptc_trial(residual_jac, y, active, step, norm):
    """(trial point, its residual norm) of a continuation ``step`` from ``y``: the full
    step, or the first of its halves (at most :data:`PTC_HALVINGS`) that lowers the
    residual below ``norm``; the full step when none does (the relaxation may pass a
    hump).  Without the halving a root where the flow goes as the square root of a
    pressure difference (a closed valve's output, its line's quadrature law) is
    overshot to its mirror point each step: a 2-cycle that never converges."""
    trial = y.copy()
    trial[active] += step
    norm_full = np.max(np.abs(residual_jac(trial, False)[0][active]))
    if not norm_full >= norm:
        return trial, norm_full
    for k in range(1, PTC_HALVINGS + 1):
        half = y.copy()
        half[active] += step * 0.5 ** k
        norm_half = np.max(np.abs(residual_jac(half, False)[0][active]))
        if norm_half < norm and np.all(half[active] > 0):
            return half, norm_half
    return trial, norm_full
