"""The verdict of a diagnosis: never a forced choice.

* ``adequate``: the base model's held-out error is already at the noise floor
  (within ``tolerance`` × floor): nothing is claimed;
* ``explained``: an accepted effect (or two, the waterfall) brings the held-out error
  back within ``tolerance`` × floor;
* ``unexplained``: structure above the floor remains that no candidate removes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

VERDICTS = ("adequate", "explained", "unexplained")

#: held-out error within this factor of the noise floor counts as "at the floor"
TOLERANCE = 1.5


@dataclass
class Step:
    """One bar of the error waterfall: the model after the effects in ``effects``."""

    label: str
    held_out: float  # held-out error (the diagnosis' unit)
    se: float = float("nan")  # its standard error, when known
    effects: tuple = ()
    extra: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"label": self.label, "held_out_rms": _num(self.held_out),
                "held_out_se": _num(self.se), "effects": list(self.effects), **self.extra}


def at_floor(error: float, floor: float, tolerance: float = TOLERANCE) -> bool:
    """True when ``error`` is within ``tolerance`` × ``floor``."""
    return bool(math.isfinite(error) and math.isfinite(floor) and error <= tolerance * floor)


def decide(steps: list[Step], floor: float, tolerance: float = TOLERANCE) -> tuple[str, list]:
    """(verdict, accepted effect names) from the waterfall ``steps`` (base first, then
    the model with 1, 2 … effects, each step's ``effects`` the whole set so far)."""
    if not steps:
        raise ValueError("no waterfall steps")
    if at_floor(steps[0].held_out, floor, tolerance):
        return "adequate", []
    for s in steps[1:]:
        if at_floor(s.held_out, floor, tolerance):
            return "explained", list(s.effects)
    return "unexplained", []


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None
