"""Starting values of a circuit fit from the recorded cycle (no trace fit needed).

A trace fit alone gets stuck when the guessed period is off by more than a few per
cent, because the simulated and recorded cycles drift out of phase.  For an oscillator
the circuit recognises (:func:`~pneunet.physics.oscillator_branches.spec_from_circuit`) the cycle
gives R_out (stationary-branch turning points vs recorded p_min/p_max), R_vent (rise
fraction by quadrature along the branches) and V (the period); otherwise a short
least-squares fit to the cycle features (period, p_min, p_max, rise fraction).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ...common.errors import PneunetError
from .model import sample_at


def cycle_features(t, y, levels=None):
    """Robust cycle features of a (noisy) sampled oscillation: period, p_min, p_max and
    rise fraction = t_up / (t_up + t_down), the times the signal takes to rise from
    ``levels[0]`` to ``levels[1]`` and to fall back (default: 25 % and 75 % of the
    range over the second half of the record); medians over the full cycles between rising crossings of the mid level.
    Crossing times are interpolated between samples, so the rise fraction is
    insensitive to noise; the extremes are the raw sample extremes (the relaxation
    cycle has corners there).  None if fewer than one full cycle."""
    from ...engine.oscillation import rising_crossings
    from .data import crossing_band

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    band = crossing_band(y)
    if levels is None:
        half = t >= t[0] + 0.5 * (t[-1] - t[0])  # past the start-up transient
        lo_, hi_ = float(np.min(y[half])), float(np.max(y[half]))
        levels = (lo_ + 0.25 * (hi_ - lo_), lo_ + 0.75 * (hi_ - lo_))
    l1, l2 = levels
    rises = rising_crossings(t, y, 0.5 * (l1 + l2), band)
    if len(rises) < 2:
        return None
    up1, up2 = rising_crossings(t, y, l1, band), rising_crossings(t, y, l2, band)
    dn2, dn1 = rising_crossings(t, -y, -l2, band), rising_crossings(t, -y, -l1, band)
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
    from ...physics.oscillator_branches import vent_flow

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
    from ...physics.oscillator_branches import spec_from_circuit

    values = dict(zip(names, np.exp(x)))
    base = spec_from_circuit(model.circuit(values, settle=False))
    roles = {}
    for i, k in enumerate(names):
        v = dict(values)
        v[k] = values[k] * 1.01
        s = spec_from_circuit(model.circuit(v, settle=False))
        for field_ in ("Rout", "Rvent", "V"):
            a_, b_ = getattr(s, field_), getattr(base, field_)
            if field_ not in roles and math.isfinite(a_) and math.isfinite(b_) and a_ != b_:
                roles[field_] = i
    return roles, base


#: continuation step of the R_out search, which needs only the turning points (refined
#: by Newton; the same to 1e-6 kPa as with the default step 5, in half the time)
TURNING_POINT_DS = 10.0


@functools.lru_cache(maxsize=256)
def _branches(spec, ds: float = 5.0):
    """The stationary branches of ``spec`` (a pure function of it): a screen recentres
    every grid point of every effect from the same base values, so its R_out searches
    ask for the same specs again (kept per worker process)."""
    from ...physics.oscillator_branches import stationary_branches

    return stationary_branches(spec, ds=ds)


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

    from ...physics.oscillator_branches import spec_from_circuit

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
        if it:  # the first iteration's is the one found with the roles
            spec = spec_from_circuit(model.circuit(values, settle=False))
        if "Rout" in roles:
            i = roles["Rout"]
            scale = spec.Rout / math.exp(x[i])  # spec R_out per unit of the fitted parameter

            def miss(lr):
                try:
                    b = _branches(dataclasses.replace(spec, Rout=scale * math.exp(lr)),
                                  TURNING_POINT_DS)
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
        b = _branches(spec)
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
            b = _branches(spec)
        values = dict(zip(names, np.exp(x)))
        try:
            sol = model.simulate(values, float(t_fit[-1]), float(np.median(np.diff(t_fit))))
            sim_f = cycle_features(t_fit, sample_at(sol.t - model.first_time,
                                                    sol.pressure(node), t_fit),
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
    from ...engine.oscillation import analyze_oscillation

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
            sim_t = sol.t - model.first_time
            inside = sim_t >= t_fit[0]
            f = _features(sim_t[inside], sol.pressure(node)[inside])
        except PneunetError:
            f = None
        if f is None:
            return np.full(4, 1e3)
        return (f - target) / scale

    r = optimize.least_squares(fres, x0, bounds=(lb, ub), diff_step=1e-2, max_nfev=max_nfev,
                               method="trf")
    return r.x, {"values": dict(zip(names, map(float, np.exp(r.x)))), "nfev": int(r.nfev),
                 "feature_residual": [float(v) for v in r.fun]}

