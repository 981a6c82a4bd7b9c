"""Design to a specification under manufacturing spread (the last stage: language →
engine → physics → truth-finding → design).

:mod:`.spec` the specification language (targets, ranges, tolerances); :mod:`.metrics`
what one simulation measures; :mod:`.problem` a circuit with targets on the sweep
machinery; :mod:`.search` the design search; :mod:`.spread` stated tolerances and fitted
covariances; :mod:`.yields` the Monte Carlo yield; :mod:`.sensitivity` which spread
matters most.  Command line: ``pneunet design`` (docs/design.md).
"""
from __future__ import annotations

from .search import DesignResult, design
from .problem import Problem
from .spec import Range, Target, Tolerance, parse_range, parse_target, parse_tolerance
from .spread import Spread, combined, from_fit, from_tolerances
from .yields import YieldResult, yield_analysis

__all__ = ["DesignResult", "Problem", "Range", "Spread", "Target", "Tolerance",
           "YieldResult", "combined", "design", "from_fit", "from_tolerances", "parse_range",
           "parse_target", "parse_tolerance", "yield_analysis"]
