"""Liquids for hydraulic circuits (``.options fluid=water``): density, viscosity, bulk modulus.

Internal units as for gases: density in mg/mL (= kg/m³), dynamic viscosity in Pa·s, bulk
modulus in kPa.  The density is taken as constant in the flow laws; compressibility
enters only through the volumes' capacitance ρ·V/K (see :mod:`pneunet.physics.elements.volumes`).
"""
from __future__ import annotations

from dataclasses import dataclass

from .gas import check_fluid


@dataclass(frozen=True)
class Liquid:
    """A slightly compressible liquid."""

    name: str
    density: float        # mg/mL = kg/m³
    viscosity: float      # Pa·s
    bulk_modulus: float   # kPa

    def __post_init__(self):
        check_fluid(self.name, "liquid", rho=self.density, mu=self.viscosity,
                    K=self.bulk_modulus)

    @property
    def normal_density_mg_ml(self) -> float:
        """The density a volume flow of this liquid is converted with, mg/mL: its own
        (``1L/min`` of water is a litre of water; see :func:`pneunet.physics.units.to_internal`)."""
        return self.density


#: water at 20 °C; ISO VG 32 hydraulic oil at 40 °C (32 mm²/s)
WATER = Liquid("water", 998.2, 1.002e-3, 2.18e6)
HYDRAULIC_OIL = Liquid("hydraulic_oil", 857.0, 0.0274, 1.5e6)
LIQUIDS = {liquid.name: liquid for liquid in (WATER, HYDRAULIC_OIL)}
