"""Two-stage identification of the six valve parameters (paper sec. 4.1, eqs. 20–24).

Stage 1 — open/closed boundary (:mod:`.separation`).  Points are labelled open when
ṁ > ṁ_min and a soft-margin linear SVM (scikit-learn ``SVC(kernel="linear")``, the paper's C) finds
the plane w·x + b = 0 in x = (p_in, p_out, p_ctrl); eq. 22 turns it into
a_in = −w_in/w_ctrl, a_out = −w_out/w_ctrl, p_close = b/w_ctrl.

Stage 2 — on the points with Δp > p_close, ``scipy.optimize.least_squares`` fits
1/R = ṁ/√(p_in² − p_out²) against Δp with eq. 24 (free: R_f, p_trans, e).

Threshold correction (default on, ``correct_threshold=False`` is the paper's
procedure exactly).  A point is labelled open only once its flow exceeds ṁ_min,
i.e. at Δp = p_close + δ_i with δ_i = (p_trans − p_close)·(m/√(1−m²))^(1/e),
m = ṁ_min·R_f/√(p_in² − p_out²) — 2 to 5 kPa for the paper's axi valve.  The
SVM therefore finds p_close too high by a few kPa and slightly tilted areas.  The
correction re-runs stage 1 with p_ctrl shifted by δ_i (from the stage-2 estimates),
which makes the labelled boundary exactly the plane Δp = p_close, then stage 2.

Uncertainties.  Neighbouring points of one sweep share the regulator state and
setpoint errors, so points are not independent: the resampling unit is the sweep
(:func:`sweep_groups`; ``groups=None`` treats points as independent).  The whole
pipeline is resampled, linearised: ``n_boot`` replicates each keep a random half of
the sweeps (weight 2) — the delete-d jackknife with d = n/2, which unlike the
ordinary bootstrap stays consistent for non-smooth estimators such as the SVM,
whose plane hinges on the few dozen points in its margin.  Stage 1 re-solves the
soft-margin problem with those weights (smoothed hinge, warm-started, on the points
near the boundary: points beyond the margin never enter the SVM solution); stage 2
takes one weighted Gauss–Newton step from the full-data solution with the *same*
weights plus G·(replicate − estimate) of the stage-1 parameters, G = ∂(R_f, p_trans,
e)/∂(a_in, a_out, p_close) from re-solving stage 2.  The covariance of the
replicates is that of all six parameters, stage-1/stage-2 cross terms included.
Stage-2 variances are not allowed below the sweep-clustered (CR1) sandwich plus
G·cov₁·Gᵀ (100 replicates scatter by ~7 % in standard error).  ``n_boot=0``: stage 2
only, by the clustered sandwich.  95 % intervals are value ± 1.96 standard errors;
``benchmarks/coverage_fit.py`` measures their coverage on bench data (0.90–0.97 per
parameter and valve over 110 seeds; see docs/identify.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ....common.errors import DataError, ParameterError
from ....common.reprs import Summarized, listed, number
from ....physics.valve_params import VALVE_PARAMETERS, ValveParams
from ...core.intervals import inverse_normal_matrix, sandwich_of
from .data import PRESSURES, Measurements, as_frame
from .separation import plane_to_params, separate, smooth_svm

NAMES = ("Rf", "pclose", "ptrans", "e", "ain", "aout")
STAGE1 = ("ain", "aout", "pclose")
STAGE2 = ("Rf", "ptrans", "e")
Z95 = 1.959963984540054
#: automatic ṁ_min = centre + AUTO_SIGMAS × noise of the closed points
AUTO_SIGMAS = 5.0


# --------------------------------------------------------------------------- helpers
def inverse_resistance(frame) -> np.ndarray:
    """Measured 1/R = ṁ/√(p_in² − p_out²), mg/(s·kPa) (eq. 23)."""
    p_in = frame["p_in_kPa"].to_numpy(float)
    p_out = frame["p_out_kPa"].to_numpy(float)
    s = np.sqrt(np.maximum(p_in * p_in - p_out * p_out, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(s > 0, frame["mdot_mg_s"].to_numpy(float) / s, np.nan)


def delta_p(frame, ain, aout) -> np.ndarray:
    """Equivalent membrane pressure difference Δp of every point (eq. 13/25), kPa."""
    from ....physics.laws import valve_delta_p

    return valve_delta_p(frame["p_in_kPa"].to_numpy(float), frame["p_out_kPa"].to_numpy(float),
                         frame["p_ctrl_kPa"].to_numpy(float), ain, aout)


def auto_mdot_min(mdot, *, sigmas=AUTO_SIGMAS):
    """ṁ_min from the noise of the closed points.

    Starts from the 10 % of readings nearest zero (any sensible protocol has that
    many closed points), then iterates: centre = median, noise σ = 1.4826·MAD of the
    points within 4σ of the centre.  Returns ``(mdot_min, centre, sigma)`` with
    mdot_min = centre + ``sigmas``·σ (floor: 1e-4 of the largest reading).
    """
    mdot = np.asarray(mdot, dtype=float)
    mdot = mdot[np.isfinite(mdot)]
    order = np.argsort(np.abs(mdot))
    sample = mdot[order[:max(10, len(mdot) // 10)]]
    centre = float(np.median(sample))
    sigma = float(1.4826 * np.median(np.abs(sample - centre)))
    for _ in range(20):
        if sigma <= 0:
            break
        sample = mdot[np.abs(mdot - centre) <= 4.0 * sigma]
        new_centre = float(np.median(sample))
        new_sigma = float(1.4826 * np.median(np.abs(sample - new_centre)))
        if abs(new_sigma - sigma) <= 1e-3 * sigma and abs(new_centre - centre) <= 1e-3 * sigma:
            centre, sigma = new_centre, new_sigma
            break
        centre, sigma = new_centre, new_sigma
    floor = 1e-4 * float(np.max(np.abs(mdot))) if len(mdot) else 1e-6
    return max(centre + sigmas * sigma, floor), centre, sigma


def sweep_groups(frame) -> np.ndarray:
    """Sweep index of every point: the resampling unit of the uncertainties.

    A ``group`` column is used as is.  Otherwise a new sweep starts where the
    ``sweep`` column (direction of p_ctrl) changes or p_ctrl jumps against that
    direction by more than half the typical step; without a ``sweep`` column, at
    each local maximum of p_ctrl in row order (steps below a quarter of the typical
    step keep the previous direction), so a falling and the following rising run
    form one group.  The paper's protocol gives 210 sweeps of 21
    points (one per p_in/p_out setting).
    """
    n = len(frame)
    if "group" in frame:
        return pd.factorize(frame["group"])[0]
    pc = frame["p_ctrl_kPa"].to_numpy(float)
    if n < 2:
        return np.zeros(n, dtype=int)
    step = np.diff(pc)
    moving = np.abs(step) > 1e-9
    typical = float(np.median(np.abs(step[moving]))) if moving.any() else 1.0
    brk = np.zeros(n, dtype=bool)
    if "sweep" in frame:
        d = np.sign(frame["sweep"].to_numpy(float))
        brk[1:] = (d[1:] != d[:-1]) | (step * d[1:] < -0.5 * typical)
    else:
        d = np.sign(step)
        d[np.abs(step) < 0.25 * typical] = 0
        for i in range(1, len(d)):  # small steps keep the previous direction
            if d[i] == 0:
                d[i] = d[i - 1]
        brk[1:-1] = (d[:-1] > 0) & (d[1:] < 0)  # starts at each highest p_ctrl
    return np.cumsum(brk)


# --------------------------------------------------------------------------- stage 2
def _conductance(x, Rf, pclose, ptrans, e):
    from ....physics.laws import valve_conductance

    return valve_conductance(x, Rf, pclose, ptrans, e)[0]


def _stage2(x, y, pclose, start=None):
    """Least squares of 1/R on Δp (eq. 24): returns (Rf, ptrans, e, result)."""
    from scipy.optimize import least_squares

    if start is None:
        top = float(np.quantile(y, 0.99))
        Rf0 = 1.0 / top if top > 0 else 1.0
        level = 0.7071 * top
        above = x[y >= level]
        d0 = max(float(np.min(above)) - pclose, 1.0) if len(above) else 50.0
        start = (Rf0, pclose + d0, 2.0)
    Rf0, pt0, e0 = start
    theta0 = np.array([math.log(Rf0), math.log(max(pt0 - pclose, 1e-3)), min(max(e0, 0.2), 9.0)])

    def residual(theta):
        Rf, d, e = math.exp(theta[0]), math.exp(theta[1]), theta[2]
        return _conductance(x, Rf, pclose, pclose + d, e) - y

    result = least_squares(residual, theta0, bounds=([-20, -10, 0.1], [20, 20, 10.0]),
                           x_scale="jac", method="trf")
    Rf, d, e = math.exp(result.x[0]), math.exp(result.x[1]), float(result.x[2])
    return Rf, pclose + d, e, result


def _stage2_jacobian(x, Rf, pclose, ptrans, e):
    """Model 1/R at x and its Jacobian in (Rf, ptrans, e) (forward differences)."""
    p = np.array([Rf, ptrans, e])
    base = _conductance(x, *_unpack(p, pclose))
    J = np.empty((len(x), 3))
    for k in range(3):
        h = 1e-6 * max(abs(p[k]), 1e-3)
        q = p.copy()
        q[k] += h
        J[:, k] = (_conductance(x, *_unpack(q, pclose)) - base) / h
    return base, J


def _stage2_cov(x, y, Rf, pclose, ptrans, e, groups=None):
    """Sandwich covariance of (Rf, ptrans, e) at fixed stage-1 parameters.

    ``groups`` (one label per point): cluster-robust CR1 — the score is summed over
    each group (sweep) before its outer product; None: HC1 (independent points).
    """
    base, J = _stage2_jacobian(x, Rf, pclose, ptrans, e)
    r = base - y
    n = len(x)
    bread = inverse_normal_matrix(J)[0]  # an undetermined direction: infinite variance
    score = J * r[:, None]
    if groups is None:
        meat = score.T @ score
        factor = n / max(n - 3, 1)
    else:
        _, index = np.unique(np.asarray(groups), return_inverse=True)
        sums = np.zeros((index.max() + 1, 3))
        np.add.at(sums, index, score)
        g = len(sums)
        meat = sums.T @ sums
        factor = g / max(g - 1, 1) * (n - 1) / max(n - 3, 1)
    return sandwich_of(bread, meat) * factor


def _unpack(p, pclose):
    return p[0], pclose, p[1], p[2]


# --------------------------------------------------------------------------- result
@dataclass(repr=False)
class ValveFit(Summarized):
    """Result of :func:`fit_valve`.

    ``params`` (ValveParams), ``stderr`` and ``ci95`` by parameter name, ``metrics``
    (rmse, rmse_open, rmse_inv_r, misclassified, n, n_open, ...), per point
    ``open`` (labels ṁ > ṁ_min), ``misclassified`` and ``fitted`` (stage-2 points),
    and ``frame`` (the data used).
    """

    params: ValveParams
    stderr: dict
    ci95: dict
    metrics: dict
    open: np.ndarray
    misclassified: np.ndarray
    fitted: np.ndarray
    frame: pd.DataFrame
    mdot_min: float
    C: float
    covariance: pd.DataFrame
    settings: dict = field(default_factory=dict)
    measurements: Measurements | None = None
    plane: tuple = ()

    def _summary(self):
        values = (f"{k} {number(getattr(self.params, k), VALVE_PARAMETERS[k][0].strip('1'))}"
                  for k in NAMES)
        m = self.metrics
        rows = [("parameters", listed(values)),
                ("rms flow error", number(m.get("rmse"), "mg/s", 3)),
                ("points", f"{m.get('n')} ({m.get('misclassified')} misclassified)")]
        return "", rows, ".params, .stderr, .ci95, .report(), .model_card(name)"

    # ---- predictions
    def predict(self, frame) -> np.ndarray:
        """Model flow (mg/s) at the pressures of ``frame`` (canonical columns)."""
        from ....physics.laws import valve_flow

        return valve_flow(np.asarray(frame["p_in_kPa"], float),
                          np.asarray(frame["p_out_kPa"], float),
                          np.asarray(frame["p_ctrl_kPa"], float), **self.params.as_dict())

    def delta_p(self, frame=None) -> np.ndarray:
        return delta_p(self.frame if frame is None else frame, self.params.ain,
                       self.params.aout)

    def inverse_resistance(self, frame=None) -> np.ndarray:
        return inverse_resistance(self.frame if frame is None else frame)

    # ---- output
    def model_card(self, name: str = "VFIT") -> str:
        return self.params.model_card(name)

    def to_json(self) -> dict:
        out = {"params": {k: {"value": float(getattr(self.params, k)),
                              "stderr": _finite_or_none(self.stderr[k]),
                              "ci95": [_finite_or_none(v) for v in self.ci95[k]],
                              "unit": VALVE_PARAMETERS[k][0]} for k in NAMES},
               "metrics": {k: (int(v) if isinstance(v, (int, np.integer)) else float(v))
                           for k, v in self.metrics.items()},
               "covariance": {a: {b: _finite_or_none(float(self.covariance.loc[a, b]))
                                  for b in NAMES} for a in NAMES},
               "settings": {k: v for k, v in self.settings.items()
                            if isinstance(v, (int, float, str, bool)) or v is None}}
        return out

    def report(self, name: str | None = None) -> str:
        m = self.metrics
        s = self.settings
        lines = ["[[Valve fit]]" + (f" {name}" if name else "")]
        lines.append(f"    method           = two-stage (linear SVM C={self.C:g} kPa^-2, "
                     f"then least squares of 1/R on Δp)")
        lines.append(f"    mdot_min         = {self.mdot_min:.4g} mg/s"
                     + (f" (auto: closed-point noise {s.get('noise_sigma', 0):.3g} mg/s around "
                        f"{s.get('noise_centre', 0):.3g})" if s.get("mdot_min_mode") == "auto"
                        else ""))
        lines.append(f"    threshold corr.  = {'on' if s.get('correct_threshold') else 'off (paper)'}")
        unit = "points" if str(s.get("groups", "")).startswith("points") else "sweeps"
        lines.append("    uncertainties    = " + (
            f"{s.get('n_boot')} half-samples of {s.get('n_groups', 0)} {unit} (whole pipeline)"
            if s.get("n_boot", 0) and s.get("n_boot") > 1 else
            f"stage 2 only: sandwich clustered by {unit} (no bootstrap)"))
        lines.append("[[Fit statistics]]")
        lines.append(f"    data points      = {m['n']}   (open {m['n_open']}, stage-2 points "
                     f"{m['n_fit']})")
        lines.append(f"    misclassified    = {m['misclassified']} ({100 * m['misclassified_frac']:.2f} %), "
                     f"largest distance from the plane {m['misclassified_max_kPa']:.3g} kPa (in p_ctrl)")
        lines.append(f"    RMSE flow        = {m['rmse']:.4g} mg/s all, {m['rmse_open']:.4g} mg/s open "
                     f"(max flow {m['max_flow']:.4g} mg/s)")
        lines.append(f"    RMSE 1/R         = {m['rmse_inv_r']:.4g} mg/(s·kPa) "
                     f"(max 1/R {m['max_inv_r']:.4g})")
        lines.append("[[Variables]]")
        for k in NAMES:
            v, e = getattr(self.params, k), self.stderr[k]
            lo, hi = self.ci95[k]
            rel = f"({100 * e / abs(v):.2f}%)" if v else ""
            unit = VALVE_PARAMETERS[k][0]
            stage = "stage 1" if k in STAGE1 else "stage 2"
            if not math.isfinite(e):
                lines.append(f"    {k:<7}= {v:<11.5g} +/- not computed (needs --bootstrap 2 or "
                             f"more)    {unit:<9} {stage}")
                continue
            lines.append(f"    {k:<7}= {v:<11.5g} +/- {e:<10.3g} {rel:<9} 95% CI "
                         f"[{lo:.5g}, {hi:.5g}] {unit:<9} {stage}")
        corr = self.correlations()
        pairs = [(a, b, corr.loc[a, b]) for i, a in enumerate(NAMES) for b in NAMES[i + 1:]
                 if abs(corr.loc[a, b]) > 0.5]
        if pairs:
            lines.append("[[Correlations]] (|r| > 0.5)")
            for a, b, r in sorted(pairs, key=lambda t: -abs(t[2])):
                lines.append(f"    C({a}, {b}) = {r:+.3f}")
        if self.measurements is not None and len(self.measurements.excluded):
            lines.append("[[Data]]")
            lines.append("    " + self.measurements.summary().replace("\n", "\n    "))
        return "\n".join(lines)

    def correlations(self) -> pd.DataFrame:
        sd = np.sqrt(np.clip(np.diag(self.covariance.to_numpy()), 1e-300, None))
        return self.covariance / np.outer(sd, sd)


def _finite_or_none(x):
    """A float for JSON: None where not computed (NaN) or unbounded (inf)."""
    return float(x) if math.isfinite(x) else None


# --------------------------------------------------------------------------- driver
def _labels(mdot, mdot_min):
    return np.where(mdot > mdot_min, 1, -1)


#: the largest SVM slack weight accepted, kPa^-2
MAX_C = 1000.0


def fit_valve(data, *, mdot_min=1.0, C=0.1, correct_threshold=True, n_boot=100, seed=0,
              groups="auto", **load_options) -> ValveFit:
    """Identify the six parameters from static measurements (two stages, eqs. 20–24).

    Parameters
    ----------
    data : Measurements, DataFrame or path
        Canonical columns; DataFrames and paths go through :func:`load_measurements`
        (``load_options`` are passed on).
    mdot_min : float or "auto"
        Flow threshold (mg/s) between closed and open (paper: 1); ``"auto"`` takes
        it from the noise of the closed points (:func:`auto_mdot_min`).
    C : float
        SVM slack weight in kPa⁻² (paper: 0.1).
    correct_threshold : bool
        Correct stage 1 for the flow threshold (module docstring); False is the
        paper's procedure.
    n_boot : int
        Block-bootstrap replicates for the uncertainties (0: stage 2 only, by the
        cluster-robust sandwich).
    seed : int
        Seed of the bootstrap.
    groups : "auto", None, str or array
        Resampling unit of the uncertainties: ``"auto"`` the sweeps
        (:func:`sweep_groups`), a column name, one label per point, or None for
        independent points (the pre-0.x behaviour, optimistic on real sweeps).
    """
    frame, measurements = as_frame(data, **load_options)
    missing = [c for c in PRESSURES + ("mdot_mg_s",) if c not in frame]
    if missing:
        raise DataError(f"data lacks column(s) {missing}")
    if len(frame) < 10:
        raise DataError(f"only {len(frame)} points: too few to identify six parameters")
    if not 0 < C <= MAX_C:
        raise ParameterError(f"C must lie in (0, {MAX_C:g}] kPa^-2, got {C}",
                             hint="the SVM's time grows with C: 1000 takes ~15 s, inf never "
                                  "ends; the default 0.1 is the paper's")
    mdot = frame["mdot_mg_s"].to_numpy(float)
    X = frame[list(PRESSURES)].to_numpy(float)
    settings = {"C": C, "correct_threshold": bool(correct_threshold), "n_boot": n_boot,
                "seed": seed}
    if groups is None:
        group = np.arange(len(frame))
    elif isinstance(groups, str) and groups == "auto":
        group = sweep_groups(frame)
    elif isinstance(groups, str):
        if groups not in frame:
            raise DataError(f"groups={groups!r}: no such column")
        group = pd.factorize(frame[groups])[0]
    else:
        group = pd.factorize(np.asarray(groups))[0]
        if len(group) != len(frame):
            raise ParameterError(f"groups has {len(group)} labels for {len(frame)} points")
    settings["groups"] = "points" if groups is None else (
        groups if isinstance(groups, str) else "given")
    if groups is not None and len(group) and group.max() + 1 < 10:
        # too few groups to resample: fall back to independent points, and say so
        group = np.arange(len(frame))
        settings["groups"] = "points (fewer than 10 sweeps)"
    settings["n_groups"] = int(group.max()) + 1 if len(group) else 0
    if isinstance(mdot_min, str):
        if mdot_min != "auto":
            raise ParameterError(f"mdot_min must be a number or 'auto', got {mdot_min!r}")
        mdot_min, centre, sigma = auto_mdot_min(mdot)
        settings.update(mdot_min_mode="auto", noise_centre=centre, noise_sigma=sigma)
    else:
        mdot_min = float(mdot_min)
        settings["mdot_min_mode"] = "given"
    settings["mdot_min"] = mdot_min
    y = _labels(mdot, mdot_min)
    inv_r = inverse_resistance(frame)
    s_root = np.sqrt(np.maximum(X[:, 0] ** 2 - X[:, 1] ** 2, 0.0))

    # stage 1 (paper), stage 2
    shift = np.zeros(len(frame))
    usable = np.ones(len(frame), dtype=bool)
    w, b = separate(X, y, C)
    ain, aout, pclose = plane_to_params(w, b)
    Rf, ptrans, e, _ = _stage2_fit(X, inv_r, ain, aout, pclose)
    if correct_threshold:
        # iterate with the smoothed SVM (fast), then one exact SVM on the final shift
        for _ in range(8):
            shift, usable = _threshold_shift(s_root, mdot_min, Rf, pclose, ptrans, e)
            Xs = X.copy()
            Xs[:, 2] += shift
            ws, bs = smooth_svm(Xs[usable], y[usable], C, start=(w, b))
            new = plane_to_params(ws, bs)
            Rf, ptrans, e, _ = _stage2_fit(X, inv_r, *new, start=(Rf, ptrans, e))
            converged = max(abs(new[0] - ain), abs(new[1] - aout)) < 1e-5 and abs(
                new[2] - pclose) < 1e-3
            ain, aout, pclose = new
            if converged:
                break
        shift, usable = _threshold_shift(s_root, mdot_min, Rf, pclose, ptrans, e)
        Xs = X.copy()
        Xs[:, 2] += shift
        w, b = separate(Xs[usable], y[usable], C)
        ain, aout, pclose = plane_to_params(w, b)
        Rf, ptrans, e, _ = _stage2_fit(X, inv_r, ain, aout, pclose, start=(Rf, ptrans, e))
    Xs = X.copy()
    Xs[:, 2] += shift
    try:
        params = ValveParams(Rf=Rf, pclose=pclose, ptrans=ptrans, e=e, ain=ain, aout=aout)
    except ParameterError as exc:
        raise DataError(f"the identified parameters are not a valid valve: {exc.message}",
                        hint="check units (absolute kPa, mg/s) and that the data spans closed "
                             "and fully open states") from None

    # uncertainties
    dp = delta_p(frame, ain, aout)
    fitted = (dp > pclose) & np.isfinite(inv_r)
    G = _stage2_sensitivity(X, inv_r, (ain, aout, pclose), (Rf, ptrans, e))
    model, J = _stage2_jacobian(dp[fitted], Rf, pclose, ptrans, e)
    cov2 = _stage2_cov(dp[fitted], inv_r[fitted], Rf, pclose, ptrans, e, group[fitted])
    order1 = [NAMES.index(k) for k in STAGE1]
    order2 = [NAMES.index(k) for k in STAGE2]
    replicates = _block_bootstrap(Xs[usable], y[usable], C, w, b,
                                  (group[usable], group[fitted]),
                                  (J, model - inv_r[fitted], group[fitted]), G, n_boot, seed)
    cov = np.zeros((6, 6))
    if len(replicates) >= 2:
        cov = np.cov(replicates.T)
        # the stage-2 variances: not below the sandwich + delta-method ones (a bootstrap
        # of ~100 replicates scatters by ~7 % in standard error)
        analytic = np.diag(cov2 + G @ cov[np.ix_(order1, order1)] @ G.T)
        boot = np.diag(cov)[order2]
        scale = np.sqrt(np.maximum(analytic / np.where(boot > 0, boot, np.inf), 1.0))
        scale = np.where(boot > 0, scale, 1.0)
        full = np.ones(6)
        full[order2] = scale
        cov = cov * np.outer(full, full)
        for k, i in enumerate(order2):
            if boot[k] <= 0:
                cov[i, i] = analytic[k]
    else:  # no resampling: stage 1 has no uncertainty estimate (NaN: "not computed")
        cov[np.ix_(order2, order2)] = cov2
        cov[order1, :] = np.nan
        cov[:, order1] = np.nan
    covariance = pd.DataFrame(cov, index=list(NAMES), columns=list(NAMES))
    stderr = {k: float(math.sqrt(max(cov[i, i], 0.0))) if np.isfinite(cov[i, i]) else math.nan
              for i, k in enumerate(NAMES)}
    ci95 = {k: (getattr(params, k) - Z95 * stderr[k], getattr(params, k) + Z95 * stderr[k])
            for k in NAMES}

    # figures of merit
    f = Xs @ w + b
    misclassified = np.zeros(len(frame), dtype=bool)
    misclassified[usable] = (np.sign(f[usable]) != y[usable])
    from ....physics.laws import valve_flow

    pred = valve_flow(X[:, 0], X[:, 1], X[:, 2], **params.as_dict())
    is_open = y > 0
    pred_inv_r = _conductance(dp, Rf, pclose, ptrans, e)
    metrics = {
        "n": int(len(frame)),
        "n_open": int(is_open.sum()),
        "n_fit": int(fitted.sum()),
        "misclassified": int(misclassified.sum()),
        "misclassified_frac": float(misclassified.mean()),
        "misclassified_max_kPa": float(np.max(np.abs(f[misclassified] / w[2])))
        if misclassified.any() else 0.0,
        "rmse": float(np.sqrt(np.mean((pred - mdot) ** 2))),
        "rmse_open": float(np.sqrt(np.mean((pred[is_open] - mdot[is_open]) ** 2)))
        if is_open.any() else float("nan"),
        "rmse_inv_r": float(np.sqrt(np.mean((pred_inv_r[fitted] - inv_r[fitted]) ** 2))),
        "max_flow": float(np.max(mdot)),
        "max_inv_r": float(np.nanmax(inv_r)),
    }
    return ValveFit(params=params, stderr=stderr, ci95=ci95, metrics=metrics, open=is_open,
                    misclassified=misclassified, fitted=fitted, frame=frame,
                    mdot_min=mdot_min, C=C, covariance=covariance, settings=settings,
                    measurements=measurements, plane=(w, b))


def _stage2_fit(X, inv_r, ain, aout, pclose, start=None):
    from ....physics.laws import valve_delta_p

    dp = valve_delta_p(X[:, 0], X[:, 1], X[:, 2], ain, aout)
    use = (dp > pclose) & np.isfinite(inv_r)
    if use.sum() < 5:
        raise DataError(f"only {int(use.sum())} points with an open valve (Δp > p_close): "
                        "too few for stage 2",
                        hint="the protocol must lower p_ctrl far enough to open the valve fully")
    return _stage2(dp[use], inv_r[use], pclose, start)


def _threshold_shift(s_root, mdot_min, Rf, pclose, ptrans, e):
    """δ_i: how far above p_close point i must be for its flow to exceed ṁ_min."""
    m = np.where(s_root > 0, mdot_min * Rf / np.where(s_root > 0, s_root, 1.0), np.inf)
    usable = m < 0.999
    if mdot_min <= 0:
        return np.zeros_like(s_root), usable | True
    ms = np.where(usable, m, 0.5)
    u = (ms / np.sqrt(1.0 - ms * ms)) ** (1.0 / e)
    return np.where(usable, (ptrans - pclose) * u, 0.0), usable


def _block_bootstrap(X, y, C, w, b, groups, stage2, G, n_boot, seed, window_margin=3.0):
    """Replicates of all six parameters: linearised half-sampling of the groups.

    Each replicate keeps a random half of the groups (sweeps) with weight 2 — the
    delete-d jackknife with d = n/2 (Shao & Wu 1989), whose variance is the spread of
    the half-sample estimates times r/d (≈ 1).  Unlike the ordinary bootstrap or the
    delete-1 jackknife it stays consistent for non-smooth estimators; the SVM stage
    is one (its solution hinges on the few points in the margin), and on bench data
    a Poisson bootstrap of it under-estimated the boundary error at high pressure by
    ~25 % in variance.  Stage 1: the soft-margin problem re-solved with the weights
    (smoothed hinge, warm start) on the points near the boundary (``X, y``: the
    stage-1 points, group labels ``groups[0]``).  Stage 2: one weighted Gauss–Newton
    step from the full-data solution with the same weights (``stage2 = (J, r, _)`` of
    the stage-2 points, labels ``groups[1]``) plus ``G`` times the change of the
    stage-1 parameters.  The replicates use a wider smoothing of the hinge (0.2 margin
    units, same spread, 2.5× faster Newton solves).  Returns an (m × 6) array in the order of ``NAMES``, already
    scaled so that its covariance is the variance estimate (m ≤ n_boot).
    """
    g1, g2 = groups
    J, r, _ = stage2
    f = X @ w + b
    near = (np.abs(f) <= window_margin) | (y * f < 1.0)
    Xn, yn, gn = X[near], y[near], g1[near]
    if len(np.unique(yn)) < 2:
        return np.empty((0, 6))
    n_groups = int(max(g1.max(initial=-1), g2.max(initial=-1))) + 1
    base1 = np.array(plane_to_params(w, b))
    rng = np.random.default_rng(seed)
    kept = n_groups - n_groups // 2
    out = []
    for _ in range(n_boot):
        cluster = np.zeros(n_groups)
        cluster[rng.permutation(n_groups)[:kept]] = n_groups / kept
        weights = cluster[gn]
        keep = weights > 0
        if len(np.unique(yn[keep])) < 2:
            continue
        wb, bb = smooth_svm(Xn[keep], yn[keep], C, sample_weight=weights[keep], start=(w, b),
                            eps=0.2)
        if wb[2] >= 0:
            continue
        p1 = np.array(plane_to_params(wb, bb))
        c2 = cluster[g2]
        A = J.T @ (J * c2[:, None])
        try:
            step = -np.linalg.solve(A, J.T @ (c2 * r))
        except np.linalg.LinAlgError:
            continue
        p2 = step + G @ (p1 - base1)
        out.append([p2[0], p1[2], p2[1], p2[2], p1[0], p1[1]])  # NAMES order
    # delete-d jackknife: the spread of half-samples, times r/d, estimates the variance
    factor = math.sqrt(kept / max(n_groups - kept, 1))
    out = np.asarray(out).reshape(-1, 6)
    if len(out) < 2:
        return out
    return out.mean(axis=0) + factor * (out - out.mean(axis=0))


def _stage2_sensitivity(X, inv_r, stage1, stage2):
    """G = ∂(Rf, ptrans, e)/∂(ain, aout, pclose) by re-solving stage 2 (central diff.)."""
    steps = (1e-3, 1e-3, 0.2)
    G = np.zeros((3, 3))
    for k, h in enumerate(steps):
        values = []
        for sign in (+1, -1):
            p1 = list(stage1)
            p1[k] += sign * h
            Rf, ptrans, e, _ = _stage2_fit(X, inv_r, *p1, start=stage2)
            values.append(np.array([Rf, ptrans, e]))
        G[:, k] = (values[0] - values[1]) / (2 * h)
    return G
