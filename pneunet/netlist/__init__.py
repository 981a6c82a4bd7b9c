"""The pneunet netlist language (see docs/netlist.md).

    from pneunet.netlist import parse_file
    deck = parse_file("netlists/oscillator.pn")
    deck.circuit.validate()
    for analysis in deck.analyses: ...

Pipeline: text --(lark, grammar.lark)--> statements with spans --(elaborate)-->
:class:`Deck` (a :class:`~pneunet.engine.circuit.Circuit` plus analyses, measurements,
saves and steps).  :func:`print_circuit` writes a circuit back as netlist text.
"""
from __future__ import annotations

from pathlib import Path

from .deck import DC, Deck, Measure, Op, Signal, Step, Tran


def parse_netlist(text: str, name: str = "<netlist>", overrides: dict | None = None) -> Deck:
    """Parse netlist text; ``.include`` paths are relative to ``name``'s folder (or the cwd)."""
    from .elaborate import elaborate, load
    from .syntax import parse_text

    path = Path(name) if name != "<netlist>" else None
    return elaborate(load(parse_text(text, name, path)), overrides)


def parse_file(path, overrides: dict | None = None) -> Deck:
    """Parse a netlist file."""
    from .elaborate import elaborate, load
    from .syntax import read_source

    return elaborate(load(read_source(Path(path))), overrides)


def print_circuit(circuit, **kw) -> str:
    """Netlist text that parses back to ``circuit``."""
    from .printer import print_circuit as _p

    return _p(circuit, **kw)


__all__ = ["parse_netlist", "parse_file", "print_circuit", "Deck", "Tran", "Op", "DC", "Step",
           "Measure", "Signal"]
