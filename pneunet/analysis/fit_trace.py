"""Fit a circuit to a recorded transient (docs DATA-FORMAT, "Transient circuit recordings").

Least squares through the simulator: the unknown parameters (e.g. the hand-set ball
valves R_out and R_vent and the volume V of the oscillator) are varied in log space
within bounds until the simulated signals match the recorded ones at the recorded
times.  Reported: estimates with confidence intervals (linearised, from the Jacobian
and the residual variance, Student t), residuals over time and over the oscillation
phase, and the period error.

Circuit-level effects are offered as candidates in the same way as the valve diagnosis
offers valve effects (:func:`rank_effects`): a polytropic volume (exponent n between 1,
isothermal, and 1.4, adiabatic: the volume exchanges only part of its compression heat),
a tubing dead volume at the valve output, and a tubing resistance between the volume and
the node it is sensed at.  Each candidate is fitted together with the base parameters on
the first cycles of the record and ranked by its error on the later cycles (held out).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import DataError, ParameterError, PneunetError


# -- data -----------------------------------------------------------------------------------
def read_trace(path_or_frame, signals=None):
    """A recorded transient as a DataFrame: ``time_s`` then ``p_<node>_kPa`` /
    ``mdot_<element>_mg_s`` columns; ``#`` lines are comments.  Checks the columns."""
    import pandas as pd

    if isinstance(path_or_frame, pd.DataFrame):
        df = path_or_frame.copy()
        where = "trace"
    else:
        where = str(path_or_frame)
        if not Path(where).exists():
            raise DataError(f"no such file: {where}")
        df = pd.read_csv(where, comment="#")
    if "time_s" not in df.columns:
        raise DataError("a transient recording needs a time_s column", where=where,
                        hint="columns: " + ", ".join(map(str, df.columns)))
    cols = [c for c in df.columns if c != "time_s"]
    known = [c for c in cols if (c.startswith("p_") and c.endswith("_kPa"))
             or (c.startswith("mdot_") and c.endswith("_mg_s"))]
    if not known:
        raise DataError("no signal columns named p_<node>_kPa or mdot_<element>_mg_s", where=where)
    if signals:
        missing = [s for s in signals if s not in df.columns]
        if missing:
            raise DataError(f"signal {missing[0]} not in the recording", where=where,
                            hint="columns: " + ", ".join(known))
        known = list(signals)
    df = df[["time_s"] + known].dropna()
    t = df["time_s"].to_numpy()
    if len(t) < 5 or np.any(np.diff(t) <= 0):
        raise DataError("time_s must increase strictly and have at least 5 rows", where=where)
    return df.reset_index(drop=True)


def signal_of_column(col: str) -> str:
    """``p_tank_kPa`` → ``p_tank`` (the Solution signal name)."""
    if col.endswith("_kPa"):
        return col[:-4]
    if col.endswith("_mg_s"):
        return col[:-5]
    return col


# -- effects -------------------------------------------------------------------------------
@dataclass(frozen=True)
class CircuitEffect:
    """A circuit-level effect: extra parameters (name → (guess, low, high)) and how to
    add it to a built circuit (``apply(circuit, values)``, in place)."""

    name: str
    description: str
    params: dict
    apply: Callable

    def __repr__(self):
        return f"CircuitEffect({self.name!r})"


def _polytropic(circuit, values):
    for spec in circuit.elements.values():
        if spec.kind in ("volume", "actuator") and spec.name not in ("Vdead",):
            spec.params["n"] = float(values["n"])


def _dead_volume(circuit, values):
    nodes = [s.nodes[1] for s in circuit.elements.values() if s.kind == "valve"]
    stored = {s.nodes[0] for s in circuit.elements.values() if s.kind in ("volume", "actuator")}
    for i, node in enumerate(n for n in dict.fromkeys(nodes) if n not in stored):
        circuit.volume(f"Vdead{i}" if i else "Vdead", node, V=float(values["V_dead"]))


def _tube_resistance(circuit, values):
    vols = [s for s in circuit.elements.values() if s.kind in ("volume", "actuator")]
    for spec in vols:
        node = spec.nodes[0]
        inner = f"{node}__vessel"
        spec.nodes = (inner,)
        circuit.resistor(f"Rtube_{spec.name}", node, inner, R=float(values["R_tube"]))


POLYTROPIC = CircuitEffect("polytropic_volume",
                           "volumes compress polytropically, 1 ≤ n ≤ 1.4 (partial heat exchange)",
                           {"n": (1.2, 1.0, 1.4)}, _polytropic)
DEAD_VOLUME = CircuitEffect("tubing_dead_volume",
                            "tubing volume at each valve output without a volume (mL)",
                            {"V_dead": (5.0, 0.01, 100.0)}, _dead_volume)
TUBE_RESISTANCE = CircuitEffect("tubing_resistance",
                                "a tube (quadrature resistor) between each volume and its node",
                                {"R_tube": (0.3, 0.005, 5.0)}, _tube_resistance)
