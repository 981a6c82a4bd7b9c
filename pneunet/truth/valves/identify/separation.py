"""Stage 1 of the valve identification: the open/closed plane (paper eqs. 21–22).

Points labelled open (ṁ > ṁ_min) and closed are separated in x = (p_in, p_out, p_ctrl)
(kPa) by a soft-margin linear SVM (scikit-learn ``SVC(kernel="linear")``, the paper's
C); eq. 22 turns the plane w·x + b = 0 into a_in, a_out and p_close.  A smoothed-hinge
Newton solver of the same problem serves the resampling replicates.
"""
from __future__ import annotations

import warnings

import numpy as np

from ....common.errors import DataError


def _svc(X, y, C, sample_weight=None):
    from sklearn.svm import SVC

    mu = X.mean(axis=0)
    model = SVC(kernel="linear", C=C, tol=1e-3, cache_size=200)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(X - mu, y, sample_weight=sample_weight)
    w = model.coef_[0].astype(float)
    return w, float(model.intercept_[0] - w @ mu)


def smooth_svm(X, y, C=0.1, *, sample_weight=None, start=None, eps=0.05, max_iter=100):
    """The soft-margin problem of eq. 21 with a smoothed hinge, by damped Newton.

    The hinge max(0, 1 − z) is replaced by a quadratic within ``eps`` of the margin,
    so the solution differs from the SVM by O(eps) in the margin units (1/|w|,
    a few kPa here, so well below 0.1 kPa).  Four unknowns, so a Newton step costs
    microseconds: used for the bootstrap replicates and to pick the points the
    exact SVM (:func:`separate`) needs.  Returns (w, b).
    """
    X = np.asarray(X, float)
    y = np.asarray(y, float)
    c = np.ones(len(y)) if sample_weight is None else np.asarray(sample_weight, float)
    mu = X.mean(axis=0)
    Xt = np.column_stack([X - mu, np.ones(len(y))])
    if start is None:
        v = np.zeros(4)
        v[2] = -0.1
    else:
        w0, b0 = start
        v = np.append(w0, b0 + w0 @ mu)
    ridge = np.diag([1.0, 1.0, 1.0, 0.0])

    def objective(v):
        z = y * (Xt @ v)
        loss = np.where(z >= 1, 0.0, np.where(z <= 1 - eps, 1 - z - eps / 2,
                                               (1 - z) ** 2 / (2 * eps)))
        return 0.5 * v[:3] @ v[:3] + C * (c @ loss), z

    f, z = objective(v)
    for _ in range(max_iter):
        dl = np.where(z >= 1, 0.0, np.where(z <= 1 - eps, -1.0, -(1 - z) / eps))
        d2 = np.where((z > 1 - eps) & (z < 1), 1.0 / eps, 0.0)
        grad = ridge @ v + C * (Xt.T @ (c * dl * y))
        hess = ridge + C * (Xt.T @ (Xt * (c * d2)[:, None])) + 1e-9 * np.eye(4)
        try:
            step = -np.linalg.solve(hess, grad)
        except np.linalg.LinAlgError:
            step = -grad
        t = 1.0
        while True:
            f_new, z_new = objective(v + t * step)
            if f_new <= f + 1e-4 * t * (grad @ step) or t < 1e-10:
                break
            t *= 0.5
        v, f_old, f, z = v + t * step, f, f_new, z_new
        if abs(f_old - f) <= 1e-12 * max(1.0, abs(f)) and np.linalg.norm(t * step) < 1e-10 * (
                1 + np.linalg.norm(v)):
            break
    w = v[:3]
    return w, float(v[3] - w @ mu)


def separate(X, y, C=0.1, *, window=60.0):
    """Soft-margin linear SVM (scikit-learn SVC) on pressures X (n×3, kPa), labels y (±1).

    Returns (w, b) of the plane w·x + b = 0.  Solves the same problem as an SVM on
    all points, faster: a smoothed-hinge solution (:func:`smooth_svm`) selects the
    points within ``window`` kPa of the plane (in p_ctrl) or inside its margin, the
    SVM is solved on those, and points left out that violate the margin (y·f < 1)
    are added until there are none — points beyond the margin have zero dual
    weight, so the result is the full-data SVM solution.
    """
    y = np.asarray(y)
    if (y > 0).all() or (y < 0).all():
        kind = "open" if (y > 0).all() else "closed"
        raise DataError(f"all {len(y)} points are labelled {kind}: there is no open/closed "
                        f"boundary to identify",
                        hint="check mdot_min and the flow units, and that the protocol lowers "
                             "p_ctrl far enough to open the valve and raises it to close it")
    n = len(y)
    w, b = smooth_svm(X, y, C)
    for _ in range(10):
        f = X @ w + b
        dist = np.abs(f / w[2]) if w[2] != 0 else np.abs(f)
        active = (dist <= window) | (y * f < 1.5)
        if len(np.unique(y[active])) < 2:
            active = np.ones(n, dtype=bool)
        w, b = _svc(X[active], y[active], C)
        f = X @ w + b
        violators = (~active) & (y * f < 1.0 - 1e-6)
        if not violators.any():
            return w, b
        window *= 2.0
    return _svc(X, y, C)


def plane_to_params(w, b):
    """eq. 22: (a_in, a_out, p_close) from the plane w·x + b = 0."""
    if not w[2] < 0:
        raise DataError("the separating plane does not close the valve as p_ctrl rises "
                        f"(w_ctrl = {w[2]:.3g} ≥ 0)",
                        hint="the open/closed labels do not follow the control pressure; check "
                             "column order (p_in, p_out, p_ctrl) and mdot_min")
    return -w[0] / w[2], -w[1] / w[2], b / w[2]
