"""Design: what a designer does with circuits (the stage after truth-finding).

Sweeps and regime maps (:mod:`.sweep`, :mod:`.store`, :mod:`.regime`,
:mod:`.sweep_plot`), the paper's circuits as Python builders (:mod:`.paper_circuits`,
:mod:`.circuits`), sizing helpers (:mod:`.sizing`: fill and empty times, normal flow),
fluid-logic truth tables (:mod:`.logic`), McKibben work (:mod:`.muscle`), the piping
footprint (:mod:`.piping`), and design to a specification under manufacturing spread:
:mod:`.spec` the specification language, :mod:`.metrics` what one simulation measures,
:mod:`.problem` a circuit with targets on the sweep machinery, :mod:`.search` the search,
:mod:`.spread` stated tolerances and fitted covariances, :mod:`.yields` the Monte Carlo
yield, :mod:`.sensitivity` which spread matters most.  Command line: ``pneunet sweep``,
``pneunet design``, ``pneunet piping`` (docs/design.md).

May import: common, physics, engine, netlist, truth.  Modules and names load on first
use (``from pneunet.design import sweep, design``).
"""
from __future__ import annotations

import importlib

_NAMES = {"DesignResult": "search", "design": "search", "Problem": "problem",
          "Range": "spec", "Target": "spec", "Tolerance": "spec", "parse_range": "spec",
          "parse_target": "spec", "parse_tolerance": "spec", "Spread": "spread",
          "combined": "spread", "from_fit": "spread", "from_tolerances": "spread",
          "YieldResult": "yields", "yield_analysis": "yields"}
_MODULES = ("circuits", "logic", "metrics", "muscle", "paper_circuits", "piping", "problem",
            "regime", "search", "sensitivity", "sizing", "spec", "spread", "store", "sweep",
            "sweep_dask", "sweep_plot", "yields")


def __getattr__(name):
    if name in _NAMES:
        value = getattr(importlib.import_module(f".{_NAMES[name]}", __name__), name)
    elif name in _MODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


__all__ = sorted(_NAMES) + list(_MODULES)
