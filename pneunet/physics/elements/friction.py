"""Darcy–Weisbach friction of a fully developed line flow, for gas and liquid lines.

A line of length L and bore D carrying ṁ (kg/s), Reynolds number Re = 4ṁ/(π·D·μ), in SI
units, with the driving difference Δ and line constant κ of its fluid:

* liquid (density ρ):                 Δ = p_a − p_b (Pa),    κ = 8·L/(π²·D⁵·ρ)
* isothermal ideal gas (R_s·T):       Δ = p_a² − p_b² (Pa²), κ = 16·L·R_s·T/(π²·D⁵)

Turbulent flow: Δ = κ·f(Re)·ṁ² with Haaland's Darcy friction factor for wall roughness ε

    1/√f = −1.8·log10((ε/D/3.7)^1.11 + 6.9/Re_h),    Re_h = (Re⁴ + 100⁴)^(1/4)

(Re_h: Haaland's formula has no root below Re ≈ 24; the floor keeps the turbulent branch
finite and smooth there, where the laminar law rules; above Re = 400 it changes f by
< 0.02 %).  ṁ(Δ) is implicit: Newton's method on ln ṁ, from an explicit Colebrook guess.
Laminar flow (f = 64/Re): Δ = A·ṁ, A = 16·π·D·μ·κ (Hagen–Poiseuille).  The two blend as
the gas ``tube`` does (:mod:`pneunet.physics.elements.tubes`): ṁ = (ṁ_lam⁻⁴ + ṁ_turb⁻⁴)^(−1/4).
"""
from __future__ import annotations

import numpy as np

BLEND = 4.0          # exponent of the smooth minimum of laminar and turbulent flow
RE_FLOOR = 100.0     # Haaland's Reynolds number is floored smoothly at this value
_LN10 = np.log(10.0)
_NEWTON_STEPS = 30
_NEWTON_TOL = 1e-13  # on ln ṁ


def haaland(reynolds, relative_roughness):
    """Darcy friction factor f (Haaland 1983) at Re (floored as the module doc says), and
    d ln f / d ln Re."""
    re_h = (reynolds ** 4 + RE_FLOOR ** 4) ** 0.25
    beta = (relative_roughness / 3.7) ** 1.11 + 6.9 / re_h
    s = -1.8 * np.log10(beta)                       # 1/√f
    dlnf_dlnre = -3.6 * 6.9 / (s * beta * _LN10 * re_h) * (reynolds / re_h) ** 4
    return s ** -2.0, dlnf_dlnre


def turbulent_flow(mag, kappa, diameter, mu, relative_roughness):
    """|ṁ| (kg/s) solving |Δ| = κ·f(Re)·ṁ² (Haaland), and d ln ṁ/d ln |Δ|; ``mag`` = |Δ|
    > 0 (SI, arrays broadcast)."""
    x = np.sqrt(mag / kappa)                        # ṁ·√f
    c = 4.0 / (np.pi * diameter * mu)               # Re per kg/s
    psi = np.maximum(c * x, 50.0)                   # Re·√f, floored for the guess
    y = np.log(x * -2.0 * np.log10(relative_roughness / 3.7 + 2.51 / psi))  # Colebrook
    target = np.log(mag / kappa)
    for _ in range(_NEWTON_STEPS):
        f, g = haaland(c * np.exp(y), relative_roughness)
        step = (2.0 * y + np.log(f) - target) / (2.0 + g)
        y = y - step
        if np.all(np.abs(step) < _NEWTON_TOL):
            break
    _, g = haaland(c * np.exp(y), relative_roughness)
    return np.exp(y), 1.0 / (2.0 + g)


def line_flow(delta, laminar, kappa, diameter, mu, relative_roughness, partials=True):
    """Signed ṁ (kg/s) through the line at Δ (SI, see module doc), laminar coefficient
    ``laminar`` = A, and dṁ/dΔ (None unless ``partials``)."""
    mag = np.maximum(np.abs(delta), 1e-300)
    m_lam = mag / laminar
    m_turb, dln_turb = turbulent_flow(mag, kappa, diameter, mu, relative_roughness)
    u = (m_lam / m_turb) ** BLEND
    mdot = m_lam * (1.0 + u) ** (-1.0 / BLEND)
    signed = np.sign(delta) * mdot
    if not partials:
        return signed, None
    # dṁ/d|Δ| = ṁ^(k+1)·(ṁ_lam^−k·(1/|Δ|) + ṁ_turb^−k·(d ln ṁ_turb/d|Δ|)), k = BLEND
    slope = (1.0 + u) ** (-1.0 / BLEND - 1.0) * (1.0 + u * dln_turb) / laminar
    return signed, slope
