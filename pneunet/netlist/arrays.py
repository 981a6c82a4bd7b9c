"""Array ranges on element, instance and node names: ``R[0:7]``, ``X[0:63:2]``, ``act[0:7]``.

A range holds whole numbers ``lo <= hi`` (``lo >= 0``) and an optional step >= 1; one range per
name, and at most ``max_array_size`` copies.  A single index (``act[5]``) is a plain name.
"""
from __future__ import annotations

import dataclasses
import math
import re

from ..common.errors import NetlistError

_TAIL = re.compile(r"\[([^\[\]]*)\]$")
_ANY_RANGE = re.compile(r"\[[^\[\]]*:[^\[\]]*\]")


def split_range(text: str, item, limits):
    """``(base, indices)`` for ``text`` (``item``'s text after ``{}`` substitution) ending in a
    range; None for a plain name.  Errors point at the range's ``[`` in ``item``."""
    if "[" not in text:
        return None
    m = _TAIL.search(text)
    if not m or ":" not in m.group(1):
        if _ANY_RANGE.search(text):
            raise _error(item, f"a range must end the name, got {text!r}",
                         "write NAME[lo:hi], e.g. R[0:7]")
        return None
    base, inside = text[:m.start()], m.group(1)
    if _ANY_RANGE.search(base):
        raise _error(item, f"{text!r} has more than one range",
                     "arrays have one dimension: use an array of subcircuit instances whose "
                     "subcircuit holds the inner array")
    parts = [p.strip() for p in inside.split(":")]
    if len(parts) > 3:
        raise _error(item, f"bad array range [{inside}]", "write [lo:hi] or [lo:hi:step]")
    bounds = []
    for part in parts:
        try:
            value = float(part)
        except ValueError:
            value = math.nan
        if not math.isfinite(value) or value != int(value) or value < 0:
            raise _error(item, f"array range [{inside}]: {part!r} is not a whole number >= 0",
                         "indices count up from 0 or more, e.g. [0:7] or [0:63:2]")
        bounds.append(int(value))
    lo, hi = bounds[0], bounds[1]
    step = bounds[2] if len(bounds) == 3 else 1
    if step < 1:
        raise _error(item, f"array range [{inside}]: the step must be >= 1", "e.g. [0:63:2]")
    if hi < lo:
        raise _error(item, f"array range [{inside}] counts down ({lo} > {hi})",
                     f"write the smaller index first: [{hi}:{lo}]")
    count = (hi - lo) // step + 1
    if count > limits.max_array_size:
        raise _error(item, f"array range [{inside}] makes {count} copies "
                           f"({limits.exceeded('max_array_size')})",
                     limits.hint("max_array_size"))
    return base, range(lo, hi + 1, step)


def _error(item, message, hint=None) -> NetlistError:
    offset = item.text.rfind("[")
    span = dataclasses.replace(item.span, column=item.span.column + max(offset, 0))
    return NetlistError(message, span=span, hint=hint)
