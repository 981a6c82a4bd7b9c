"""The text beside each symbol: the element's name (with its count) and key values in
pneunet's units (kPa absolute, kPa·s/mg, mL, mm, mg/s)."""
from __future__ import annotations

import math

#: (parameter, unit) shown for each kind, in order; the first few that are set are shown
KEY_VALUES = {
    "resistor": [("R", "kPa·s/mg")], "thermal_inlet": [("r", "")],
    "orifice": [("diameter", "mm"), ("Cd", "")],
    "pipe": [("length", "mm"), ("diameter", "mm")], "tube": [("length", "mm"), ("diameter", "mm")],
    "tube_line": [("length", "mm"), ("diameter", "mm")],
    "laminar_tube": [("length", "mm"), ("diameter", "mm")],
    "volume": [("V", "mL")], "thermal_volume": [("V", "mL"), ("tau", "s")],
    "thermal_chamber": [("V", "mL"), ("tau", "s")],
    "actuator": [("V", "mL"), ("length", "mm"), ("diameter", "mm")],
    "accumulator": [("V0", "mL"), ("k", "mL/kPa")],
    "check_valve": [("R", "kPa·s/mg"), ("pcrack", "kPa")],
    "hysteretic_check_valve": [("pcrack", "kPa"), ("preseat", "kPa")],
    "mckibben": [("L0", "mm"), ("mass", "kg")], "mckibben_static": [("L0", "mm"), ("mass", "kg")],
    "mckibben_damped": [("L0", "mm"), ("mass", "kg")],
    "mckibben_inertial": [("L0", "mm"), ("mass", "kg")],
}


def name_line(part) -> str:
    """``Rout``, or ``Xcell[0:7].Vn1 ×8`` for an array drawn once."""
    return part.label + (f" ×{part.count}" if part.count > 1 else "")


def value_line(part) -> str:
    """The part's key values, e.g. ``R=1.132 kPa·s/mg`` or ``496 kPa`` (a subcircuit box:
    its parameters); '' if none."""
    if part.pins:
        return part.params
    params = part.spec.params
    if part.kind in ("pressure_source", "flow_source"):
        return _waveform(params.get("value"), "kPa" if part.kind == "pressure_source" else "mg/s")
    if part.kind == "valve":
        model = params.get("model")
        return f"Rf={model.Rf:g} pclose={model.pclose:g}" if hasattr(model, "Rf") else ""
    if part.kind in ("pv_volume", "pv_volume_state"):
        return "p–V table"
    shown = []
    for key, unit in KEY_VALUES.get(part.kind, []):
        value = params.get(key)
        if isinstance(value, (int, float)) and math.isfinite(value) and len(shown) < 2:
            shown.append(f"{key}={value:.4g}" + (f" {unit}" if unit else ""))
    if part.segments > 1:
        shown.append(f"{part.segments} segments")
    return " ".join(shown)


def _waveform(wave, unit: str) -> str:
    level = getattr(wave, "level", None)
    if level is not None:
        return f"{level:.4g} {unit}"
    low, high = getattr(wave, "low", None), getattr(wave, "high", None)
    if low is not None and high is not None:
        return f"{type(wave).__name__.lower()} {low:.4g}–{high:.4g} {unit}"
    return type(wave).__name__.lower()
