"""Gas line with its own volume: ``tube`` (issue 12), N lumped segments.

A tube of length L and inner diameter D becomes N segment elements in series
(``NAME.s1`` … ``NAME.sN``, junction nodes ``NAME.1`` … ``NAME.N-1``).  Each segment
has the flow resistance of length L/N and stores half its gas volume π/4·D²·L/N at
each of its two ends: a junction holds one segment volume, each tube end a half.

Flow law of a segment (isothermal ideal gas, Δ = p_a² − p_b², kPa²):

* with ``f`` given: eq. 6 (Weymouth, Fanning f), Δ = R²·ṁ², R as ``pipe``;
* without: laminar Hagen–Poiseuille, ṁ_lam = π·D⁴·Δ/(256·μ·R_s·T·L), blended with
  turbulent Blasius flow (Fanning f = 0.0791·Re^(−1/4), Re = 4ṁ/(π·D·μ)),
  ṁ_turb = (Δ/B)^(4/7), by the smooth minimum ṁ = (ṁ_lam^(−4) + ṁ_turb^(−4))^(−1/4).
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..gas import GAS_CONSTANT
from ..laws import quadrature_flow
from . import register
from .base import ElementFamily, ElementSpec, Param
from .resistors import check_line, pipe_resistance

#: Sutherland viscosity μ = μ0·(T/T0)^1.5·(T0 + S)/(T + S): (μ0 Pa·s, T0 K, S K)
SUTHERLAND = {"air": (1.716e-5, 273.15, 110.4), "nitrogen": (1.663e-5, 273.15, 106.7)}
BLEND = 4.0            # exponent of the smooth minimum of laminar and turbulent flow
BLASIUS = 0.0791       # Fanning f = BLASIUS·Re^(−1/4)
MAX_SEGMENTS = 20
DIAMETERS_PER_SEGMENT = 100.0


def viscosity(gas_name: str, temperature_k):
    """Dynamic viscosity of the gas (Sutherland), Pa·s."""
    mu0, t0, s = SUTHERLAND[gas_name]
    return mu0 * (temperature_k / t0) ** 1.5 * (t0 + s) / (temperature_k + s)


def default_segments(length_mm: float, diameter_mm: float) -> int:
    """One segment per 100 diameters, at least 4 (the slowest mode of a closed line then
    within 1.3 %), at most 20."""
    per_aspect = np.ceil(length_mm / (DIAMETERS_PER_SEGMENT * diameter_mm))
    return int(min(MAX_SEGMENTS, max(4, per_aspect)))


def laminar_turbulent_coefficients(length_mm, diameter_mm, temperature_k, molar_mass_g_mol, mu):
    """(A, B) of Δ = A·ṁ (laminar) and Δ = B·ṁ^(7/4) (Blasius); Δ kPa², ṁ mg/s."""
    length, diameter = length_mm * 1e-3, diameter_mm * 1e-3
    rs_t = GAS_CONSTANT * temperature_k / (molar_mass_g_mol * 1e-3)  # R_s·T, J/kg
    a_si = 256.0 * mu * rs_t * length / (np.pi * diameter ** 4)      # Pa²·s/kg
    k_si = 64.0 * rs_t * length / (np.pi ** 2 * diameter ** 5)       # Δ = k·f·ṁ², SI
    b_si = k_si * BLASIUS * (4.0 / (np.pi * diameter * mu)) ** -0.25
    # Δ: Pa² = 1e6 kPa²; ṁ: kg/s = 1e-6 mg/s
    return a_si * 1e-12, b_si * 1e-6 * 1e-6 ** 1.75


def blended_flow(delta, a, b, partials=True):
    """ṁ(Δ) = sign(Δ)·(|Δ|/A)·(1 + u)^(−1/k), u = (ṁ_lam/ṁ_turb)^k, and dṁ/dΔ."""
    n = 4.0 / 7.0
    mag = np.abs(delta)
    u = (mag ** (1.0 - n) * b ** n / a) ** BLEND
    mdot = np.sign(delta) * mag / a * (1.0 + u) ** (-1.0 / BLEND)
    if not partials:
        return mdot, None
    return mdot, (1.0 + u) ** (-1.0 / BLEND - 1.0) * (1.0 + n * u) / a


@register
class Tube(ElementFamily):
    """Gas line with resistance and volume, expanded into N lumped segments."""

    kind = "tube"
    description = "gas line with its own volume: N segments of resistance and volume"
    ports = ("a", "b")
    storage_ports = (0, 1)
    params = {
        "length": Param("length", "tube length, mm", low=0.0, low_inclusive=False,
                        typical=(10.0, 1e5), plausible=(1.0, 1e6)),
        "diameter": Param("length", "inner diameter, mm", low=0.0, low_inclusive=False,
                          typical=(0.1, 50.0), plausible=(0.01, 500.0)),
        "segments": Param("dimensionless", "number of segments (default: from L/D, 4 to 20)",
                          low=1.0, high=1000.0, default=np.nan),
        "f": Param("dimensionless", "Fanning friction factor (default: laminar/Blasius)",
                   low=0.0, high=1.0, low_inclusive=False, default=np.nan),
    }

    @classmethod
    def check_spec(cls, spec):
        check_line(spec)
        n = spec.params["segments"]
        if not np.isnan(n) and n != int(n):
            raise ParameterError(f"segments={n:g} must be a whole number", where=spec.where)

    @classmethod
    def expand(cls, spec):
        """N segment elements ``NAME.s1`` … joined at nodes ``NAME.1`` … (see module doc)."""
        p = spec.params
        n = default_segments(p["length"], p["diameter"]) if np.isnan(p["segments"]) \
            else int(p["segments"])
        if n == 1:
            return [spec]
        nodes = [spec.nodes[0], *(f"{spec.name}.{k}" for k in range(1, n)), spec.nodes[1]]
        part = {**p, "length": p["length"] / n, "segments": 1.0}
        return [ElementSpec(spec.kind, f"{spec.name}.s{k + 1}", (nodes[k], nodes[k + 1]),
                            dict(part), spec.span) for k in range(n)]

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts, gas = context.options, context.gas
        length, diameter, self._f = self.column("length"), self.column("diameter"), self.column("f")
        self._half_c = gas.capacitance(np.pi / 8 * diameter ** 2 * length * 1e-3, opts.temperature)
        self._explicit = ~np.isnan(self._f)
        # eq. 6 where f is given (a placeholder f = 1 elsewhere: np.where drops it)
        self._r = pipe_resistance(length, diameter, np.where(self._explicit, self._f, 1.0),
                                  opts.temperature, gas.molar_mass_g_mol)
        if gas.name not in SUTHERLAND and not self._explicit.all():
            raise ParameterError(f"tube: no viscosity known for gas {gas.name!r}",
                                 where=specs[0].where, hint="give f= for eq. 6")
        mu = viscosity(gas.name, opts.temperature) if gas.name in SUTHERLAND else np.nan
        self._a, self._b = laminar_turbulent_coefficients(length, diameter, opts.temperature,
                                                          gas.molar_mass_g_mol, mu)

    def _through(self, p_a, p_b, partials):
        """Segment flow a→b (mg/s) and its partials in p_a, p_b."""
        m_q, da_q, db_q = quadrature_flow(p_a, p_b, self._r, self.context.options.flow_band,
                                          partials)
        m_l, slope = blended_flow(p_a * p_a - p_b * p_b, self._a, self._b, partials)
        mdot = np.where(self._explicit, m_q, m_l)
        if not partials:
            return mdot, None, None
        return (mdot, np.where(self._explicit, da_q, 2.0 * p_a * slope),
                np.where(self._explicit, db_q, -2.0 * p_b * slope))

    def outflows(self, t, p, pdot):
        mdot, d_a, d_b = self._through(p[:, 0], p[:, 1], True)
        q = np.stack([mdot, -mdot], axis=1) + self._half_c[:, None] * pdot
        dq_dp = np.empty((self.n, 2, 2))
        dq_dp[:, 0, 0], dq_dp[:, 0, 1] = d_a, d_b
        dq_dp[:, 1, 0], dq_dp[:, 1, 1] = -d_a, -d_b
        dq_dpdot = np.zeros((self.n, 2, 2))
        dq_dpdot[:, 0, 0] = dq_dpdot[:, 1, 1] = self._half_c
        return q, dq_dp, dq_dpdot

    def flows(self, t, p, pdot):
        mdot, _, _ = self._through(p[..., 0], p[..., 1], False)
        return np.stack([mdot, -mdot], axis=-1) + self._half_c[:, None] * pdot

    def signals(self, t, p):
        return {"mdot": ("mg/s", self._through(p[..., 0], p[..., 1], False)[0])}
