"""Numbers with units and SPICE scale factors, converted for a parameter slot.

The rule for the letters after a number (documented in docs/netlist.md):

1. If the letters are a unit of the slot's dimension, they are a unit:
   ``5ms`` (time), ``200mL`` (volume), ``1.2mm`` (length), ``1m`` in a length
   slot is one metre, ``293K`` in a temperature slot is kelvin.
2. Otherwise, if they are a SPICE scale factor — ``f p n u µ m k meg g t``
   (case-insensitive; ``m`` is milli, ``meg`` mega as in SPICE) — the number is
   scaled and read in the slot's internal unit: ``2k`` = 2000, ``5m`` = 0.005.
3. Otherwise they must be a unit (pint syntax, e.g. ``kPa*s/mg``, ``L/min``);
   a unit of the wrong dimension is an error naming the slot and its unit.

A trailing ``g`` on a pressure unit means gauge (``200kPag``): the ambient
pressure (``.options ambient=``) is added.  A bare number is in the internal
unit of the slot (kPa, mg/s, kPa·s/mg, mL, mm, s, K).
"""
from __future__ import annotations

import functools
import re

import numpy as np

from ..common.errors import NetlistError, ParameterError, SourceSpan

SCALE = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "m": 1e-3, "k": 1e3,
         "meg": 1e6, "g": 1e9, "t": 1e12}

_NUMBER = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(.*)$")


def split(text: str):
    """``'200kPag'`` -> (200.0, 'kPag'); None if the text does not start with a number."""
    m = _NUMBER.match(text)
    if not m:
        return None
    return float(m.group(1)), m.group(2)


#: scale-factor letters that are also units of a slot's dimension (``1m`` is a metre)
SCALE_LETTER_UNITS = {("m", "length"), ("µ", "length"),  # metre, micron
                      ("g", "mass"), ("t", "mass"), ("u", "mass")}  # gram, tonne, dalton


#: what a unit may look like before pint is asked (pint's parser is slow on long text:
#: ``1eee…`` with 10^5 letters took minutes)
_UNIT_TEXT = re.compile(r"[A-Za-zµ°%0-9_*/^.()·²³\-]{1,40}")


def plausible_unit(unit: str) -> bool:
    """True if ``unit`` could be a unit (at most 40 characters of unit syntax)."""
    return bool(_UNIT_TEXT.fullmatch(unit))


@functools.lru_cache(maxsize=512)
def _unit_dimension_matches(unit: str, slot: str) -> bool:
    """True if ``unit`` is a unit whose dimension fits ``slot``.

    Common units and the scale-factor letters are decided without pint (the
    tests check both tables against pint); anything else asks pint.
    """
    from ..physics.units import FAST_FACTORS

    if not plausible_unit(unit):
        return False
    if (unit, slot) in FAST_FACTORS:
        return True
    if unit.lower() in SCALE and unit == unit.lower():
        return (unit, slot) in SCALE_LETTER_UNITS
    return pint_dimension_matches(unit, slot)


def pint_dimension_matches(unit: str, slot: str) -> bool:
    """What pint says: is ``unit`` a unit whose dimension fits ``slot``?"""
    from ..physics.units import SLOTS, pint_unit, registry

    try:
        ureg = registry()
        q = ureg.Quantity(1.0, pint_unit(unit))
        target = SLOTS[slot]
        if slot == "flow" and q.check("[volume]/[time]"):
            return True
        return q.check(ureg.Quantity(1.0, target).dimensionality) if target else \
            q.dimensionless
    except Exception:  # noqa: BLE001 - any pint failure means "not a unit"
        return False


def convert(text: str, slot: str, span: SourceSpan, *, name: str, ambient: float, gas) -> float:
    """Convert a literal like ``496kPa``, ``2k`` or ``0.566`` for ``slot``."""
    from ..physics.units import example

    parts = split(text)
    if parts is None:
        raise NetlistError(f"{name}: cannot read {text!r} as a number",
                           span=span, hint=f"{slot} is written like {example(slot)}")
    return convert_magnitude(*parts, slot, span, name=name, ambient=ambient, gas=gas)


def convert_magnitude(magnitude, suffix: str, slot: str, span: SourceSpan, *, name: str,
                      ambient: float, gas):
    """:func:`convert` of a number already split from its unit ``suffix``; ``magnitude``
    may be an array (a TABLE column: one conversion for all its values)."""
    from ..physics.units import GAUGE_UNITS, SLOTS, example, pretty, to_internal

    if not suffix:
        return magnitude
    gauge = suffix in GAUGE_UNITS
    unit = suffix[:-1] if gauge else suffix
    if not gauge and not _unit_dimension_matches(unit, slot) and suffix.lower() in SCALE:
        return magnitude * SCALE[suffix.lower()]
    if slot == "dimensionless" and not gauge:
        raise NetlistError(f"{name} is a plain number, got unit {_cut(suffix)!r}", span=span,
                           hint="write it without a unit (SPICE scale factors like 2k are allowed)")
    if not plausible_unit(unit):
        raise NetlistError(f"{name}: unknown unit {_cut(suffix)!r}", span=span,
                           hint=f"{name} needs {pretty(SLOTS[slot])}, e.g. {example(slot)}")
    try:
        value = to_internal(magnitude, unit, slot, gauge=gauge, ambient_kpa=ambient, gas=gas,
                            name=name)
        return np.asarray(value, float) if isinstance(magnitude, np.ndarray) else float(value)
    except ParameterError as err:
        if err.message.startswith(f"{name}: unknown unit"):
            raise NetlistError(f"{name}: unknown unit {_cut(suffix)!r}", span=span,
                               hint=f"{name} needs {pretty(SLOTS[slot])}, e.g. {example(slot)}") \
                from None
        raise NetlistError(err.message, span=span, hint=err.hint) from None


