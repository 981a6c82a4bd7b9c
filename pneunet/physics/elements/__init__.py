"""Element families and their registry.

Built-in families live in the modules of this package; plug-ins register more
through the ``pneunet.physics.elements`` entry-point group (each entry point names an
:class:`~pneunet.physics.elements.base.ElementFamily` subclass) or by calling
:func:`register` directly.
"""
from __future__ import annotations

from ...common.errors import ParameterError
from .base import _REGISTRY, ElementFamily, ElementSpec, FamilyContext, Param, register

_LOADED = False


def _load_builtins() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    from . import (check_valves, elastic, liquid, mckibben, pv_state, resistors,  # noqa: F401
                   sources, thermal, tubes, valves, volumes)
    from importlib.metadata import entry_points

    for ep in entry_points(group="pneunet.physics.elements"):
        register(ep.load())


def family(kind: str) -> type[ElementFamily]:
    """The family class for an element kind or alias, with a helpful error."""
    _load_builtins()
    try:
        return _REGISTRY[kind.lower()]
    except KeyError:
        raise ParameterError(f"unknown element kind {kind!r}",
                             hint="known: " + ", ".join(sorted(known_kinds()))) from None


def known_kinds() -> list[str]:
    _load_builtins()
    return sorted({f.kind for f in _REGISTRY.values()})


__all__ = ["ElementFamily", "ElementSpec", "FamilyContext", "Param", "register", "family",
           "known_kinds"]
