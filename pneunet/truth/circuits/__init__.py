"""Circuit recordings: fit a netlist to a recorded transient and find the physics it
lacks (the circuit side of the truth-finding pipeline; the shared core is
:mod:`pneunet.truth`).

``fit_trace`` (one fit with intervals), ``diagnose_trace`` (base fit → noise floor →
where → candidate effects ranked on held-out cycles → verdict and waterfall), circuit
effects in :mod:`.effects` (``CircuitEffect``, ``NetlistEffect``, ``register``).
"""
from __future__ import annotations

from .data import read_trace, split_by_cycles
from .diagnosis import TraceDiagnosis, diagnose_trace
from .effects import CircuitEffect, NetlistEffect, candidates_for, register, registered_effects
from .fit import TraceFit, fit_trace
from .model import FIT_OPTIONS, TraceModel, synthetic_trace

__all__ = ["CircuitEffect", "FIT_OPTIONS", "NetlistEffect", "TraceDiagnosis", "TraceFit",
           "TraceModel", "candidates_for", "diagnose_trace", "fit_trace", "read_trace",
           "register", "registered_effects", "split_by_cycles", "synthetic_trace"]
