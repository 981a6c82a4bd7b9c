"""Line with its own volume: ``tube`` (issue 12), N lumped segments, gas or liquid.

A tube of length L and inner diameter D becomes N segment elements in series
(``NAME.s1`` … ``NAME.sN``, junction nodes ``NAME.1`` … ``NAME.N-1``).  Each segment
has the flow resistance of length L/N and stores half its gas volume π/4·D²·L/N at
each of its two ends: a junction holds one segment volume, each tube end a half.

Flow law of a segment (isothermal ideal gas, Δ = p_a² − p_b², kPa²):

* with ``f`` given: eq. 6 (Weymouth, Fanning f), Δ = R²·ṁ², R as ``pipe``;
* without: laminar Hagen–Poiseuille, ṁ_lam = π·D⁴·Δ/(256·μ·R_s·T·L), blended with
  turbulent Blasius flow (Fanning f = 0.0791·Re^(−1/4), Re = 4ṁ/(π·D·μ)),
  ṁ_turb = (Δ/B)^(4/7), by the smooth minimum ṁ = (ṁ_lam^(−4) + ṁ_turb^(−4))^(−1/4);
* with ``roughness`` ε given: the same blend with Haaland's friction factor for the
  turbulent flow (:mod:`pneunet.physics.elements.friction`).

``volume=`` replaces the bore's volume (split over the segments); ``volume=0`` makes the
tube one part of kind ``tube_line``: the flow law alone, no storage at its ends.

In a liquid circuit a segment stores ρ·V/K at each end (as a ``volume``), Δ = p_a − p_b,
and the law is Darcy–Weisbach: laminar Hagen–Poiseuille blended with Haaland (ε = 0 when
not given; :mod:`pneunet.physics.elements.friction`), or with ``f``: Δp = 4f·8L·ṁ²/(π²·D⁵·ρ).
"""
from __future__ import annotations

import numpy as np

from ...common.errors import ParameterError
from ..gas import GAS_CONSTANT
from ..laws import signed_root
from .friction import line_flow
from .base import ElementFamily, ElementSpec, Param, register
from .resistors import check_line, pipe_resistance

