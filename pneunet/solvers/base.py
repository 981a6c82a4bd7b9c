"""What a transient backend provides: an integrator of F(t, y, ẏ) = 0 with events."""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

#: step() statuses shared by all backends
OK, TSTOP, EVENT, FAILED = "ok", "tstop", "event", "failed"


@dataclass
class StepResult:
    status: str
    t: float
    y: np.ndarray
    yp: np.ndarray
    message: str = ""


class Integrator(ABC):
    """Interface of a DAE integrator (see :mod:`pneunet.solvers.sundae`).

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

    def counters(self) -> dict:
        return {}


def available_backends() -> dict:
    """{name: factory} of the IDA bindings importable on this machine."""
    import importlib.util

    out = {}
    if importlib.util.find_spec("sksundae") is not None:
        from .sundae import SundaeIntegrator

        out["sksundae"] = SundaeIntegrator
    if importlib.util.find_spec("scikits") is not None and \
            importlib.util.find_spec("scikits.odes") is not None:
        try:
            from .odes import OdesIntegrator
        except ModuleNotFoundError:  # binding installed, pneunet adapter not present
            pass
        else:
            out["odes"] = OdesIntegrator
    return out
