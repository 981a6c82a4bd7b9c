"""Design to a specification under manufacturing spread (the last stage: language →
engine → physics → truth-finding → design).

:mod:`.spec` the specification language (targets, ranges, tolerances); :mod:`.metrics`
what one simulation measures; :mod:`.problem` a circuit with targets on the sweep
machinery; :mod:`.search` the design search.
"""
from __future__ import annotations

from .search import DesignResult, design
from .spec import Range, Target, Tolerance, parse_range, parse_target, parse_tolerance

__all__ = ["DesignResult", "Range", "Target", "Tolerance", "design", "parse_range",
           "parse_target", "parse_tolerance"]
