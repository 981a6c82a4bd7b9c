"""Values that are allowed but not what was meant: a bare number far outside a parameter's
usual range (``theta0=0.35`` is 0.35°, ``mass=200`` is 200 kg, a tube ``length=3`` is 3 mm)
and any value outside the range its law makes sense in (``length=3M`` is 3 µm: ``M`` is
SPICE milli).  Each is a located :class:`~pneunet.common.errors.InputWarning` naming how the value
was read and, for a bare number, the units that would put it in range.
"""
from __future__ import annotations

import warnings

from ..common.errors import InputWarning
from .values import split

#: units a bare number may have been meant in, per slot (tried for the hint)
ALTERNATIVES = {
    "length": ("m", "cm", "um"), "mass": ("g", "t"), "angle": ("rad",),
    "pressure": ("bar", "kPag", "barg", "psig"), "stiffness": ("N/mm",),
    "volume": ("L", "uL"), "time": ("ms", "min"), "force": ("kN",), "temperature": ("degC",),
}


def check(param, key: str, value: float, text: str, span, label: str) -> None:
    """Warn (once per call) when ``value`` of ``param`` (read from ``text``) lies outside
    its usual range as a bare number, or outside its plausible range at all."""
    from ..physics.units import GAUGE_UNITS, SLOTS, pretty, to_internal

    if param.typical is None or value == 0 and param.default == 0:
        return  # zero: "none" (no spring, no mass)
    parts = split(text)
    bare = parts is not None and not parts[1]
    lo, hi = param.typical
    wide = param.plausible or (lo / 100.0 if lo > 0 else lo, hi * 100.0)
    unit = pretty(SLOTS[param.slot])
    usual = f"usual {_g(lo)}–{_g(hi)} {unit}"
    if bare and not lo <= value <= hi:
        meant = []
        for alt in ALTERNATIVES.get(param.slot, ()):
            gauge = alt in GAUGE_UNITS
            try:
                other = float(to_internal(parts[0], alt[:-1] if gauge else alt, param.slot,
                                          gauge=gauge))
            except Exception:  # noqa: BLE001 - a unit pint lacks: no suggestion
                continue
            if lo <= other <= hi and not any(f"({_g(other)} " in m for m in meant):
                meant.append(f"{text}{alt} ({_g(other)} {unit})")
        warnings.warn(InputWarning(
            f"{label}={text} is read as {_g(value)} {unit} (a bare number is in {unit}), "
            f"outside the {usual}", span=span,
            hint=("did you mean " + " or ".join(meant) + "? " if meant else "") +
                 f"write the unit to say what is meant, e.g. {label}={_g(value)}{unit}"
                 .replace("·", "*")), stacklevel=3)
    elif not wide[0] <= value <= wide[1]:
        scale = parts[1] if parts else ""
        why = (" (M is SPICE milli, as m; mega is meg)" if scale == "M" else "")
        warnings.warn(InputWarning(
            f"{label}={text} is {_g(value)} {unit}{why}, far outside the {usual}: its law "
            "does not describe such an element", span=span,
            hint=f"check the number and its unit ({param.doc})"), stacklevel=3)


def _options():
    from ..physics.elements.base import Param

    return {"temperature": Param("temperature", "gas temperature, K", typical=(200.0, 400.0),
                                 plausible=(150.0, 1000.0)),
            "ambient": Param("pressure", "ambient pressure, kPa absolute",
                             typical=(50.0, 120.0), plausible=(10.0, 1000.0))}


def check_option(key: str, value: float, word) -> None:
    """Warn about an ``.options`` value far from the usual (``temperature=20`` is 20 K)."""
    param = _options().get(key)
    if param is not None:
        check(param, key, value, word.text, word.span, key)


def check_level(value: float, word, label: str) -> None:
    """Warn about a pressure source's waveform level far from the usual (``PULSE(0 200)``:
    0 kPa absolute is a vacuum)."""
    from ..physics import elements

    if isinstance(getattr(word, "text", None), str):
        check(elements.family("pressure_source").params["value"], label, value, word.text,
              word.span, label)


def _g(x: float) -> str:
    return f"{x:.4g}"
