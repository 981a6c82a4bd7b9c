"""Truth-finding core shared by the valve diagnosis (:mod:`pneunet.diagnose`) and the
circuit-recording diagnosis (:mod:`pneunet.traces`).

The steps every diagnosis takes, whatever its model: the measurement noise floor from
the data alone (:mod:`.noise`), parameter fits with honest intervals (:mod:`.lsq`,
:mod:`.intervals`), where the residual sits (:mod:`.locate`), and the verdict with its
error waterfall (:mod:`.verdict`, :mod:`.waterfall`).
"""
from __future__ import annotations

from .noise import difference_sigma
from .verdict import TOLERANCE, VERDICTS, Step, decide, verdict
from .waterfall import Waterfall

__all__ = ["TOLERANCE", "VERDICTS", "Step", "Waterfall", "decide", "difference_sigma", "verdict"]
