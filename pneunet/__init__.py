"""pneunet: lumped-parameter pneumatic circuits of fluid-driven membrane valves.

``import pneunet`` stays light: the public names below are loaded on first use.

Units everywhere: absolute pressure kPa, mass flow mg/s, resistance kPa·s/mg,
volume mL, time s (see :mod:`pneunet.physics.gas`).
"""
from __future__ import annotations

import importlib

from .common import views as _views

__version__ = "0.1.0"

_LAZY = {
    "Circuit": "pneunet.engine.circuit",
    "SimulationOptions": "pneunet.engine.options",
    "transient": "pneunet.engine.simulate",
    "operating_point": "pneunet.engine.simulate",
    "Solution": "pneunet.engine.solution",
    "save_run": "pneunet.interfaces.runfile",
    "read_run": "pneunet.interfaces.runfile",
    "ValveParams": "pneunet.physics.valve_params",
    "PAPER_VALVES": "pneunet.physics.valve_params",
    "waveforms": "pneunet.physics.waveforms",
    "PneunetError": "pneunet.common.errors",
    "NetlistError": "pneunet.common.errors",
    "TopologyError": "pneunet.common.errors",
    "ParameterError": "pneunet.common.errors",
    "DataError": "pneunet.common.errors",
    "SolverError": "pneunet.common.errors",
    "AIR": "pneunet.physics.gas",
    "Gas": "pneunet.physics.gas",
    "Liquid": "pneunet.physics.liquids",
}

__all__ = sorted(_LAZY) + ["__version__"]

# the interfaces stage draws and writes what the engine and the language hold
_views.provide("schematic", "pneunet.interfaces.schematic", "draw")
_views.provide("run file", "pneunet.interfaces.runfile", "save_run")


def __getattr__(name):
    if name in _LAZY:
        module = importlib.import_module(_LAZY[name])
        value = module if name == "waveforms" else getattr(module, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pneunet' has no attribute {name!r}")


def __dir__():
    return __all__
