"""The pneunet netlist language (see docs/netlist.md).

    from pneunet.netlist import parse_file
    deck = parse_file("netlists/oscillator.pn")
    deck.circuit.validate()
    for analysis in deck.analyses: ...

Pipeline: text --(lark, grammar.lark)--> statements with spans --(elaborate)-->
:class:`Deck` (a :class:`~pneunet.engine.circuit.Circuit` plus analyses, measurements,
saves and steps).  :func:`print_circuit` writes a circuit back as netlist text;
:mod:`.builder` makes a circuit at a parameter point.  The language builds circuits for
the engine, which knows no language.  May import: common, physics, engine.
"""
from __future__ import annotations

from pathlib import Path

from .deck import DC, Deck, Measure, Op, Signal, Step, Tran
from .limits import Limits


def parse_netlist(text: str, name: str = "<netlist>", overrides: dict | None = None, *,
                  limits=None, include_path=()) -> Deck:
    """Parse netlist text; ``.include`` paths are relative to ``name``'s folder (or the cwd).

    ``limits`` is a :class:`~.limits.Limits` or a mapping of limits to change
    (``{"max_elements": 2_000_000}``); ``include_path`` adds folders includes may come from.
    """
    from .syntax import parse_text

    limits = _limits(limits)
    path = Path(name) if name != "<netlist>" else None
    return _build(parse_text(text, name, path, limits=limits), path, overrides, limits,
                  include_path)


def parse_file(path, overrides: dict | None = None, *, limits=None, include_path=()) -> Deck:
    """Parse a netlist file (``limits`` and ``include_path`` as for :func:`parse_netlist`)."""
    from .syntax import read_source

    limits = _limits(limits)
    return _build(read_source(Path(path), limits=limits), Path(path), overrides, limits,
                  include_path)


def load_file(path, *, limits=None, include_path=()):
    """A netlist file read, parsed and its includes expanded, not yet elaborated: give it
    to :func:`elaborate_source` as often as needed (a fit's every trial point), the file
    read and parsed once."""
    from .includes import IncludePolicy
    from .structure import load
    from .syntax import read_source

    limits = _limits(limits)
    return load(read_source(Path(path), limits=limits), IncludePolicy.for_netlist(
        Path(path), include_path), limits)


def elaborate_source(source, overrides: dict | None = None) -> Deck:
    """The :class:`Deck` of a :func:`load_file` result with ``.param`` ``overrides``."""
    from ..common.gcpause import collector_paused
    from .elaborate import elaborate

    with collector_paused():
        return elaborate(source, overrides)


def _limits(limits):
    from .limits import DEFAULT

    return limits if isinstance(limits, Limits) else DEFAULT.replace(limits or {})


def _build(src, path, overrides, limits, include_path) -> Deck:
    from .elaborate import elaborate
    from .structure import load
    from .includes import IncludePolicy

    from ..common.gcpause import collector_paused

    policy = IncludePolicy.for_netlist(path, include_path)
    with collector_paused():
        return elaborate(load(src, policy, limits), overrides)


def print_circuit(circuit, **kw) -> str:
    """Netlist text that parses back to ``circuit``."""
    from .printer import print_circuit as _p

    return _p(circuit, **kw)


__all__ = ["parse_netlist", "parse_file", "print_circuit", "Deck", "Tran", "Op", "DC", "Step",
           "Measure", "Signal", "Limits"]