BLEND = 4.0            # exponent of the smooth minimum of laminar and turbulent flow
BLASIUS = 0.0791       # Fanning f = BLASIUS·Re^(−1/4)
MAX_SEGMENTS = 20
MAX_RELATIVE_ROUGHNESS = 0.05  # Haaland's range: ε/D ≤ 0.05
DIAMETERS_PER_SEGMENT = 100.0


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
    """Gas or liquid line with resistance and volume, expanded into N lumped segments."""

    kind = "tube"
    description = "line with its own volume (gas or liquid): N segments of resistance and volume"
    ports = ("a", "b")
    storage_ports = (0, 1)
    fluids = ("gas", "liquid")
    params = {
        "length": Param("length", "tube length, mm", low=0.0, low_inclusive=False,
                        typical=(10.0, 1e5), plausible=(1.0, 1e6)),
        "diameter": Param("length", "inner diameter, mm", low=0.0, low_inclusive=False,
                          typical=(0.1, 50.0), plausible=(0.01, 500.0)),
        "segments": Param("dimensionless", "number of segments (default: from L/D, 4 to 20)",
                          low=1.0, high=1000.0, default=np.nan),
        "f": Param("dimensionless", "Fanning friction factor (default: laminar/Blasius)",
                   low=0.0, high=1.0, low_inclusive=False, default=np.nan),
        "roughness": Param("length", "wall roughness ε, mm (turbulent flow by Haaland; "
                           "default: a smooth wall)", low=0.0, default=np.nan),
        "volume": Param("volume", "volume the line holds, mL (default: its bore's "
                        "π/4·D²·L; 0: none, a resistance only)", low=0.0, default=np.nan),
    }

    @classmethod
    def check_spec(cls, spec):
        check_line(spec)
        p = spec.params
        n = p["segments"]
        if not np.isnan(n) and n != int(n):
            raise ParameterError(f"segments={n:g} must be a whole number", where=spec.where)
        if p["roughness"] > MAX_RELATIVE_ROUGHNESS * p["diameter"]:
            raise ParameterError(
                f"roughness={p['roughness']:g} mm is over {MAX_RELATIVE_ROUGHNESS:.0%} of the "
                f"bore {p['diameter']:g} mm", where=spec.where,
                hint="Haaland's friction factor covers ε/D ≤ 0.05; check the unit (e.g. "
                     "roughness=0.0015mm for drawn tubing)")

    @classmethod
    def expand(cls, spec):
        """N segment elements ``NAME.s1`` … joined at nodes ``NAME.1`` … (see module doc)."""
        p = spec.params
        if p["volume"] == 0:  # no volume: one resistance, no storage at its ends
            return [ElementSpec("tube_line", spec.name, spec.nodes, {**p, "segments": 1.0},
                                spec.span)]
        n = default_segments(p["length"], p["diameter"]) if np.isnan(p["segments"]) \
            else int(p["segments"])
        if n == 1:
            return [spec]
        nodes = [spec.nodes[0], *(f"{spec.name}.{k}" for k in range(1, n)), spec.nodes[1]]
        part = {**p, "length": p["length"] / n, "segments": 1.0, "volume": p["volume"] / n}
        return [ElementSpec(spec.kind, f"{spec.name}.s{k + 1}", (nodes[k], nodes[k + 1]),
                            dict(part), spec.span) for k in range(n)]

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts, gas, liquid = context.options, context.gas, context.options.liquid
        length, diameter, self._f = self.column("length"), self.column("diameter"), self.column("f")
        roughness = self.column("roughness")
        given = self.column("volume")
        half_volume = np.where(np.isnan(given), np.pi / 4 * diameter ** 2 * length * 1e-3,
                               given) / 2  # mL
        self._explicit = ~np.isnan(self._f)
        self._liquid = liquid is not None
        # Haaland where ε is given or the fluid is a liquid (not where f is given)
        self._haaland = ~self._explicit & (self._liquid | ~np.isnan(roughness))
        f_or_1 = np.where(self._explicit, self._f, 1.0)  # a placeholder f: np.where drops it
        length_m, diameter_m = length * 1e-3, diameter * 1e-3
        if self._liquid:
            self._half_c = liquid.density * half_volume / liquid.bulk_modulus
            mu = liquid.viscosity
            self._kappa = 8.0 * length_m / (np.pi ** 2 * diameter_m ** 5 * liquid.density)
            self._to_si, self._band = 1e3, opts.flow_band / (2.0 * opts.ambient)  # kPa → Pa
            # Δp = 4f·κ·ṁ² (SI) → Δp[kPa] = R²·ṁ[mg/s]², R = √(4f·κ·1e-15)
            self._r = np.sqrt(4.0 * f_or_1 * self._kappa * 1e-15)
        else:
            self._half_c = gas.capacitance(half_volume, opts.temperature)
            self._r = pipe_resistance(length, diameter, f_or_1, opts.temperature,
                                      gas.molar_mass_g_mol)
            mu = gas.viscosity(opts.temperature)
            if np.isnan(mu) and not self._explicit.all():
                raise ParameterError(f"tube: no viscosity known for gas {gas.name!r}",
                                     where=specs[0].where,
                                     hint="give f= for eq. 6, or the gas's mu (.fluid)")
            self._a, self._b = laminar_turbulent_coefficients(length, diameter, opts.temperature,
                                                              gas.molar_mass_g_mol, mu)
            rs_t = GAS_CONSTANT * opts.temperature / (gas.molar_mass_g_mol * 1e-3)
            self._kappa = 16.0 * length_m * rs_t / (np.pi ** 2 * diameter_m ** 5)
            self._to_si, self._band = 1e6, opts.flow_band  # kPa² → Pa²
        mu = np.nan_to_num(mu, nan=1.8e-5)  # a placeholder where f is given
        self._line = (16.0 * np.pi * diameter_m * mu * self._kappa, self._kappa, diameter_m,
                      mu, np.nan_to_num(roughness) / diameter)

    def _through(self, p_a, p_b, partials):
        """Segment flow a→b (mg/s) and its partials in p_a, p_b."""
        if self._liquid:
            delta, dd_a, dd_b = p_a - p_b, 1.0, -1.0
        else:
            delta, dd_a, dd_b = p_a * p_a - p_b * p_b, 2.0 * p_a, -2.0 * p_b
        root, slope = signed_root(delta, self._band, derivative=partials)
        mdot, slope = root / self._r, (slope / self._r if partials else None)
        if not self._liquid and not (self._explicit | self._haaland).all():
            m_b, s_b = blended_flow(delta, self._a, self._b, partials)
            mdot = np.where(self._explicit | self._haaland, mdot, m_b)
            slope = np.where(self._explicit | self._haaland, slope, s_b) if partials else None
        if self._haaland.any():
            m_h, s_h = line_flow(delta * self._to_si, *self._line, partials=partials)
            mdot = np.where(self._haaland, m_h * 1e6, mdot)
            slope = np.where(self._haaland, s_h * 1e6 * self._to_si, slope) if partials else None
        if not partials:
            return mdot, None, None
        return mdot, slope * dd_a, slope * dd_b

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


@register
class TubeLine(Tube):
    """A ``tube`` given ``volume=0``: its flow law alone, storing nothing at its ends."""

    kind = "tube_line"
    description = "line without volume (tube volume=0): the tube's flow law only"
    storage_ports = ()

    def outflows(self, t, p, pdot):
        q, dq_dp, _ = super().outflows(t, p, pdot)
        return q, dq_dp, None
