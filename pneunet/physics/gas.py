"""Gas properties and the unit conventions of pneunet.

Internal units throughout the package: absolute pressure in kPa, mass flow in
mg/s, pneumatic resistance in kPa·s/mg, volume in mL, time in s, temperature in K.
With these, the capacitance of a volume C = M·V/(R·T) comes out in mg/kPa.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..common.errors import ParameterError

STANDARD_ATMOSPHERE_KPA = 101.325
NORMAL_TEMPERATURE_K = 273.15  # DIN 1343 normal conditions: 0 °C, 101.325 kPa
ROOM_TEMPERATURE_K = 293.15  # the default gas temperature (.options temperature=)
GAS_CONSTANT = 8.314462618  # J/(mol·K) == kPa·L/(mol·K), CODATA 2018 (exact: N_A·k_B)


#: a fluid's name: one netlist word, as ``.options fluid=NAME`` reads it
FLUID_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_fluid(name: str, what: str, **positive: float) -> None:
    """A ParameterError unless ``name`` is a word and every value is finite and > 0."""
    if not isinstance(name, str) or not FLUID_NAME.fullmatch(name):
        raise ParameterError(f"{what} name {name!r} is not a word",
                             hint="letters, digits and _, starting with a letter")
    for key, value in positive.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                not math.isfinite(value) or value <= 0:
            raise ParameterError(f"{what} {name}: {key} must be a finite number > 0, got "
                                 f"{value!r}")


@dataclass(frozen=True)
class Gas:
    """An ideal gas, by molar mass M in g/mol; its viscosity μ0 (Pa·s) at t0 (K), and
    Sutherland's constant S (K) for μ(T) = μ0·(T/t0)^1.5·(t0 + S)/(T + S) (NaN: μ0 at any
    T; μ0 NaN: unknown, a ``tube`` then needs ``f=``); its heat-capacity ratio γ = c_p/c_v
    (the thermal elements' default)."""

    name: str
    molar_mass_g_mol: float
    mu0: float = math.nan
    t0: float = 273.15
    sutherland: float = math.nan
    gamma: float = 1.4

    def __post_init__(self):
        check_fluid(self.name, "gas", molar_mass=self.molar_mass_g_mol, t0=self.t0,
                    **{k: v for k, v in (("mu", self.mu0), ("S", self.sutherland))
                       if not (isinstance(v, float) and math.isnan(v))})
        if not 1.0 < self.gamma <= 5.0 / 3.0:
            raise ParameterError(f"gas {self.name}: gamma = c_p/c_v must lie in (1, 5/3], got "
                                 f"{self.gamma:g}", hint="1.4 diatomic (air), 1.667 monatomic")
        if math.isnan(self.mu0) and not math.isnan(self.sutherland):
            raise ParameterError(f"gas {self.name}: Sutherland's S needs the viscosity mu "
                                 "at T0", hint="e.g. mu=1.87e-5Pa*s T0=273.15K S=79.4K")

    def viscosity(self, temperature_k: float) -> float:
        """Dynamic viscosity at ``temperature_k``, Pa·s (NaN when not known)."""
        if math.isnan(self.sutherland):
            return self.mu0
        return (self.mu0 * (temperature_k / self.t0) ** 1.5 * (self.t0 + self.sutherland)
                / (temperature_k + self.sutherland))

    def capacitance(self, volume_ml, temperature_k=ROOM_TEMPERATURE_K):
        """Isothermal capacitance C = M·V/(R·T) of a volume, in mg/kPa."""
        # M [mg/mol] * V [mL] / (R [kPa·mL/(mol·K)] * T [K])
        return self.molar_mass_g_mol * 1e3 * volume_ml / (GAS_CONSTANT * 1e3 * temperature_k)

    @property
    def normal_density_mg_ml(self) -> float:
        """Density at normal conditions (0 °C, 101.325 kPa), in mg/mL (= kg/m³)."""
        return STANDARD_ATMOSPHERE_KPA * self.molar_mass_g_mol / (GAS_CONSTANT * NORMAL_TEMPERATURE_K)

    def normal_l_min(self, mdot_mg_s):
        """Convert a mass flow in mg/s to normal litres per minute (NL/min)."""
        return mdot_mg_s / self.normal_density_mg_ml * 60.0 / 1e3

    def mg_s(self, normal_l_min):
        """Convert normal litres per minute to a mass flow in mg/s."""
        return normal_l_min * 1e3 / 60.0 * self.normal_density_mg_ml


# Sutherland constants: White, Viscous Fluid Flow (air 1.716e-5 Pa·s, 110.4 K; N2 1.663e-5, 106.7)
AIR = Gas("air", 28.965, 1.716e-5, 273.15, 110.4)
NITROGEN = Gas("nitrogen", 28.0134, 1.663e-5, 273.15, 106.7)
GASES = {g.name: g for g in (AIR, NITROGEN)}
