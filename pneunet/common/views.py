"""Views of a circuit or a run that a later stage draws or writes.

``Circuit.draw``, ``Deck.draw`` (the schematic) and ``Solution.save`` (the run file) are
methods of the engine and the language, but drawing and file formats belong to the
interfaces stage.  The methods call the view registered here under a name; :mod:`pneunet`
registers the built-in ones when it is imported (which every ``import pneunet.…`` does
first), so an earlier stage never imports a later one.
"""
from __future__ import annotations

import importlib

_VIEWS: dict[str, tuple[str, str]] = {}


def provide(name: str, module: str, function: str) -> None:
    """Make ``module.function`` (imported on first use) the view called ``name``."""
    _VIEWS[name] = (module, function)


def view(name: str):
    """The function registered as view ``name``."""
    module, function = _VIEWS[name]
    return getattr(importlib.import_module(module), function)
