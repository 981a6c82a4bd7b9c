"""Stand-alone recordings of a third circuit: the chain of two fluidic inverters of
``netlists/inverter.pn`` (normally-open mirror valves fed from a 496 kPa supply, each
output pulled down to the atmosphere through R_pull and holding 2 mL), the first gate's
control switched by a PULSE, the second gate's control the first one's output.

Nothing here imports pneunet: the mirror valve in both directions and the PULSE waveform
(:mod:`.standalone_driven`), the quadrature resistor (:mod:`.standalone`) and every hidden
effect are coded below and integrated by scipy's Radau.  It records the gate outputs
``out1`` and ``out2`` (optionally the input ``in``), time on the sources' clock.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .standalone import resistor
from .standalone_driven import GAMMA, T_WALL, capacitance, integrate_between, pulse, valve

DEFAULTS = {"psup": 496.0, "plo": 96.0, "phi": 496.0, "ambient": 96.0, "Rpull": 20.0,
            "V1": 2.0, "V2": 2.0,
            "pulse": (1.0, 0.05, 0.05, 2.0, 4.0),  # td, tr, tf, pw, per (s)
            # hidden effects (None: absent)
            "heat_tau": None,     # energy balance in out1's volume, hA = m(ambient)·c_v/τ
            "dead_volume": None,  # mL of extra gas volume at out1
            "tube_ctrl": None,    # (R, V): tube from out1 to the second gate's control port
            "leak": None,         # kPa·s/mg: laminar leak of out1's volume to ambient
            "compliance": None,   # 1/kPa: out1's volume V1·(1 + κ·(p − ambient))
            }


def inverter_record(t_start=0.0, duration=20.0, dt=0.02, noise=0.3, seed=0,
                    signals=("out1", "out2"), **kw):
    """A noisy recording (DataFrame: time_s on the sources' clock from ``t_start``,
    p_<node>_kPa) of the inverter chain with the hidden effects in ``kw``
    (see :data:`DEFAULTS`); every volume starts at ambient pressure at t = 0."""
    p = dict(DEFAULTS, **kw)
    td, tr, tf, pw, per = p["pulse"]
    wave = (p["plo"], p["phi"], td, tr, tf, pw, per)
    amb = p["ambient"]
    idx = {"out1": 0, "out2": 1}
    for key, state in (("heat_tau", "T"), ("tube_ctrl", "ctrl")):
        if p[key] is not None:
            idx[state] = len(idx)
    V1 = p["V1"] + (p["dead_volume"] or 0.0)
    m_ref_over_tau = capacitance(V1) * amb / p["heat_tau"] if p["heat_tau"] else 0.0

    def out1_pressure(y):
        if p["heat_tau"] is not None:  # y[0]: gas mass in out1's volume, mg
            return y[0] / capacitance(V1, y[idx["T"]])
        return y[0]

    def rhs(t, y):
        p1, p2 = out1_pressure(y), y[1]
        p_ctrl2 = y[idx["ctrl"]] if "ctrl" in idx else p1
        q_v1 = valve(p["psup"], p1, pulse(t, *wave))
        q_p1 = resistor(p1, amb, p["Rpull"])
        q_v2 = valve(p["psup"], p2, p_ctrl2)
        q_p2 = resistor(p2, amb, p["Rpull"])
        q_leak = (p1 - amb) / p["leak"] if p["leak"] else 0.0
        q_tube = resistor(p1, p_ctrl2, p["tube_ctrl"][0]) if "ctrl" in idx else 0.0
        dy = np.zeros(len(idx))
        net = q_v1 - q_p1 - q_leak - q_tube
        if p["heat_tau"] is not None:
            temp, m = y[idx["T"]], y[0]
            # m·dT/dt = γ·Σ T_k·q_k − T·Σ q_k + hA/c_v·(T_w − T), q_k into the volume,
            # T_k = T_w for inflow, T for outflow
            enthalpy = sum(GAMMA * (T_WALL if q >= 0 else temp) * q
                           for q in (q_v1, -q_p1, -q_leak, -q_tube))
            dy[0] = net
            dy[idx["T"]] = (enthalpy - temp * net + m_ref_over_tau * (T_WALL - temp)) / m
        elif p["compliance"]:
            # m = C(V(p))·p: dm/dp = C(V(p)) + C(V1)·κ·p
            k = p["compliance"]
            dy[0] = net / (capacitance(V1 * (1.0 + k * (p1 - amb))) + capacitance(V1) * k * p1)
        else:
            dy[0] = net / capacitance(V1)
        dy[1] = (q_v2 - q_p2) / capacitance(p["V2"])
        if "ctrl" in idx:
            dy[idx["ctrl"]] = q_tube / capacitance(p["tube_ctrl"][1])
        return dy

    y0 = np.full(len(idx), amb)
    if p["heat_tau"] is not None:
        y0[0] = capacitance(V1) * amb
        y0[idx["T"]] = T_WALL
    t_end = t_start + duration
    corners = {td + k * per + c for k in range(int(t_end / per) + 2)
               for c in (0.0, tr, tr + pw, tr + pw + tf)}
    breaks = sorted({0.0, t_end} | {b for b in corners if 0 < b < t_end})
    times = t_start + dt * np.arange(int(round(duration / dt)) + 1)
    t_all, y_all = integrate_between(rhs, y0, breaks, times, t_start)
    values = {"out1": np.array([out1_pressure(c) for c in y_all.T]), "out2": y_all[1],
              "in": np.array([pulse(t, *wave) for t in t_all])}
    rng = np.random.default_rng(seed)
    data = {"time_s": t_all}
    for s in signals:
        data[f"p_{s}_kPa"] = values[s] + noise * rng.standard_normal(len(t_all))
    return pd.DataFrame(data)
