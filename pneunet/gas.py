"""Gas properties and the unit conventions of pneunet.

Internal units throughout the package: absolute pressure in kPa, mass flow in
mg/s, pneumatic resistance in kPa·s/mg, volume in mL, time in s, temperature in K.
With these, the capacitance of a volume C = M·V/(R·T) comes out in mg/kPa.
"""
from __future__ import annotations

from dataclasses import dataclass

STANDARD_ATMOSPHERE_KPA = 101.325
NORMAL_TEMPERATURE_K = 273.15  # DIN 1343 normal conditions: 0 °C, 101.325 kPa
ROOM_TEMPERATURE_K = 293.15  # the default gas temperature (.options temperature=)
GAS_CONSTANT = 8.314462618  # J/(mol·K) == kPa·L/(mol·K), CODATA 2018 (exact: N_A·k_B)


@dataclass(frozen=True)
class Gas:
    """An ideal gas, by molar mass M in g/mol."""

    name: str
    molar_mass_g_mol: float

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


AIR = Gas("air", 28.965)
NITROGEN = Gas("nitrogen", 28.0134)
GASES = {g.name: g for g in (AIR, NITROGEN)}
