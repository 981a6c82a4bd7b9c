"""Stand-alone recordings of the paper's oscillator, written out by hand for the tests.

Nothing here imports pneunet: the valve law (eq. 19), the quadrature resistors (eq. 4),
the volumes and every hidden effect are coded below and integrated by scipy's Radau, so
a diagnosis that names the effect has found it in data its own code did not make.

The valve output node always carries a small gas volume (``V_out``, default 1e-6 mL:
the tubing stub of a real valve); the jump of p_out at a fold is then a fast transient,
the limit that pneunet's explicit branch jumps reproduce.  A larger stub is an effect of
its own: it delays each jump (1e-4 mL lengthened a 1.9 s cycle by 0.43 ms, 2.3e-4, about
a clean 30 s recording's standard error; 1e-6 mL by 2e-5 s, 1e-5).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

M_AIR = 28.965  # g/mol
R_GAS = 8.314462618  # J/(mol K), CODATA
T_WALL = 293.15  # K
GAMMA = 1.4
AXI = {"Rf": 0.566, "pclose": 96.42, "ptrans": 155.1, "e": 1.99, "ain": 0.32, "aout": 0.71}
BAND = 1.0  # kPa², zero-flow band of the regularised root


def capacitance(V_ml, T=T_WALL):
    """Isothermal capacitance M·V/(R·T), mg/kPa."""
    return M_AIR * V_ml / (R_GAS * T)


def root(d):
    """Signed root regularised in a 1 kPa² band."""
    return d / (d * d + BAND * BAND) ** 0.25


def resistor(pa, pb, R):
    """Quadrature resistor, mg/s from a to b."""
    return root(pa * pa - pb * pb) / R


def valve(p_in, p_out, p_ctrl, v, p_close):
    """Six-parameter valve, eq. 19 with eq. 25's areas, mg/s from in to out."""
    hi, lo = max(p_in, p_out), min(p_in, p_out)
    dp = v["ain"] * hi + v["aout"] * lo - p_ctrl
    if dp <= p_close:
        return 0.0
    x = (dp - p_close) / (v["ptrans"] - p_close)
    g = 1.0 / (v["Rf"] * np.sqrt(1.0 + x ** (-2.0 * v["e"])))
    return g * root(p_in * p_in - p_out * p_out)


DEFAULTS = {"Rout": 1.132, "Rvent": 3.0, "V": 50.0, "pH": 496.0, "pL": 96.0, "V_out": 1e-6,
            # hidden effects (None: absent)
            "poly_n": None,          # p·V^n: tank gas compresses polytropically (closed form)
            "gas_law_n": None,       # dp/dt = n·R·T_w/(M·V)·ṁ (Richer–Hurmuzlu, T ≈ T_w)
            "heat_tau": None,        # energy balance, constant hA = m(200 kPa)·c_v/τ
            "tube_ctrl": None,       # (R, V): tube from the tank to the control port
            "tube_supply": None,     # (R, V): tube from the supply to the valve input
            "side": None,            # (R, V): a dead-end volume joined to the tank by R
            "creep": None,           # kPa/s: p_close drifts (membrane creep)
            "ripple": None,          # (amplitude kPa, frequency Hz) on the supply
            }


