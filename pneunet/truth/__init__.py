"""Truth-finding: one pipeline applied to two kinds of data.

:mod:`.core` the steps every diagnosis takes, whatever its model: the measurement noise
floor from the data alone, parameter fits with honest intervals, where the residual sits,
and the verdict with its error waterfall.  :mod:`.valves` valve bench data (identify the
six-parameter model, diagnose what it misses from the valve-law effects);
:mod:`.circuits` circuit recordings (fit a netlist to a logger's file from wherever it
starts, diagnose what it misses from the circuit effects, write the corrected netlist).
May import: common, physics, engine, netlist.
"""
from __future__ import annotations

from .core.noise import difference_sigma
from .core.verdict import TOLERANCE, VERDICTS, Step, decide, verdict
from .core.waterfall import Waterfall

__all__ = ["TOLERANCE", "VERDICTS", "Step", "Waterfall", "decide", "difference_sigma", "verdict"]
