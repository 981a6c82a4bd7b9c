"""Units: convert user quantities to pneunet's internal units (pint does the work).

Internal units (see :mod:`pneunet.physics.gas`): kPa absolute, mg/s, kPa·s/mg, mL, mm, s, K.

Each *slot* (a parameter's kind) has one internal unit.  Two pneumatic
conventions go beyond plain unit conversion:

* **gauge pressure** — a pressure unit with a trailing ``g`` (``200kPag``,
  ``4.96barg``, ``72psig``) is relative to the ambient pressure, which is added
  when converting to an absolute pressure;
* **normal volume flow** — a volume flow (``40L/min``, ``slpm``) in a mass-flow
  slot means litres at normal conditions (0 °C, 101.325 kPa) and is converted
  with the gas's normal density; in a liquid circuit it is the liquid's own volume
  (``gas`` is then a :class:`~pneunet.physics.liquids.Liquid`; ``slpm``/``sccm`` refused).
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass

from ..common.errors import ParameterError
from .gas import AIR, STANDARD_ATMOSPHERE_KPA, Gas
from .liquids import Liquid

#: slot -> (internal unit, pint dimensionality written as a unit of that slot)
SLOTS = {
    "pressure": "kPa",       # absolute pressure
    "pressure_difference": "kPa",
    "flow": "mg/s",
    "resistance": "kPa*s/mg",
    "volume": "mL",
    "length": "mm",
    "time": "s",
    "temperature": "K",
    "frequency": "Hz",
    "compliance": "mL/kPa",  # volume per pressure of an elastic volume
    "dimensionless": "",
    "mass": "kg",            # mechanical loads (mckibben)
    "force": "N",
    "stiffness": "N/m",
    "damping": "N*s/m",
    "angle": "deg",
    "density": "kg/m^3",     # = mg/mL (a user fluid: .fluid)
    "viscosity": "Pa*s",
    "molar_mass": "g/mol",
}

#: common units converted without loading pint (its registry takes ~0.5 s to build):
#: (unit, slot) -> factor to the slot's internal unit.  tests/netlist/test_units.py
#: checks every entry against pint.
FAST_FACTORS = {
    **{(u, slot): f for slot in ("pressure", "pressure_difference") for u, f in (
        ("kPa", 1.0), ("Pa", 1e-3), ("hPa", 0.1), ("MPa", 1e3), ("bar", 100.0),
        ("mbar", 0.1), ("psi", 6.894757293168361), ("atm", 101.325))},
    ("mg/s", "flow"): 1.0, ("g/s", "flow"): 1e3, ("kg/s", "flow"): 1e6,
    ("kPa*s/mg", "resistance"): 1.0, ("Pa*s/mg", "resistance"): 1e-3,
    ("mL", "volume"): 1.0, ("ml", "volume"): 1.0, ("L", "volume"): 1e3, ("l", "volume"): 1e3,
    ("uL", "volume"): 1e-3, ("cm^3", "volume"): 1.0,
    ("mm", "length"): 1.0, ("cm", "length"): 10.0, ("m", "length"): 1e3, ("um", "length"): 1e-3,
    ("s", "time"): 1.0, ("ms", "time"): 1e-3, ("us", "time"): 1e-6, ("min", "time"): 60.0,
    ("K", "temperature"): 1.0, ("Hz", "frequency"): 1.0, ("kHz", "frequency"): 1e3,
    ("mL/kPa", "compliance"): 1.0, ("mL/bar", "compliance"): 0.01,
    ("kg", "mass"): 1.0, ("g", "mass"): 1e-3, ("N", "force"): 1.0, ("N/m", "stiffness"): 1.0,
    ("N/mm", "stiffness"): 1e3, ("N*s/m", "damping"): 1.0, ("deg", "angle"): 1.0,
    ("kg/m^3", "density"): 1.0, ("g/mL", "density"): 1e3, ("Pa*s", "viscosity"): 1.0,
    ("mPa*s", "viscosity"): 1e-3, ("g/mol", "molar_mass"): 1.0,
}

#: a unit's power written without ^ (``kg/m3``, ``cm3``): pint needs ``m^3``
_BARE_POWER = re.compile(r"(?<=[A-Za-z])([23])(?![\w^.])")


def pint_unit(unit: str) -> str:
    """``unit`` as pint reads it: ``kg/m3`` → ``kg/m^3`` (a digit after a unit's letters)."""
    return _BARE_POWER.sub(r"^\1", unit)

GAUGE_UNITS = ("kPag", "barg", "psig", "Pag", "MPag", "mbarg", "hPag", "atmg")
_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


@functools.lru_cache(maxsize=1)
def registry():
    """The shared pint registry (created on first use: pint is slow to import)."""
    import pint

    ureg = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    ureg.define("slpm = liter / minute")   # standard litre per minute (a normal flow)
    ureg.define("sccm = milliliter / minute")
    return ureg


@dataclass(frozen=True)
class Quantity:
    """A parsed literal: magnitude, unit text and whether the pressure is gauge."""

    magnitude: float
    unit: str
    gauge: bool = False


def split_quantity(text: str) -> Quantity:
    """Split ``'200 kPag'`` into magnitude 200, unit 'kPa', gauge True."""
    m = _QUANTITY.match(text)
    if not m:
        raise ParameterError(f"cannot read {text!r} as a number with a unit")
    magnitude, unit = float(m.group(1)), m.group(2)
    gauge = unit in GAUGE_UNITS
    if gauge:
        unit = unit[:-1]
    return Quantity(magnitude, unit, gauge)


def to_internal(value, unit: str, slot: str, *, gauge: bool = False,
                ambient_kpa: float = STANDARD_ATMOSPHERE_KPA, gas: Gas | Liquid = AIR,
                name: str = "value"):
    """Convert ``value`` (scalar or array) given in ``unit`` to the slot's internal unit.

    ``name`` is used in error messages ("Rout: R needs kPa·s/mg, got kPa"); ``gas`` gives
    the density of a volume flow in a flow slot (a Gas: normal litres; a Liquid: its own).
    """
    if slot not in SLOTS:
        raise ValueError(f"unknown slot {slot!r}")
    target = SLOTS[slot]
    if gauge and slot != "pressure":
        raise ParameterError(f"{name}: a gauge unit only makes sense for a pressure, got {unit}g")
    if not unit:
        converted = value
    elif (unit, slot) in FAST_FACTORS:
        converted = value * FAST_FACTORS[unit, slot]
    else:
        converted = _convert(value, unit, target, slot, gas, name)
    if gauge:
        converted = converted + ambient_kpa
    return converted


def _convert(value, unit, target, slot, gas, name):
    import pint

    ureg = registry()
    try:
        q = ureg.Quantity(value, pint_unit(unit))
    except Exception as exc:  # noqa: BLE001 - pint's parser raises many kinds on bad text
        # (UndefinedUnitError, ValueError, tokenize.TokenError for an unclosed '(' ...)
        raise ParameterError(f"{name}: unknown unit {unit!r}",
                             hint=f"{slot} is given in {target or 'no unit'}, e.g. "
                                  f"{example(slot)}") from exc
    try:
        return q.to(target or "dimensionless").magnitude
    except pint.errors.DimensionalityError:
        pass
    if slot == "flow" and q.check("[volume]/[time]"):
        if isinstance(gas, Liquid) and any(u in unit for u in ("slpm", "sccm")):
            raise ParameterError(f"{name}: {unit} is a gas unit (standard litres), and this "
                                 f"circuit holds {gas.name}",
                                 hint=f"a volume flow of {gas.name} is written in L/min or "
                                      "mL/s (its own litres), or give the mass flow in g/s")
        normal_ml_s = q.to("mL/s").magnitude
        return normal_ml_s * gas.normal_density_mg_ml
    raise ParameterError(f"{name} needs {pretty(target)}, got {unit}",
                         hint=f"write it like {example(slot)}")


def pretty(unit: str) -> str:
    return unit.replace("*", "·") if unit else "a plain number"


_EXAMPLES = {
    "pressure": "496kPa, 4.96bar, 72psi or 200kPag (gauge)",
    "pressure_difference": "20kPa or 0.2bar",
    "flow": "870mg/s or 40L/min (normal litres)",
    "resistance": "0.566kPa*s/mg",
    "volume": "200mL or 0.2L",
    "length": "173mm or 1.2cm",
    "time": "5ms or 2s",
    "temperature": "293.15K or 20degC",
    "frequency": "2Hz",
    "compliance": "0.1mL/kPa or 10mL/bar",
    "dimensionless": "1.5",
    "mass": "200g or 0.2kg",
    "force": "5N",
    "stiffness": "500N/m or 0.5N/mm",
    "damping": "20N*s/m",
    "angle": "25deg",
    "density": "1260kg/m3 or 1.26g/mL",
    "viscosity": "1.41Pa*s or 1mPa*s",
    "molar_mass": "28.97g/mol",
}


def example(slot: str) -> str:
    return _EXAMPLES.get(slot, "")
