"""Stand-alone recordings of the paper's Fig. 12 rig, written out by hand for the tests.

The single-valve oscillator (supply, membrane valve, R_out, a tank that vents through
R_vent) drives a vertical McKibben muscle that lifts a weight; a wire-draw encoder
records its contraction beside the tank pressure.  Nothing here imports pneunet: the
valve and resistor laws come from :mod:`tests.traces.standalone` (also pneunet-free),
the muscle is Chou & Hannaford's ideal braid (1996) with the load's mass, a viscous
damper and a stiff stop at its stretch limit, coded below and integrated by scipy's
Radau.

Hidden effects (keyword arguments, None: absent):

* ``tube``: (R kPa·s/mg, V mL) a line between the tank and the muscle's port;
* ``friction``: N, Coulomb friction of the sleeve (smoothed over 1 mm/s), which the
  netlist's muscle lacks.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from .standalone import AXI, capacitance, resistor, valve

G = 9.81  # m/s²
MUSCLE = {"L0": 530.0, "D0": 12.0, "theta0": 25.0, "mass": 0.2, "damping": 20.0}
DEFAULTS = {"Rout": 1.132, "Rvent": 3.0, "V": 200.0, "pH": 496.0, "pL": 96.0,
            "V_out": 1e-4, "tube": None, "friction": None}
STOP_K = 1e6  # N/m, the stop at the stretch limit (x < 0)


def braid(L0, D0, theta0):
    """Thread length b (mm) and turns n of the braid."""
    th = math.radians(theta0)
    b = L0 / math.cos(th)
    return b, b * math.sin(th) / (math.pi * D0)


def muscle_volume(x, m=MUSCLE):
    """Gas volume (mL) and dV/dx (mL/mm) at contraction x (mm)."""
    b, n = braid(m["L0"], m["D0"], m["theta0"])
    L = m["L0"] - x
    k = 4.0 * math.pi * n * n
    return L * (b * b - L * L) / k * 1e-3, (3.0 * L * L - b * b) / k * 1e-3


def muscle_force(p_gauge, x, m=MUSCLE):
    """Pull of the braid (N) at gauge pressure p_gauge (kPa) and contraction x (mm)."""
    b, n = braid(m["L0"], m["D0"], m["theta0"])
    L = m["L0"] - x
    return p_gauge * (3.0 * L * L - b * b) / (4.0 * math.pi * n * n) * 1e-3


def fig12_record(t_end=40.0, dt=0.05, noise=0.3, noise_mm=0.05, seed=0, start=0.0,
                 muscle=None, **kw):
    """A noisy recording (time_s, p_tank_kPa, p_out_kPa, contraction_M1_mm) of the rig
    from ``start`` s after switch-on for ``t_end`` s (time counted from the first
    sample), with the hidden effects in ``kw`` (see the module)."""
    p = dict(DEFAULTS, **kw)
    mus = dict(MUSCLE, **(muscle or {}))
    C_out, C_tank = capacitance(p["V_out"]), capacitance(p["V"])
    rho1 = capacitance(1.0)  # mg/(kPa·mL)
    tube = p["tube"]
    # state: p_out, p_tank, x (mm), v (mm/s), [p_muscle behind the tube]
    n_state = 5 if tube else 4

    def rhs(t, y):
        p_out, p_tank, x, v = y[:4]
        p_m = y[4] if tube else p_tank
        q_valve = valve(p["pH"], p_out, p_tank, AXI, AXI["pclose"])
        q_out = resistor(p_out, p_tank, p["Rout"])
        q_vent = resistor(p_tank, p["pL"], p["Rvent"])
        vol, dvol = muscle_volume(x, mus)
        force = muscle_force(p_m - p["pL"], x, mus) - mus["mass"] * G
        if x < 0:  # the stop at the stretch limit, critically damped
            force += -STOP_K * x * 1e-3 - 2.0 * math.sqrt(STOP_K * mus["mass"]) * v * 1e-3
        if p["friction"]:
            force -= p["friction"] * math.tanh(v / 1.0)
        dv = (force - mus["damping"] * v * 1e-3) / (mus["mass"] * 1e-3)
        into_muscle = rho1 * p_m * dvol * v  # mg/s taken by the muscle's growth at p_m
        dy = np.zeros(n_state)
        dy[0] = (q_valve - q_out) / C_out
        dy[2], dy[3] = v, dv
        if tube:
            R, V = tube
            q_t = resistor(p_tank, p_m, R)
            dy[1] = (q_out - q_vent - q_t) / C_tank
            # the tube's gas sits at the muscle's side (a lumped line)
            dy[4] = (q_t - into_muscle) / (capacitance(V) + rho1 * vol)
        else:
            dy[1] = (q_out - q_vent - into_muscle) / (C_tank + rho1 * vol)
        return dy

    y0 = np.zeros(n_state)
    y0[0] = brentq(lambda x: valve(p["pH"], x, p["pL"], AXI, AXI["pclose"])
                   - resistor(x, p["pL"], p["Rout"]), p["pL"], p["pH"])
    y0[1] = p["pL"]
    y0[2] = -mus["mass"] * G / STOP_K * 1e3  # hanging on its stop
    if tube:
        y0[4] = p["pL"]
    times = np.arange(0.0, start + t_end + 1e-9, dt)
    sol = solve_ivp(rhs, (0.0, times[-1]), y0, method="Radau", t_eval=times, rtol=1e-8,
                    atol=1e-8)
    assert sol.success, sol.message
    rng = np.random.default_rng(seed)
    keep = times >= start - 1e-9
    data = {"time_s": times[keep] - times[keep][0],
            "p_tank_kPa": sol.y[1][keep] + noise * rng.standard_normal(keep.sum()),
            "p_out_kPa": sol.y[0][keep] + noise * rng.standard_normal(keep.sum()),
            "contraction_M1_mm": sol.y[2][keep] + noise_mm * rng.standard_normal(keep.sum())}
    return pd.DataFrame(data)
