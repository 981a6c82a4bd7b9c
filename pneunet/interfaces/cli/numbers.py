"""Every number and count a command reads from its options, checked when it is read
(argparse ``type=``), before any work: finite, in range, whole where a count is meant; a
count that allocates is also checked against the limits (``--limit``) once they are known
(:func:`within`)."""
from __future__ import annotations

import argparse
import math


def real(low: float | None = None, high: float | None = None, *, above: float | None = None,
         below: float | None = None, unit: str = ""):
    """A finite number ``>= low`` (or ``> above``) and ``<= high`` (or ``< below``)."""
    def check(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r}: a finite number is needed")
        if above is not None and not value > above:
            raise argparse.ArgumentTypeError(f"{text}: must be > {above:g}{unit}")
        if low is not None and value < low:
            raise argparse.ArgumentTypeError(f"{text}: must be >= {low:g}{unit}")
        if below is not None and not value < below:
            raise argparse.ArgumentTypeError(f"{text}: must be < {below:g}{unit}")
        if high is not None and value > high:
            raise argparse.ArgumentTypeError(f"{text}: must be <= {high:g}{unit}")
        return value
    return check


def whole(low: int = 0, high: int | None = None):
    """A whole number ``>= low`` (and ``<= high``); ``1e3`` is read as 1000."""
    def check(text: str) -> int:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if not math.isfinite(value) or value != int(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number")
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(
                f"{text}: must be >= {low}" + (f" and <= {high}" if high is not None else ""))
        return int(value)
    return check


def within(count: float, flag: str, limits, name: str) -> None:
    """A ParameterError when ``count`` (what ``flag`` asks for) passes the limit ``name``."""
    from ...common.errors import ParameterError

    if count > getattr(limits, name):
        raise ParameterError(f"{flag} asks for {count:.6g} ({limits.exceeded(name)})",
                             hint=limits.hint(name))
