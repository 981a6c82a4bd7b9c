"""Reference laws written independently of pneunet, shared by the tube and piping tests.

A line of gas at rest between two pressures, isothermal air at 20 °C, SI units: the
laminar (Hagen–Poiseuille) and smooth-tube turbulent (Blasius, eq. 6 of the paper with
f = 0.0791·Re^(−1/4)) mass flows, blended as docs/netlist.md documents for ``tube``.
"""
import numpy as np

R_AIR = 8.314462618 / 28.965e-3   # J/(kg·K)
T = 293.15                  # K, pneunet's default temperature
MU = 1.813e-5               # Pa·s, air at 20 °C


def line_flow(p_a, p_b, dx, d):
    """kg/s through dx metres of line of bore d (m) between pressures p_a, p_b (Pa):
    ṁ = (ṁ_lam⁻⁴ + ṁ_turb⁻⁴)^(−1/4), signed."""
    delta = p_a ** 2 - p_b ** 2
    lam = np.abs(delta) * np.pi * d ** 4 / (256 * MU * R_AIR * T * dx)
    b = 64 * R_AIR * T * dx / (np.pi ** 2 * d ** 5) * 0.0791 * (4 / (np.pi * d * MU)) ** -0.25
    turb = (np.abs(delta) / b) ** (4 / 7)
    with np.errstate(divide="ignore"):
        return np.where(delta == 0, 0.0, np.sign(delta) * (lam ** -4 + turb ** -4) ** -0.25)