CANDIDATES = (POLYTROPIC, DEAD_VOLUME, TUBE_RESISTANCE)


# -- simulation wrapper --------------------------------------------------------------------
class TraceModel:
    """Simulate ``build(point)`` (+ effects) and sample its signals at given times."""

    def __init__(self, build: Callable, fixed: dict | None = None, effects=(), start: str = "ic",
                 options: dict | None = None):
        self.build, self.fixed, self.effects, self.start = build, dict(fixed or {}), tuple(effects), start
        self.options = dict(options or {})
        self.calls = 0

    def circuit(self, values: dict):
        from .sweep import apply_overrides

        point = dict(self.fixed)
        point.update({k: v for k, v in values.items() if not self._effect_param(k)})
        c = self.build(point)
        apply_overrides(c, point)
        for eff in self.effects:
            eff.apply(c, {k: values.get(k, eff.params[k][0]) for k in eff.params})
        if self.options:
            c.options = c.options.replace(**self.options)
        return c

    def _effect_param(self, name):
        return any(name in e.params for e in self.effects)

    def simulate(self, values: dict, t_end: float, t_step: float | None = None):
        self.calls += 1
        return self.circuit(values).tran(t_end, t_step=t_step, start=self.start)

    def sample(self, values: dict, times, signals):
        # output at the sample spacing: IDA interpolates its own polynomial there, which
        # is smooth in the parameters (linear interpolation between internal steps is not,
        # and makes finite-difference Jacobians noisy)
        dt = float(np.median(np.diff(times))) if len(times) > 1 else None
        sol = self.simulate(values, float(times[-1]), dt)
        return {s: _sample(sol.t, sol[s], times) for s in signals}, sol


def _sample(t, y, times):
    # the solution stores the states before and after a branch jump at the same time;
    # np.interp needs increasing abscissae: nudge duplicates
    t = np.array(t, dtype=float)
    dup = np.nonzero(np.diff(t) <= 0)[0]
    if dup.size:
        t[dup + 1] = t[dup] + 1e-12 * np.maximum(1.0, np.abs(t[dup]))
        t = np.maximum.accumulate(t)
    return np.interp(times, t, y)


# -- fit ---------------------------------------------------------------------------------
@dataclass
class TraceFit:
    """Result of :func:`fit_trace`.

    ``values``, ``ci`` ({name: (low, high)}), ``stderr_log`` (standard error of ln value),
    ``rmse`` per signal and overall (kPa or mg/s) in the fitted window, ``residuals``
    (DataFrame: time, phase, one column per signal), ``phase_rms`` (DataFrame: phase bin
    centre, rms per signal), ``period_measured``/``period_simulated``/``period_error``
    (s, at ``node``), ``solution`` (simulation with the estimates over the whole record).
    """

    values: dict
    ci: dict
    stderr_log: dict
    rmse: dict
    residuals: object
    phase_rms: object
    period_measured: float
    period_simulated: float
    period_error: float
    sigma: float
    nfev: int
    success: bool
    message: str
    effects: tuple = ()
    solution: object = None
    wall_time_s: float = 0.0
    extras: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"values": self.values, "ci": {k: list(v) for k, v in self.ci.items()},
                "rmse": self.rmse, "period_measured": self.period_measured,
                "period_simulated": self.period_simulated, "period_error": self.period_error,
                "sigma": self.sigma, "nfev": self.nfev, "success": self.success,
                "message": self.message, "effects": [e.name for e in self.effects],
                "wall_time_s": self.wall_time_s, **self.extras}

    def report(self) -> str:
        lines = ["parameter        estimate      95 % CI"]
        for k, v in self.values.items():
            lo, hi = self.ci[k]
            lines.append(f"  {k:<14} {v:>10.5g}   [{lo:.5g}, {hi:.5g}]")
        lines.append("rms residual: " + ", ".join(f"{k} {v:.3g}" for k, v in self.rmse.items()))
        if math.isfinite(self.period_error):
            lines.append(f"period: measured {self.period_measured:.4g} s, simulated "
                         f"{self.period_simulated:.4g} s, error {self.period_error:+.3g} s")
        return "\n".join(lines)


def _phase(t, y, level=None):
    """Oscillation phase in [0, 1) of each time from the rising crossings of ``y``."""
    from .oscillation import _rising_crossings

    if level is None:
        level = 0.5 * (np.min(y) + np.max(y))
    rises = _rising_crossings(np.asarray(t), np.asarray(y), level)
    phase = np.full(len(t), np.nan)
    for a, b in zip(rises[:-1], rises[1:]):
        inside = (t >= a) & (t < b)
        phase[inside] = (t[inside] - a) / (b - a)
    return phase


#: simulator settings of the fit's simulations: the Jacobian is taken by finite differences
#: with a relative parameter step of ``diff_step`` (1e-3 in ln value), so the simulator's
#: own error must be far smaller than the response to a 0.1 % change (rtol 1e-5 moves
#: sampled tank pressures by up to 0.2 kPa near the folds; 1e-7 by < 2e-3 kPa)
FIT_OPTIONS = {"rtol": 1e-7, "atol": 1e-6}


