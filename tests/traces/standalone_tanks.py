"""Stand-alone recordings of two tanks charged and vented through quadrature lines by a
supply step (96 → 296 kPa at 2 s, back at 12 s): ``netlists/two_tanks.pn``; or by a
square wave (:func:`square_supply`): ``netlists/two_tanks_pulse.pn``; or by a sine
(:func:`sine_supply`): ``netlists/two_tanks_sine.pn``.

Nothing here imports pneunet: the quadrature law (eq. 4, 1 kPa² band), isothermal
tanks, and the hidden effects are coded below and integrated by scipy's Radau.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

M_AIR = 28.965  # g/mol
R_GAS = 8.314462618  # J/(mol K)
T_WALL = 293.15  # K
GAMMA = 1.4
TRUTH = {"R1": 0.5, "R2": 2.0, "V1": 50.0, "V2": 100.0}


def capacitance(V_ml, T=T_WALL):
    """Isothermal capacitance M·V/(R·T), mg/kPa."""
    return M_AIR * V_ml / (R_GAS * T)


def line(a, b, R):
    """Quadrature line, mg/s from a to b (1 kPa² band)."""
    d = a * a - b * b
    return d / (d * d + 1.0) ** 0.25 / R


def supply(t):
    return float(np.interp(t, [0, 2, 2.02, 12, 12.02], [96, 96, 296, 296, 96]))


def square_supply(t):
    """96 kPa until 1 s, then 296 kPa for 3 s (20 ms ramps included) in every 6 s."""
    if t < 1.0:
        return 96.0
    u = (t - 1.0) % 6.0
    return float(np.interp(u, [0.0, 0.02, 3.0, 3.02, 6.0], [96, 296, 296, 96, 96]))


def sine_supply(t):
    """196 − 100·cos(2π·0.2·t) kPa: between 96 and 296 kPa every 5 s, from 96 at 0 s."""
    return 196.0 - 100.0 * float(np.cos(2.0 * np.pi * 0.2 * t))


def tanks_record(start=1.1, seconds=18.0, dt=0.02, noise=0.3, seed=0, heat_tau=None,
                 leak=None, side=None, source=supply, **values):
    """p_t1, p_t2 from ``start`` s on the supply's clock (``source``: its pressure, kPa,
    at t s), the logger's clock from 0.

    Hidden effects: ``heat_tau`` (s) energy balance in tank 1 with hA = C(V1)·200/τ;
    ``leak`` (kPa·s/mg) a laminar leak of tank 2 to 96 kPa; ``side`` (R, V mL) a
    dead-end volume behind a line at tank 2."""
    v = dict(TRUTH, **values)
    c1, c2 = capacitance(v["V1"]), capacitance(v["V2"])
    hA = c1 * 200.0 / heat_tau if heat_tau else 0.0

    def rhs(t, y):
        # y: tank 1 (pressure, or gas mass with heat), T1, p2, p_side
        p1 = y[0] / capacitance(v["V1"], y[1]) if heat_tau else y[0]
        q1, q2 = line(source(t), p1, v["R1"]), line(p1, y[2], v["R2"])
        into2 = q2 - ((y[2] - 96.0) / leak if leak else 0.0)
        dy = np.zeros(4)
        if side:
            qs = line(y[2], y[3], side[0])
            into2 -= qs
            dy[3] = qs / capacitance(side[1])
        if heat_tau:
            T1, net = y[1], q1 - q2
            t_in = T_WALL if q1 >= 0 else T1
            t_out = T1 if q2 >= 0 else T_WALL
            dy[0] = net
            dy[1] = (GAMMA * t_in * q1 - GAMMA * t_out * q2 - T1 * net
                     + hA * (T_WALL - T1)) / y[0]
        else:
            dy[0] = (q1 - q2) / c1
        dy[2] = into2 / c2
        return dy

    y0 = [c1 * 96.0 if heat_tau else 96.0, T_WALL, 96.0, 96.0]
    t = start + dt * np.arange(int(round(seconds / dt)))
    # the states a case leaves unused (T1, p_side) have zero Jacobian columns, whose
    # difference factor scipy grows until it overflows: harmless, so not shown
    with np.errstate(over="ignore"):
        sol = solve_ivp(rhs, (0.0, t[-1]), y0, method="Radau", t_eval=t, rtol=1e-9,
                        atol=1e-9, max_step=0.01)
    p1 = sol.y[0] / capacitance(v["V1"], sol.y[1]) if heat_tau else sol.y[0]
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"time_s": t - start,
                         "p_t1_kPa": p1 + noise * rng.standard_normal(t.size),
                         "p_t2_kPa": sol.y[2] + noise * rng.standard_normal(t.size)})
