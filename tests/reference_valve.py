"""The paper's six-parameter valve law written independently of pneunet.physics.laws.

Eq. 19 in its published form (the variable resistance R_v = R_f·u^(−e) in quadrature
with R_f), eq. 25 as two explicit branches (a_in on the port with the higher pressure),
plain Python floats, exact root: the reference the valve-law tests compare against.
Units: kPa absolute, mg/s, kPa·s/mg.
"""
import math


def delta_p(p1, p2, p_ctrl, ain, aout):
    """Eq. 25: Δp = a_in·p1 + a_out·p2 − p_ctrl if p1 > p2, a_in·p2 + a_out·p1 − p_ctrl
    if p1 < p2 (kPa)."""
    if p1 >= p2:
        return ain * p1 + aout * p2 - p_ctrl
    return ain * p2 + aout * p1 - p_ctrl


def flow(p1, p2, p_ctrl, Rf, pclose, ptrans, e, ain, aout):
    """Eq. 19 with eq. 25: signed flow port 1 → port 2 (mg/s); 0 while Δp ≤ p_close."""
    dp = delta_p(p1, p2, p_ctrl, ain, aout)
    if dp <= pclose or p1 == p2:
        return 0.0
    u = (dp - pclose) / (ptrans - pclose)
    mag = math.sqrt(abs(p1 ** 2 - p2 ** 2)) / (Rf * math.sqrt(1.0 + u ** (-2.0 * e)))
    return mag if p1 > p2 else -mag