#: internal units tried, in order, for a unit in an expression or a .param value
_DIMENSION_ORDER = ("pressure", "flow", "resistance", "volume", "length", "time",
                    "temperature", "frequency", "compliance", "mass", "force", "stiffness",
                    "damping", "angle")


def number_in_expression(text: str, span: SourceSpan, ambient: float = 101.325) -> float:
    """A number inside an expression: scale factor, or a unit -> internal unit of its dimension."""
    magnitude, suffix = split(text)
    if not suffix:
        return magnitude
    if suffix.lower() in SCALE:
        if suffix in ("g", "t", "N"):
            _ambiguous_scale(text, suffix, span)
        return magnitude * SCALE[suffix.lower()]
    from ..physics.units import GAUGE_UNITS, to_internal

    gauge = suffix in GAUGE_UNITS
    unit = suffix[:-1] if gauge else suffix
    # N·s/m (a damping) has the dimension of a mass flow: a unit with newtons is mechanical
    order = _MECHANICAL_FIRST if "N" in unit else _DIMENSION_ORDER
    for slot in order:
        if _unit_dimension_matches(unit, slot):
            return float(to_internal(magnitude, unit, slot, gauge=gauge,
                                     ambient_kpa=_AMBIENT.get("kPa", ambient)))
    raise NetlistError(f"unknown unit or scale factor {_cut(suffix)!r} in {_cut(text)!r}",
                       span=span, hint="scale factors: f p n u m k meg g t; units of every "
                                       "parameter: kPa, mg/s, kPa*s/mg, mL, mm, s, K, Hz, "
                                       "mL/kPa, kg, N, N/m, N*s/m, deg")


_MECHANICAL_FIRST = ("force", "stiffness", "damping", *_DIMENSION_ORDER)


def _ambiguous_scale(text, suffix, span) -> None:
    """A located warning: ``200g``, ``2t``, ``5N`` in an expression are SPICE giga, tera,
    nano (no pneumatic quantity is that large or small), not gram, tonne, newton."""
    import warnings

    from ..common.errors import InputWarning

    unit = {"g": "gram", "t": "tonne", "N": "newton"}[suffix]
    warnings.warn(InputWarning(
        f"{text} in an expression or .param is {split(text)[0]:g}·{SCALE[suffix.lower()]:g} "
        f"(SPICE scale factor {suffix!r}), not {unit}s", span=span,
        hint=f"for {unit}s write the unit out ({split(text)[0]:g}{unit}) or give the value "
             "where it is used (mass=200g, preload=5N)"), stacklevel=4)


# ambient pressure used for gauge units inside expressions (set while elaborating)
_AMBIENT: dict[str, float] = {}


def set_expression_ambient(kpa: float) -> None:
    _AMBIENT["kPa"] = kpa


#: nonzero magnitudes below this (in the slot's internal unit) are refused: no pneumatic
#: quantity is that small, and the solver divides by them
TINY = 1e-100


def check_number(value: float, text: str, span: SourceSpan, name: str = "",
                 tiny: bool = True) -> float:
    """``value`` read from ``text``, or an error at ``span``: overflow to inf, NaN, a
    nonzero literal that underflows to 0, and (``tiny``) a nonzero value below :data:`TINY`."""
    import math

    label = f"{name}: " if name else ""
    if math.isnan(value):
        raise NetlistError(f"{label}{_cut(text)} is not a number (NaN)", span=span)
    if math.isinf(value):
        raise NetlistError(f"{label}{_cut(text)} is too large (beyond ±1.8e308, it overflows "
                           "to infinity)", span=span, hint="check the exponent and the units")
    literal = _NUMBER.match(text)
    if value == 0 and literal and re.search(r"[1-9]", literal.group(1).split("e")[0]
                                            .split("E")[0]):
        raise NetlistError(f"{label}{_cut(text)} underflows to 0", span=span,
                           hint="check the exponent; write 0 if zero is meant")
    if tiny and value != 0 and abs(value) < TINY:
        raise NetlistError(f"{label}{_cut(text)} is {abs(value):.3g} in internal units, too "
                           f"small to compute with (|x| < {TINY:g})", span=span,
                           hint="check the exponent and the unit; write 0 if zero is meant")
    return value


def dimension_of(unit: str) -> str | None:
    """The slot whose dimension ``unit`` has (``'kPa'`` -> ``'pressure'``), or None."""
    from ..physics.units import GAUGE_UNITS

    unit = unit[:-1] if unit in GAUGE_UNITS else unit
    return next((slot for slot in _DIMENSION_ORDER if _unit_dimension_matches(unit, slot)), None)


def _cut(text: str, width: int = 40) -> str:
    return text if len(text) <= width else text[:width - 1] + "…"
