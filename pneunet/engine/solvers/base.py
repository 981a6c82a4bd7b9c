"""What a transient backend provides: an integrator of F(t, y, ẏ) = 0 with events.

The driver (:mod:`pneunet.engine.simulate`) asks for *segments*: to the next stop (a
source breakpoint or the end), every internal step stored, ending early at a root
of the event function or at a failure.  A segment restarts the integrator from a
consistent state after a jump; across a corner where only a slope changes it
continues, keeping the step size, order and Jacobian.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

#: step() and segment() statuses shared by all backends
OK, TSTOP, EVENT, FAILED = "ok", "tstop", "event", "failed"


@dataclass
class StepResult:
    status: str
    t: float
    y: np.ndarray
    yp: np.ndarray
    message: str = ""


@dataclass
class Segment:
    """Accepted internal steps after a (re)start, in increasing time.

    ``t`` (k,) s; ``y``, ``yp`` (k, n) kPa and kPa/s.  ``status`` is TSTOP (the stop
    was reached: the last row is at it), EVENT (the last row is a root of the event
    function) or FAILED (the rows are the steps before the failure).
    """

    status: str
    t: np.ndarray
    y: np.ndarray
    yp: np.ndarray
    message: str = ""


class Integrator(ABC):
    """Interface of a DAE integrator (see :mod:`pneunet.engine.solvers.sundae`).

    ``init(t, y, yp)`` (re)starts from a consistent state; ``step(target, tstop,
    onestep)`` advances to ``target`` (or one internal step), never past
    ``tstop``, stopping early at a root of the events function.
    """

    name = "abstract"

    @abstractmethod
    def init(self, t: float, y: np.ndarray, yp: np.ndarray) -> None:
        """(Re)start the integration from a consistent state at time t."""

    @abstractmethod
    def step(self, target: float, tstop: float, onestep: bool) -> StepResult:
        """Advance towards ``target`` without passing ``tstop``."""

    def segment(self, t0: float, y0: np.ndarray, yp0: np.ndarray, t_end: float,
                outputs: np.ndarray | None = None, restart: bool = True,
                final: bool = False) -> Segment:
        """Integrate from ``t0`` to ``t_end``: restarted at (t0, y0, yp0), or continued
        from where the last segment ended (``restart`` False).

        ``outputs`` None stores every internal step; else the rows are the output
        times in (t0, t_end) (the integrator's own interpolation) and the end.
        ``final``: no segment will continue from this one's end (a restart or the end
        of the run follows it), so a backend may integrate it in a way it cannot
        continue from.
        """
        if restart:
            self.init(t0, y0, yp0)
        targets = [t_end] if outputs is None else [*outputs, t_end]
        k = 0
        ts, ys, yps = [], [], []
        while True:
            step = self.step(targets[k], t_end, onestep=outputs is None)
            if outputs is not None and step.status == OK and step.t >= targets[k]:
                k += 1
            if step.status == FAILED:
                return _segment(FAILED, ts, ys, yps, len(y0), step.message)
            if not ts or step.t > ts[-1]:
                ts.append(step.t)
                ys.append(step.y)
                yps.append(step.yp)
            if step.status == EVENT:
                return _segment(EVENT, ts, ys, yps, len(y0), step.message)
            if step.status == TSTOP or step.t >= t_end:
                return _segment(TSTOP, ts, ys, yps, len(y0), step.message)

    def counters(self) -> dict:
        return {}


def _segment(status, ts, ys, yps, n, message):
    shape = (len(ts), n)
    return Segment(status, np.array(ts, dtype=float), np.reshape(ys, shape),
                   np.reshape(yps, shape), message)
