"""Stand-alone recordings of a driven circuit: the flow amplifier of the paper (Fig. 10)
filling and venting an actuator, both valves switched by antiphase control pulses.

Nothing here imports pneunet: the mirror valve's law in both directions (eq. 19 with
eq. 25's areas, its backward parameters where p_out > p_in), the quadrature line
(eq. 4), the actuator, the SPICE PULSE waveform and every hidden effect are coded below
and integrated by scipy's Radau.  It records what ``netlists/amplifier.pn`` names:
the valves' junction ``act`` and the actuator ``muscle``.

The junction always carries a small gas volume (``V_act``, default 1e-4 mL: the
valves' cavities), so it follows its algebraic value within microseconds.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from .standalone import resistor as line  # the quadrature line, eq. 4 (1 kPa² band)
from .standalone import root

M_AIR = 28.965  # g/mol
R_GAS = 8.314462618  # J/(mol K)
T_WALL = 293.15  # K
GAMMA = 1.4
MIRROR = {"Rf": 0.400, "pclose": 21.86, "ptrans": 96.02, "e": 1.65, "ain": 0.578,
          "aout": 0.459}
MIRROR_BACKWARD = {"Rf": 0.395, "pclose": 19.52, "ptrans": 93.44, "e": 1.62, "ain": 0.588,
                   "aout": 0.439}

DEFAULTS = {"pH": 289.0, "pL": 120.0, "ambient": 96.0, "pc_hi": 496.0, "pc_lo": 96.0,
            "T": 10.0, "R_line": 0.2, "V": 30.0, "p0": 120.0, "V_act": 1e-4,
            "once": False,         # the pulses switch once (no period): one inflation at T/2
            "supply_on": None,     # s: the supply rests at pL until then, rises to pH in 10 ms
            # hidden effects (None: absent)
            "heat_tau": None,      # energy balance in the actuator, hA = m(200 kPa)·c_v/τ
            "tube_ctrl": None,     # (R, V): tube from the in-valve's control source
            "leak": None,          # kPa·s/mg: laminar leak of the actuator to ambient
            "compliance": None,    # 1/kPa: actuator volume V·(1 + κ·(p − p0))
            }


def capacitance(V_ml, T=T_WALL):
    """Isothermal capacitance M·V/(R·T), mg/kPa."""
    return M_AIR * V_ml / (R_GAS * T)


def valve(p_in, p_out, p_ctrl):
    """Mirror valve, mg/s from in to out: eq. 19 with eq. 25 (a_in on the higher port),
    the backward parameters where p_out > p_in."""
    v = MIRROR if p_in >= p_out else MIRROR_BACKWARD
    dp = v["ain"] * max(p_in, p_out) + v["aout"] * min(p_in, p_out) - p_ctrl
    if dp <= v["pclose"]:
        return 0.0
    x = (dp - v["pclose"]) / (v["ptrans"] - v["pclose"])
    g = 1.0 / (v["Rf"] * np.sqrt(1.0 + x ** (-2.0 * v["e"])))
    return g * root(p_in * p_in - p_out * p_out)


def pulse(t, v1, v2, td, tr, tf, pw, per):
    """SPICE PULSE(v1 v2 td tr tf pw per) at time t."""
    if t < td:
        return v1
    s = (t - td) % per
    if s < tr:
        return v1 + (v2 - v1) * s / tr
    if s < tr + pw:
        return v2
    if s < tr + pw + tf:
        return v2 + (v1 - v2) * (s - tr - pw) / tf
    return v1


def integrate_between(rhs, y0, breaks, times, t_start):
    """(t, y) of ``rhs`` integrated by Radau from ``y0`` at ``breaks[0]``, restarted at
    every corner of ``breaks`` (sorted), at the sample ``times`` from ``t_start`` on."""
    out_t, out_y = [], []
    y = y0
    for a, b in zip(breaks[:-1], breaks[1:]):
        inside = times[(times >= a) & (times < b)]
        sol = solve_ivp(rhs, (a, b), y, method="Radau", t_eval=np.append(inside, b),
                        rtol=1e-8, atol=1e-8)
        assert sol.success, sol.message
        out_t.append(sol.t[:-1])
        out_y.append(sol.y[:, :-1])
        y = sol.y[:, -1]
    t_all = np.concatenate(out_t)
    y_all = np.concatenate(out_y, axis=1)
    if times[-1] >= breaks[-1] - 1e-12:
        t_all, y_all = np.append(t_all, breaks[-1]), np.column_stack([y_all, y])
    keep = t_all >= t_start - 1e-12
    return t_all[keep], y_all[:, keep]


def amplifier_record(t_start=0.0, duration=30.0, dt=0.01, noise=0.3, seed=0,
                     signals=("act", "muscle"), **kw):
    """A noisy recording (DataFrame: time_s on the sources' clock from ``t_start``,
    p_<node>_kPa) of the driven amplifier with the hidden effects in ``kw``
    (see :data:`DEFAULTS`)."""
    p = dict(DEFAULTS, **kw)
    T = p["T"]
    period = np.inf if p["once"] else T
    c_in = (p["pc_hi"], p["pc_lo"], T / 2, 0.01, 0.01, T / 2 - 0.01, period)
    c_out = (p["pc_lo"], p["pc_hi"], T / 2, 0.01, 0.01, T / 2 - 0.01, period)
    idx = {"act": 0, "muscle": 1}
    for key, state in (("heat_tau", "T"), ("tube_ctrl", "ctrl")):
        if p[key] is not None:
            idx[state] = len(idx)
    C_act = capacitance(p["V_act"])
    m_ref_over_tau = capacitance(p["V"]) * 200.0 / p["heat_tau"] if p["heat_tau"] else 0.0

    def volume(pm):
        k = p["compliance"]
        return p["V"] * (1.0 + k * (pm - p["p0"])) if k else p["V"]

    def muscle_pressure(y):
        if p["heat_tau"] is not None:  # y[1]: gas mass, mg
            return y[1] / capacitance(p["V"], y[idx["T"]])
        return y[1]

    def supply(t):
        on = p["supply_on"]
        if on is None or t >= on + 0.01:
            return p["pH"]
        return p["pL"] + (p["pH"] - p["pL"]) * max(0.0, t - on) / 0.01

    def rhs(t, y):
        p_act, p_m = y[0], muscle_pressure(y)
        p_cin = y[idx["ctrl"]] if "ctrl" in idx else pulse(t, *c_in)
        q_in = valve(supply(t), p_act, p_cin)
        q_out = valve(p_act, p["pL"], pulse(t, *c_out))
        q_line = line(p_act, p_m, p["R_line"])
        q_leak = (p_m - p["ambient"]) / p["leak"] if p["leak"] else 0.0
        dy = np.zeros(len(idx))
        dy[0] = (q_in - q_out - q_line) / C_act
        net = q_line - q_leak
        if p["heat_tau"] is not None:
            temp, m = y[idx["T"]], y[1]
            t_in = T_WALL if q_line >= 0 else temp
            dy[1] = net
            # m·dT/dt = γ·T_in·q_in − γ·T·q_leak − T·(q_in − q_leak) + hA/c_v·(T_w − T)
            dy[idx["T"]] = (GAMMA * t_in * q_line - GAMMA * temp * q_leak - temp * net
                            + m_ref_over_tau * (T_WALL - temp)) / m
        elif p["compliance"]:
            # m = C(V(p))·p: dm/dp = C(V) + C(V0)·κ·p
            k = p["compliance"]
            dy[1] = net / (capacitance(volume(p_m)) + capacitance(p["V"]) * k * p_m)
        else:
            dy[1] = net / capacitance(p["V"])
        if "ctrl" in idx:
            R, V = p["tube_ctrl"]
            dy[idx["ctrl"]] = line(pulse(t, *c_in), p_cin, R) / capacitance(V)
        return dy

    y0 = np.zeros(len(idx))
    y0[0] = p["pL"]
    y0[1] = capacitance(p["V"]) * p["p0"] if p["heat_tau"] is not None else p["p0"]
    if "T" in idx:
        y0[idx["T"]] = T_WALL
    if "ctrl" in idx:
        y0[idx["ctrl"]] = c_in[0]
    t_end = t_start + duration
    cycles = 1 if p["once"] else int(t_end / T) + 1
    breaks = sorted({0.0, t_end} | {b for k in range(cycles)
                                    for b in (k * T + T / 2, k * T + T / 2 + 0.01,
                                              k * T + T, k * T + T + 0.01) if 0 < b < t_end}
                    | ({b for b in (p["supply_on"], p["supply_on"] + 0.01) if 0 < b < t_end}
                       if p["supply_on"] is not None else set()))
    times = np.arange(t_start, t_end + 1e-9, dt)
    t_all, y_all = integrate_between(rhs, y0, breaks, times, t_start)
    values = {"act": y_all[0], "muscle": np.array([muscle_pressure(c) for c in y_all.T])}
    rng = np.random.default_rng(seed)
    data = {"time_s": t_all}
    for s in signals:
        data[f"p_{s}_kPa"] = values[s] + noise * rng.standard_normal(len(t_all))
    return pd.DataFrame(data)