def fit_trace(build: Callable, data, params: dict, *, fixed: dict | None = None, signals=None,
              node: str | None = None, window=None, effects=(), max_nfev: int = 40,
              confidence: float = 0.95, phase_bins: int = 20, start: str = "ic",
              features: bool = True, diff_step: float = 1e-3, options: dict | None = None,
              lags: int | None = None) -> TraceFit:
    """Estimate ``params`` ({name: (guess, low, high)}) so the circuit reproduces ``data``.

    ``build(point) -> Circuit`` (or a :class:`~pneunet.analysis.sweep.NetlistBuilder`)
    with ``fixed`` values for the other parameters; ``signals``: recorded columns to fit
    (default: all); ``node``: the node whose period is compared (default: the first
    pressure signal); ``window`` = (t0, t1) restricts the fitted samples; ``effects``:
    circuit effects added (their parameters may appear in ``params``); ``options``:
    simulator options of the fit's simulations (default :data:`FIT_OPTIONS`);
    ``max_nfev``: cap on the simulations of the least-squares stage (Jacobian included).

    Two stages.  With ``features`` and an oscillating record at ``node``, the starting
    values come from the cycle (:func:`initial_values`): for an oscillator the circuit
    recognises (:func:`~pneunet.analysis.branches.spec_from_circuit`), R_out from the
    recorded p_min/p_max (the turning points of the stationary branches depend on R_out
    alone), R_vent from the rise fraction (a quadrature along the branches), V from the
    period (time scales with V); otherwise a least-squares fit to the cycle features.
    A trace fit alone gets stuck when the guessed period is off by more than a few per
    cent, because the simulated and recorded cycles drift out of phase.  Then
    Levenberg–Marquardt on the samples in ln-parameters (forward differences with
    ``diff_step``).

    Confidence intervals: the residuals of a sampled oscillation are autocorrelated
    (and carry model error), so the covariance of the ln-parameters is the sandwich
    (JᵀJ)⁻¹ S (JᵀJ)⁻¹ with S the Newey–West (Bartlett) estimate of the score covariance
    over ``lags`` samples (default: where the residual autocorrelation first falls
    below 0.1, at least the Newey–West rule 4(n/100)^(2/9)); Student t with the
    effective degrees of freedom n·(1−ρ₁)/(1+ρ₁); the standard errors are never
    taken below the white-noise ones s²(JᵀJ)⁻¹.
    """
    from scipy import optimize, stats

    wall = time.perf_counter()
    df = read_trace(data, signals)
    cols = [c for c in df.columns if c != "time_s"]
    sigs = [signal_of_column(c) for c in cols]
    times = df["time_s"].to_numpy()
    meas = {s: df[c].to_numpy() for s, c in zip(sigs, cols)}
    mask = np.ones(len(times), bool)
    if window is not None:
        mask = (times >= window[0]) & (times <= window[1])
    if mask.sum() < 5:
        raise DataError("fewer than 5 samples in the fit window")
    names = list(params)
    for k in names:
        g, lo, hi = params[k]
        if not 0 < lo <= g <= hi:
            raise ParameterError(f"fit parameter {k}: need 0 < low ≤ guess ≤ high, got {params[k]}")
    model = TraceModel(build, fixed, effects, start, FIT_OPTIONS if options is None else options)
    x0 = np.log([params[k][0] for k in names])
    lb = np.log([params[k][1] for k in names])
    ub = np.log([params[k][2] for k in names])
    t_fit = times[mask]
    # scale each signal by its range so pressures and flows weigh alike
    scales = {s: max(np.ptp(meas[s][mask]), 1e-9) / 100.0 for s in sigs}
    failures = []

    def residual(x):
        values = dict(zip(names, np.exp(x)))
        try:
            sim, _ = model.sample(values, t_fit, sigs)
        except PneunetError as err:
            failures.append(str(err))
            return np.full(len(t_fit) * len(sigs), 1e3)
        return np.concatenate([(sim[s] - meas[s][mask]) / scales[s] for s in sigs])

    node = node or next((s[2:] for s in sigs if s.startswith("p_")), None)
    stage1 = None
    if features and node and f"p_{node}" in meas:
        try:
            x0, stage1 = initial_values(model, names, x0, lb, ub, t_fit, meas[f"p_{node}"][mask],
                                        node)
        except PneunetError as err:
            stage1 = {"method": "none", "error": str(err)}
        if stage1 is None or stage1.get("method") == "none":
            x0, stage1 = _feature_fit(model, names, x0, lb, ub, t_fit, meas[f"p_{node}"][mask],
                                      node, max_nfev)
    # Levenberg-Marquardt (better in the long Rvent-V valley than trf); the bounds are
    # kept by clipping inside the residual
    # forward differences in ln-parameters with a step (diff_step) far above the
    # simulator's error; stepping backwards at an upper bound.  max_nfev caps the
    # simulations of this stage, Jacobian columns included.
    cache = {}

    def fun(x):
        r = residual(np.clip(x, lb, ub))
        cache["x"], cache["f"] = np.array(x), r
        return r

    def jac(x):
        f0 = cache["f"] if "x" in cache and np.array_equal(cache["x"], x) else fun(x)
        xc = np.clip(x, lb, ub)
        J = np.empty((f0.size, len(x)))
        for i in range(len(x)):
            h = diff_step if xc[i] + diff_step <= ub[i] else -diff_step
            xi = xc.copy()
            xi[i] += h
            J[:, i] = (residual(xi) - f0) / h
        return J

    res = optimize.least_squares(fun, np.clip(x0, lb, ub), jac=jac,
                                 max_nfev=max(2, max_nfev // (len(names) + 1)), method="lm",
                                 xtol=1e-6, ftol=1e-8)
    res.x = np.clip(res.x, lb, ub)
    res.nfev = model.calls
    est = dict(zip(names, np.exp(res.x)))
    n, p = res.fun.size, len(names)
    cov, info = _sandwich(res.jac, res.fun, len(sigs), lags)
    s2 = 2 * res.cost / max(n - p, 1)
    se_naive = np.sqrt(np.maximum(np.diag(s2 * np.linalg.pinv(res.jac.T @ res.jac)), 0))
    # never narrower than the white-noise interval (a few cycles estimate S poorly)
    se = np.maximum(np.sqrt(np.maximum(np.diag(cov), 0)), se_naive)
    dof = max(info["dof_eff"] - p, 1.0)
    tq = stats.t.ppf(0.5 + confidence / 2, dof)
    ci = {k: (float(np.exp(res.x[i] - tq * se[i])), float(np.exp(res.x[i] + tq * se[i])))
          for i, k in enumerate(names)}
    # residuals over the whole record with the estimates
    sim, sol = model.sample(est, times, sigs)
    ref = meas[f"p_{node}"] if node and f"p_{node}" in meas else meas[sigs[0]]
    phase = _phase(times, ref)
    import pandas as pd

    resid = pd.DataFrame({"time_s": times, "phase": phase, "fitted": mask,
                          **{s: sim[s] - meas[s] for s in sigs}})
    rmse = {s: float(np.sqrt(np.mean((sim[s] - meas[s])[mask] ** 2))) for s in sigs}
    bins = np.linspace(0, 1, phase_bins + 1)
    centre = 0.5 * (bins[1:] + bins[:-1])
    rows = {"phase": centre}
    idx = np.digitize(phase, bins) - 1
    for s in sigs:
        r = resid[s].to_numpy()
        rows[s] = [float(np.sqrt(np.mean(r[(idx == i) & mask] ** 2))) if np.any((idx == i) & mask)
                   else float("nan") for i in range(phase_bins)]
    phase_rms = pd.DataFrame(rows)
    pm, ps, perr = _period_error(times, ref, sol, node, mask)
    return TraceFit(est, ci, dict(zip(names, map(float, se))), rmse, resid, phase_rms, pm, ps,
                    perr, float(math.sqrt(s2)), int(res.nfev), bool(res.success),
                    str(res.message) + (f"; {len(failures)} failed simulations" if failures else ""),
                    tuple(effects), sol, time.perf_counter() - wall,
                    {"stage1": stage1, "simulations": model.calls, "covariance": info,
                     "stderr_log_iid": dict(zip(names, map(float, se_naive)))})


def _sandwich(J, r, nsig: int = 1, lags: int | None = None):
    """Newey–West sandwich covariance of the ln-parameters (see :func:`fit_trace`).

    ``J`` (n×p) and ``r`` (n) stack ``nsig`` signals of equal length one after the other;
    lags never cross from one signal to the next."""
    n, p = J.shape
    m = n // max(nsig, 1)
    rs = r.reshape(nsig, m) if nsig > 1 and m * nsig == n else r.reshape(1, -1)
    Js = J.reshape(rs.shape[0], rs.shape[1], p)
    # residual autocorrelation (pooled over signals)
    rc = rs - rs.mean(axis=1, keepdims=True)
    var = float(np.sum(rc * rc))
    maxlag = max(1, rs.shape[1] // 4)
    acf = np.array([np.sum(rc[:, l:] * rc[:, :rs.shape[1] - l]) / var if var > 0 else 0.0
                    for l in range(maxlag + 1)])
    rho1 = float(np.clip(acf[1], -0.99, 0.99)) if len(acf) > 1 else 0.0
    if lags is None:
        below = np.nonzero(np.abs(acf) < 0.1)[0]
        first = int(below[0]) if below.size else maxlag
        lags = int(min(maxlag, max(first, math.floor(4 * (rs.shape[1] / 100) ** (2 / 9)))))
    g = Js * rs[:, :, None]  # scores per sample
    S = np.einsum("kti,ktj->ij", g, g)
    for l in range(1, lags + 1):
        w = 1 - l / (lags + 1)
        G = np.einsum("kti,ktj->ij", g[:, l:], g[:, :-l])
        S += w * (G + G.T)
    Hinv = np.linalg.pinv(J.T @ J)
    cov = Hinv @ S @ Hinv * n / max(n - p, 1)
    dof_eff = n * (1 - max(rho1, 0.0)) / (1 + max(rho1, 0.0))
    return cov, {"method": "newey-west", "lags": int(lags), "rho1": rho1,
                 "dof_eff": float(dof_eff), "n": int(n)}


# -- starting values from the cycle ----------------------------------------------------------
def cycle_features(t, y, levels=None):
    """Robust cycle features of a (noisy) sampled oscillation: period, p_min, p_max and
    rise fraction = t_up / (t_up + t_down), the times the signal takes to rise from
    ``levels[0]`` to ``levels[1]`` and to fall back (default: 25 % and 75 % of the
    range over the second half of the record); medians over the full cycles between rising crossings of the mid level.
    Crossing times are interpolated between samples, so the rise fraction is
    insensitive to noise; the extremes are the raw sample extremes (the relaxation
    cycle has corners there).  None if fewer than one full cycle."""
    from .oscillation import _rising_crossings

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if levels is None:
        half = t >= t[0] + 0.5 * (t[-1] - t[0])  # past the start-up transient
        lo_, hi_ = float(np.min(y[half])), float(np.max(y[half]))
        levels = (lo_ + 0.25 * (hi_ - lo_), lo_ + 0.75 * (hi_ - lo_))
    l1, l2 = levels
    rises = _rising_crossings(t, y, 0.5 * (l1 + l2))
    if len(rises) < 2:
        return None
    up1, up2 = _rising_crossings(t, y, l1), _rising_crossings(t, y, l2)
    dn2, dn1 = _rising_crossings(t, -y, -l2), _rising_crossings(t, -y, -l1)
    per, lo, hi, frac = [], [], [], []
    for a, b in zip(rises[:-1], rises[1:]):
        inside = (t >= a) & (t < b)
        # within [a, b): rise to l2, fall through l2 then l1, rise through l1
        u2 = up2[(up2 > a) & (up2 < b)]
        d2 = dn2[(dn2 > a) & (dn2 < b)]
        d1 = dn1[(dn1 > a) & (dn1 < b)]
        u1 = up1[(up1 > a) & (up1 < b)]
        if inside.sum() < 5 or not (len(u2) and len(d2) and len(d1) and len(u1)):
            continue
        t_up = (u2[0] - a) + (b - u1[-1])
        t_down = d1[-1] - d2[0]
        per.append(b - a)
        hi.append(np.max(y[inside]))
        lo.append(np.min(y[inside]))
        frac.append(t_up / (t_up + t_down))
    if not per:
        return None
    return {"period": float(np.median(per)), "p_min": float(np.median(lo)),
            "p_max": float(np.median(hi)), "rise_fraction": float(np.median(frac)),
            "levels": (float(l1), float(l2)), "cycles": len(per)}


def branch_rise_fraction(branches, Rvent: float, levels, points: int = 400) -> float:
    """Rise fraction (see :func:`cycle_features`) between ``levels`` of the oscillator's
    relaxation cycle, in the limit
    of vanishing dead volume, by quadrature along its stationary branches: the tank
    fills on the upper attracting branch from p_c,min to p_c,max and empties on the
    lower one (ṁ = 0 above the closure pressure), dt = C dp / (ṁ_branch − ṁ_vent);
    C (∝ V) cancels.  Independent of V."""
    from .branches import vent_flow

    pc, m, att = branches.p_c, branches.mdot, branches.attracting
    l1, l2 = max(levels[0], branches.p_c_min), min(levels[1], branches.p_c_max)
    if not l1 < l2:
        return float("nan")
    p = np.linspace(l1, l2, points + 1)
    p = 0.5 * (p[1:] + p[:-1])
    up = np.full(len(p), np.nan)
    low = np.full(len(p), np.nan)
    for i in range(len(pc) - 1):
        if not (att[i] and att[i + 1]) or pc[i] == pc[i + 1]:
            continue
        a, c = sorted((pc[i], pc[i + 1]))
        sel = (p >= a) & (p < c)
        if not sel.any():
            continue
        mm = m[i] + (m[i + 1] - m[i]) * (p[sel] - pc[i]) / (pc[i + 1] - pc[i])
        up[sel] = np.fmax(up[sel], mm)
        low[sel] = np.fmin(low[sel], mm)
    low[p >= branches.closed_from] = 0.0
    vent = vent_flow(p, branches.spec.pL, Rvent)
    fill, empty = up - vent, vent - low
    if np.any(~np.isfinite(fill) | ~np.isfinite(empty)) or np.any(fill <= 0) or np.any(empty <= 0):
        return float("nan")
    t_up, t_down = np.sum(1 / fill), np.sum(1 / empty)
    return float(t_up / (t_up + t_down))


def _roles(model, names, x):
    """Which fit parameter sets the oscillator's R_out, R_vent and V (by perturbation)."""
    from .branches import spec_from_circuit

    values = dict(zip(names, np.exp(x)))
    base = spec_from_circuit(model.circuit(values))
    roles = {}
    for i, k in enumerate(names):
        v = dict(values)
        v[k] = values[k] * 1.01
        s = spec_from_circuit(model.circuit(v))
        for field_ in ("Rout", "Rvent", "V"):
            a_, b_ = getattr(s, field_), getattr(base, field_)
            if field_ not in roles and math.isfinite(a_) and math.isfinite(b_) and a_ != b_:
                roles[field_] = i
    return roles, base


def initial_values(model, names, x0, lb, ub, t_fit, y_meas, node, iterations: int = 4):
    """Starting values for the oscillator's R_out, R_vent, V from the recorded cycle.

    R_out: the stationary-branch turning points (no simulation) match the recorded
    p_min/p_max; R_vent: the branch quadrature (:func:`branch_rise_fraction`) matches
    the rise fraction between 25 % and 75 % of the range; V: scaled by the period ratio (an isothermal tank's time scales
    with V).  One simulation per iteration measures the same features on the simulated
    trace; their offsets from the branch predictions (dead volumes, smoothing, the
    quadrature's idealisation) correct the targets.  Returns (x, info); info method
    'none' when the circuit is not a recognised oscillator or the record does not
    oscillate."""
    import dataclasses

    from scipy import optimize

    from .branches import stationary_branches

    target = cycle_features(t_fit, y_meas)
    if target is None:
        return x0, {"method": "none", "error": "no full cycle in the record"}
    roles, spec = _roles(model, names, x0)
    if not roles:
        return x0, {"method": "none", "error": "no fitted parameter sets R_out, R_vent or V"}
    x = np.array(x0, float)
    bias = {"p_min": 0.0, "p_max": 0.0, "rise_fraction": 0.0}
    history = []
    sim_f = None
    for it in range(iterations):
        values = dict(zip(names, np.exp(x)))
        spec = _roles(model, names, x)[1]
        if "Rout" in roles:
            i = roles["Rout"]
            scale = spec.Rout / math.exp(x[i])  # spec R_out per unit of the fitted parameter

            def miss(lr):
                try:
                    b = stationary_branches(dataclasses.replace(spec, Rout=scale * math.exp(lr)))
                except PneunetError:
                    return 1e6
                if b.regime != "oscillation":
                    return 1e6
                return ((b.p_c_min + bias["p_min"] - target["p_min"]) ** 2
                        + (b.p_c_max + bias["p_max"] - target["p_max"]) ** 2)

            r = optimize.minimize_scalar(miss, bounds=(lb[i], ub[i]), method="bounded",
                                         options={"xatol": 1e-4})
            x[i] = r.x
            spec = dataclasses.replace(spec, Rout=scale * math.exp(x[i]))
        b = stationary_branches(spec)
        if "Rvent" in roles and b.regime == "oscillation":
            i = roles["Rvent"]
            scale = spec.Rvent / math.exp(x[i])
            goal = target["rise_fraction"] - bias["rise_fraction"]

            def rmiss(lr):
                q = branch_rise_fraction(b, scale * math.exp(lr), target["levels"])
                return (q - goal) ** 2 if math.isfinite(q) else 1e6

            r = optimize.minimize_scalar(rmiss, bounds=(lb[i], ub[i]), method="bounded",
                                         options={"xatol": 1e-4})
            x[i] = r.x
            spec = dataclasses.replace(spec, Rvent=scale * math.exp(x[i]))
            b = stationary_branches(spec)
        values = dict(zip(names, np.exp(x)))
        try:
            sol = model.simulate(values, float(t_fit[-1]), float(np.median(np.diff(t_fit))))
            sim_f = cycle_features(t_fit, _sample(sol.t, sol.pressure(node), t_fit),
                                   target["levels"])
        except PneunetError:
            sim_f = None
        if sim_f is None:
            history.append({"values": {k: float(v) for k, v in values.items()}, "features": None})
            break
        history.append({"values": {k: float(v) for k, v in values.items()}, "features": sim_f})
        if b.regime == "oscillation":
            bias["p_min"] = sim_f["p_min"] - b.p_c_min
            bias["p_max"] = sim_f["p_max"] - b.p_c_max
            q = branch_rise_fraction(b, spec.Rvent, target["levels"])
            if math.isfinite(q):
                bias["rise_fraction"] = sim_f["rise_fraction"] - q
        ratio = target["period"] / sim_f["period"]
        if "V" in roles:
            x[roles["V"]] = float(np.clip(x[roles["V"]] + math.log(ratio), lb[roles["V"]],
                                          ub[roles["V"]]))
        close = (abs(ratio - 1) < 2e-3 and abs(sim_f["p_min"] - target["p_min"]) < 0.3
                 and abs(sim_f["p_max"] - target["p_max"]) < 0.3
                 and abs(sim_f["rise_fraction"] - target["rise_fraction"]) < 2e-3)
        if close:
            break
    return np.clip(x, lb, ub), {"method": "branches", "target": target, "history": history,
                                "roles": {k: names[i] for k, i in roles.items()},
                                "values": {k: float(v) for k, v in zip(names, np.exp(x))}}


def _features(t, y):
    from .oscillation import analyze_oscillation

    o = analyze_oscillation(t, y)
    if not o.oscillating:
        return None
    return np.array([o.period_s, o.p_min, o.p_max, o.rise_fraction])


def _feature_fit(model, names, x0, lb, ub, t_fit, y_meas, node, max_nfev):
    """Stage 1: match period, p_min, p_max and rise fraction of the recorded cycle."""
    from scipy import optimize

    target = _features(t_fit, y_meas)
    if target is None:
        return x0, None
    scale = np.array([0.01 * target[0], 0.01 * (target[2] - target[1]),
                      0.01 * (target[2] - target[1]), 0.01])

    def fres(x):
        try:
            sol = model.simulate(dict(zip(names, np.exp(x))), float(t_fit[-1]))
            inside = sol.t >= t_fit[0]
            f = _features(sol.t[inside], sol.pressure(node)[inside])
        except PneunetError:
            f = None
        if f is None:
            return np.full(4, 1e3)
        return (f - target) / scale

    r = optimize.least_squares(fres, x0, bounds=(lb, ub), diff_step=1e-2, max_nfev=max_nfev,
                               method="trf")
    return r.x, {"values": dict(zip(names, map(float, np.exp(r.x)))), "nfev": int(r.nfev),
                 "feature_residual": [float(v) for v in r.fun]}


def _period_error(times, ref, sol, node, mask):
    from .oscillation import analyze_oscillation

    w = mask
    try:
        m = analyze_oscillation(times[w], ref[w])
        sim_t = sol.t
        inside = (sim_t >= times[w][0]) & (sim_t <= times[w][-1])
        s = analyze_oscillation(sim_t[inside], sol.pressure(node)[inside]) if node else m
        if m.oscillating and s.oscillating:
            return m.period_s, s.period_s, s.period_s - m.period_s
        # short windows (one or two cycles): median period between rising crossings
        fm = cycle_features(times[w], ref[w])
        fs = cycle_features(sim_t[inside], sol.pressure(node)[inside],
                            fm["levels"] if fm else None) if node else None
        if fm and fs:
            return fm["period"], fs["period"], fs["period"] - fm["period"]
        return m.period_s, s.period_s, float("nan")
    except PneunetError:
        return float("nan"), float("nan"), float("nan")


def held_out_error(fit: TraceFit, data, test_window, node=None) -> dict:
    """RMS residual and period error of a fit on the samples in ``test_window``."""
    r = fit.residuals
    w = (r["time_s"] >= test_window[0]) & (r["time_s"] <= test_window[1])
    sigs = [c for c in r.columns if c not in ("time_s", "phase", "fitted")]
    df = read_trace(data)
    scales = {s: max(np.ptp(df[[c for c in df.columns if signal_of_column(c) == s][0]]), 1e-9) / 100
              for s in sigs}
    rms = float(np.sqrt(np.mean(np.concatenate([(r.loc[w, s].to_numpy() / scales[s]) ** 2
                                                for s in sigs]))))
    per_signal = {s: float(np.sqrt(np.mean(r.loc[w, s] ** 2))) for s in sigs}
    times = df["time_s"].to_numpy()
    node = node or next((s[2:] for s in sigs if s.startswith("p_")), None)
    ref = df[f"p_{node}_kPa"].to_numpy()
    mask = (times >= test_window[0]) & (times <= test_window[1])
    pm, ps, perr = _period_error(times, ref, fit.solution, node, mask)
    return {"rms_scaled": rms, "rms": per_signal, "period_measured": pm, "period_simulated": ps,
            "period_error": perr}


def split_by_cycles(data, node: str, train_fraction: float = 0.5):
    """(train, test) windows: the first cycles (``train_fraction`` of the full cycles,
    at least 2) and the remainder of the record."""
    df = read_trace(data)
    t = df["time_s"].to_numpy()
    y = df[f"p_{node}_kPa"].to_numpy()
    from .oscillation import _rising_crossings

    rises = _rising_crossings(t, y, 0.5 * (np.min(y) + np.max(y)))
    if len(rises) < 4:
        cut = t[0] + train_fraction * (t[-1] - t[0])
    else:
        k = max(2, int(round(train_fraction * (len(rises) - 1))))
        cut = rises[min(k, len(rises) - 2)]
    return (float(t[0]), float(cut)), (float(cut), float(t[-1]))


def rank_effects(build: Callable, data, params: dict, *, candidates=CANDIDATES, fixed=None,
                 node: str = "tank", train_fraction: float = 0.5, signals=None,
                 max_nfev: int = 40, base_fit: TraceFit | None = None):
    """Fit the base model and each candidate effect on the first cycles; rank by the
    error on the later cycles.  Returns (DataFrame sorted best first, {name: TraceFit}).

    Rows: ``effect`` ('none' = base model), ``held_out_rms`` (scaled: % of each signal's
    range), ``train_rms``, ``period_error`` (held out, s), ``improvement`` relative to
    the base model, and the fitted values.
    """
    import pandas as pd

    train, test = split_by_cycles(data, node, train_fraction)
    fits = {}
    base = base_fit or fit_trace(build, data, params, fixed=fixed, signals=signals, node=node,
                                 window=train, max_nfev=max_nfev)
    fits["none"] = base
    for eff in candidates:
        p = {k: (float(np.clip(base.values[k], lo, hi)), lo, hi) for k, (_, lo, hi) in params.items()}
        p.update(eff.params)
        # started from the base estimates, then the cycle-feature stage re-centres
        # R_out, R_vent, V with the effect at its guess (a polytropic tank shortens the
        # period by up to 1/1.4, which the base fit absorbed into V)
        fits[eff.name] = fit_trace(build, data, p, fixed=fixed, signals=signals, node=node,
                                   window=train, effects=(eff,), max_nfev=max_nfev)
    rows = []
    for name, f in fits.items():
        h = held_out_error(f, data, test, node)
        w = f.residuals["fitted"].to_numpy()
        rows.append({"effect": name, "held_out_rms": h["rms_scaled"],
                     "period_error": h["period_error"], "abs_period_error": abs(h["period_error"]),
                     "train_rmse": float(np.mean(list(f.rmse.values()))),
                     "values": {k: float(v) for k, v in f.values.items()}, "nfev": f.nfev})
    table = pd.DataFrame(rows)
    base_err = float(table.loc[table.effect == "none", "held_out_rms"].iloc[0])
    table["improvement"] = 1 - table["held_out_rms"] / base_err
    table = table.sort_values("held_out_rms").reset_index(drop=True)
    table.attrs["train_window"] = train
    table.attrs["test_window"] = test
    return table, fits


def plot_fit(fit: TraceFit, data, path=None, signals=None):
    """Recorded vs fitted signals (top), residuals over time (middle), rms residual over
    the oscillation phase (bottom)."""
    from ..plotting import pyplot, save

    plt = pyplot()
    df = read_trace(data)
    r = fit.residuals
    sigs = signals or [c for c in r.columns if c not in ("time_s", "phase", "fitted")]
    fig, axes = plt.subplots(3, 1, figsize=(8, 8))
    for s in sigs:
        col = [c for c in df.columns if signal_of_column(c) == s][0]
        axes[0].plot(df["time_s"], df[col], ".", ms=2, alpha=0.5, label=f"{s} recorded")
        axes[0].plot(fit.solution.t, fit.solution[s], lw=1, label=f"{s} fitted")
        axes[1].plot(r["time_s"], r[s], lw=0.7, label=s)
        axes[2].plot(fit.phase_rms["phase"], fit.phase_rms[s], "o-", ms=3, label=s)
    if not r["fitted"].all():
        t_fit = r.loc[r["fitted"], "time_s"]
        for ax in axes[:2]:
            ax.axvspan(t_fit.min(), t_fit.max(), color="0.9", zorder=0, label="fit window")
    axes[0].set_ylabel("kPa / mg/s")
    axes[0].legend(fontsize=7, ncol=2)
    axes[1].set_ylabel("residual")
    axes[1].set_xlabel("time (s)")
    axes[2].set_xlabel("oscillation phase (0 = rising through mid level)")
    axes[2].set_ylabel("rms residual")
    axes[2].legend(fontsize=7)
    title = ", ".join(f"{k} = {v:.4g}" for k, v in fit.values.items())
    if math.isfinite(fit.period_error):
        title += f"; period error {fit.period_error:+.3g} s"
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    return save(fig, path) if path is not None else fig


def synthetic_trace(build: Callable, params: dict, t_end: float, *, dt: float = 0.05,
                    signals=("p_tank", "p_out"), noise: float = 0.5, seed: int = 0,
                    options: dict | None = None):
    """A recording simulated with known ``params`` plus white noise (kPa / mg/s), in the
    DATA-FORMAT layout, simulated with ``options`` (default :data:`FIT_OPTIONS`, so the
    record carries no numerical error of its own).  For tests and the documentation."""
    import pandas as pd

    from .sweep import apply_overrides

    c = build(params)
    apply_overrides(c, params)
    c.options = c.options.replace(**(FIT_OPTIONS if options is None else options))
    times = np.arange(0.0, t_end + 1e-9, dt)
    sol = c.tran(float(times[-1]), t_step=dt)
    rng = np.random.default_rng(seed)
    data = {"time_s": times}
    for s in signals:
        unit = "kPa" if s.startswith("p_") else "mg_s"
        data[f"{s}_{unit}"] = _sample(sol.t, sol[s], times) + noise * rng.standard_normal(len(times))
    return pd.DataFrame(data)
