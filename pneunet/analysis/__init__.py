"""Circuit design analyses (paper section 6): sweeps, oscillation, stationary branches,
regime maps, design helpers, fluid-logic checks and the piping footprint (fitting
circuits to recorded traces: :mod:`pneunet.traces`).

Each module returns data (dataclasses, pandas tables); ``plot_*`` functions draw it
through :mod:`pneunet.plotting`.  Modules are imported lazily::

    from pneunet.analysis import sweep, oscillation, branches, regime, design, logic, piping
"""
from __future__ import annotations

import importlib

_MODULES = ("sweep", "oscillation", "branches", "regime", "design", "logic", "circuits",
            "piping")


def __getattr__(name):
    if name in _MODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_MODULES)
