"""Schematics of circuits: ISO 1219-1 style symbols on a layered layout, annotated with
results (``pneunet draw``, :meth:`Circuit.draw`)."""
from __future__ import annotations

from .collapse import collapse
from .geometry import Layout
from .layout import layout
from .svg import save_raster, to_svg


def draw(circuit, path=None, *, results=None, instances=None) -> Layout:
    """The schematic of ``circuit``; written to ``path`` (.svg, .png or .pdf) if given.

    ``results`` is an :class:`~pneunet.engine.solution.OperatingPoint` or a
    ``(Solution, time)`` pair: node pressures (kPa) and element flows (mg/s) are written
    on the drawing.  ``instances`` (a netlist's ``Deck.instances``) draws each top-level
    subcircuit instance as a box; without them every element is drawn."""
    from .annotate import notes

    sch = collapse(circuit, instances)
    node_notes, part_notes = notes(sch, results) if results is not None else ({}, {})
    lay = layout(sch, node_notes, part_notes)
    lay.svg = to_svg(lay, circuit.title)
    if path is not None:
        path = str(path)
        if path.lower().endswith((".png", ".pdf")):
            save_raster(lay, path, circuit.title)
        else:
            with open(path, "w", encoding="utf-8") as fh:
                fh.write(lay.svg)
    return lay


__all__ = ["draw", "collapse", "layout", "to_svg", "Layout"]