def oscillator_record(t_end=12.0, dt=0.05, noise=0.4, seed=0, signals=("tank", "out"),
                      **kw):
    """A noisy recording (DataFrame: time_s, p_<node>_kPa) of the oscillator with the
    hidden effects in ``kw`` (see :data:`DEFAULTS`)."""
    p = dict(DEFAULTS, **kw)
    C_out = capacitance(p["V_out"])
    C_tank = capacitance(p["V"])
    # state: p_out, tank (p or mass), [T], [p_ctrl tube], [p_in tube]
    idx = {"out": 0, "tank": 1}
    for key, state in (("heat_tau", "T"), ("tube_ctrl", "ctrl"), ("tube_supply", "in"),
                       ("side", "side")):
        if p[key] is not None:
            idx[state] = len(idx)
    n = len(idx)
    m_ref_over_tau = (capacitance(p["V"]) * 200.0 / p["heat_tau"]) if p["heat_tau"] else 0.0

    def tank_pressure(y):
        if p["heat_tau"] is not None:
            return y[1] / capacitance(p["V"], y[idx["T"]])  # y[1]: gas mass, mg
        return y[1]

    def supply(t):
        if p["ripple"] is None:
            return p["pH"]
        a, f = p["ripple"]
        return p["pH"] + a * np.sin(2 * np.pi * f * t)

    def rhs(t, y):
        p_out, p_tank = y[0], tank_pressure(y)
        p_ctrl = y[idx["ctrl"]] if "ctrl" in idx else p_tank
        p_in = y[idx["in"]] if "in" in idx else supply(t)
        p_close = AXI["pclose"] + (p["creep"] or 0.0) * t
        q_valve = valve(p_in, p_out, p_ctrl, AXI, p_close)
        q_out = resistor(p_out, p_tank, p["Rout"])
        q_vent = resistor(p_tank, p["pL"], p["Rvent"])
        dy = np.zeros(n)
        dy[0] = (q_valve - q_out) / C_out
        net = q_out - q_vent
        if p["heat_tau"] is not None:
            T = y[idx["T"]]
            m = y[1]
            t_in = T_WALL if q_out >= 0 else T
            # m·dT/dt = γ·T_in·q_in − γ·T·q_vent − T·(q_in − q_vent) + hA/c_v·(T_w − T)
            dy[1] = net
            dy[idx["T"]] = (GAMMA * t_in * q_out - GAMMA * T * q_vent - T * net
                            + m_ref_over_tau * (T_WALL - T)) / m
        elif p["poly_n"] is not None:
            k = p["poly_n"]
            dy[1] = net * k * p_tank / (C_tank * p["pL"]) * (p["pL"] / p_tank) ** (1.0 / k)
        elif p["gas_law_n"] is not None:
            dy[1] = p["gas_law_n"] * net / C_tank
        else:
            dy[1] = net / C_tank
        if "ctrl" in idx:
            R, V = p["tube_ctrl"]
            q = resistor(p_tank, p_ctrl, R)
            dy[idx["ctrl"]] = q / capacitance(V)
            if p["heat_tau"] is None and p["poly_n"] is None and p["gas_law_n"] is None:
                dy[1] -= q / C_tank
            else:
                raise NotImplementedError("one hidden effect at a time with heat exchange")
        if "side" in idx:
            R, V = p["side"]
            q = resistor(p_tank, y[idx["side"]], R)
            dy[idx["side"]] = q / capacitance(V)
            dy[1] -= q / C_tank
        if "in" in idx:
            R, V = p["tube_supply"]
            dy[idx["in"]] = (resistor(supply(t), p_in, R) - q_valve) / capacitance(V)
        return dy

    y0 = np.zeros(n)
    # p_out starts where the valve's flow equals R_out's (the open branch)
    y0[0] = brentq(lambda x: valve(p["pH"], x, p["pL"], AXI, AXI["pclose"])
                   - resistor(x, p["pL"], p["Rout"]), p["pL"], p["pH"])
    y0[1] = capacitance(p["V"]) * p["pL"] if p["heat_tau"] is not None else p["pL"]
    if "T" in idx:
        y0[idx["T"]] = T_WALL
    if "ctrl" in idx:
        y0[idx["ctrl"]] = p["pL"]
    if "in" in idx:
        y0[idx["in"]] = p["pH"]
    if "side" in idx:
        y0[idx["side"]] = p["pL"]
    times = np.arange(0.0, t_end + 1e-9, dt)
    sol = solve_ivp(rhs, (0.0, times[-1]), y0, method="Radau", t_eval=times, rtol=1e-8,
                    atol=1e-8)
    assert sol.success, sol.message
    rng = np.random.default_rng(seed)
    values = {"out": sol.y[0], "tank": np.array([tank_pressure(c) for c in sol.y.T])}
    data = {"time_s": times}
    for s in signals:
        data[f"p_{s}_kPa"] = values[s] + noise * rng.standard_normal(len(times))
    return pd.DataFrame(data)
