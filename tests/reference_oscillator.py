"""The paper's oscillator (Fig. 11A) integrated from its equations, independently of pneunet.

Supply 496 kPa → axi valve (eq. 19 with eq. 25, its control port on the tank) → R_out =
2·R_f → 200 mL tank (isothermal, C = M·V/(R·T)) → R_vent 3 kPa·s/mg → 96 kPa; quadrature
resistors (eq. 4).  pneunet treats the valve output as an algebraic node crossing its
folds by jumps; here it carries a 1e-4 mL stub (time constant ~1 µs), whose limit that
is (the period moves by 1.5e-3 s from 1e-3 to 1e-4 mL, i.e. ~1.5e-4 s left), and every
square root is regularised in a 1 kPa² band.  scipy's Radau at rtol 1e-8.
Units: kPa absolute, mg/s, kPa·s/mg, mL, s.
"""
import functools

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from reference_valve import delta_p  # tests/ is on pytest's sys.path

AXI = {"Rf": 0.566, "pclose": 96.42, "ptrans": 155.1, "e": 1.99, "ain": 0.32, "aout": 0.71}
P_H, P_L, V_TANK, V_STUB, R_VENT = 496.0, 96.0, 200.0, 1e-4, 3.0
R_OUT = 2 * AXI["Rf"]


def capacitance(v_ml):
    """Isothermal capacitance M·V/(R·T) of air at 293.15 K, mg/kPa."""
    return 28.965 * v_ml / (8.314462618 * 293.15)


def root(d):
    """√|d|·sign(d), regularised in a 1 kPa² band."""
    return d / (d * d + 1.0) ** 0.25


def valve(p_in, p_out, p_ctrl):
    """Eq. 19 (R_v = R_f·u^(−e) in quadrature with R_f), mg/s from in to out."""
    v = AXI
    dp = delta_p(p_in, p_out, p_ctrl, v["ain"], v["aout"])
    if dp <= v["pclose"]:
        return 0.0
    u = (dp - v["pclose"]) / (v["ptrans"] - v["pclose"])
    return root(p_in ** 2 - p_out ** 2) / (v["Rf"] * np.sqrt(1.0 + u ** (-2.0 * v["e"])))


@functools.cache
def limit_cycle(t_end=24.0, settle=8.0, v_stub=V_STUB):
    """(period s, p_min kPa, p_max kPa) of the tank's cycle after ``settle`` s, with a
    ``v_stub`` mL stub at the valve output."""
    c_out, c_tank = capacitance(v_stub), capacitance(V_TANK)

    def rhs(t, y):
        p_out, p_tank = y
        q_out = root(p_out ** 2 - p_tank ** 2) / R_OUT
        q_vent = root(p_tank ** 2 - P_L ** 2) / R_VENT
        return [(valve(P_H, p_out, p_tank) - q_out) / c_out, (q_out - q_vent) / c_tank]

    out0 = brentq(lambda x: valve(P_H, x, P_L) - root(x * x - P_L * P_L) / R_OUT, P_L, P_H)
    t = np.arange(0.0, t_end + 1e-9, 1e-3)
    sol = solve_ivp(rhs, (0.0, t[-1]), [out0, P_L], method="Radau", t_eval=t, rtol=1e-8,
                    atol=1e-8)
    assert sol.success, sol.message
    late = t > settle
    p = sol.y[1]
    mid = 0.5 * (p[late].min() + p[late].max())
    i = np.flatnonzero((p[:-1] < mid) & (p[1:] >= mid) & late[:-1])
    crossings = t[i] + (mid - p[i]) / (p[i + 1] - p[i]) * (t[i + 1] - t[i])
    return float(np.mean(np.diff(crossings))), float(p[late].min()), float(p[late].max())
