"""Short reprs of result objects: what was computed, the key numbers, how to get the rest.

A result class derives from :class:`Summarized` and implements ``_summary()``,
returning a title, (label, value) rows and a hint naming the attributes and
methods that give the full data.  ``repr()`` is one line; ``_repr_html_`` (notebooks)
is a small table.  Dataclasses among them are declared with ``repr=False``.
"""
from __future__ import annotations

import html
from abc import ABC, abstractmethod


class Summarized(ABC):
    """Mixin: ``__repr__`` and ``_repr_html_`` from ``_summary()``."""

    @abstractmethod
    def _summary(self) -> tuple[str, list[tuple[str, str]], str]:
        """(title, [(label, value)] rows, the line that says how to use the object)."""

    def __repr__(self) -> str:
        title, rows, how = self._summary()
        body = ", ".join(f"{label} {value}" for label, value in rows)
        head = f"{type(self).__name__} {title}".rstrip()
        return f"<{head}: {body}; {how}>"

    def _repr_html_(self) -> str:
        title, rows, how = self._summary()
        cells = "".join(f"<tr><th style='text-align:left'>{html.escape(label)}</th>"
                        f"<td style='text-align:left'>{html.escape(str(value))}</td></tr>"
                        for label, value in rows)
        return (f"<b>{html.escape(type(self).__name__)}</b> {html.escape(title)}"
                f"<table>{cells}</table><small>{html.escape(how)}</small>")


def listed(names, limit: int = 6) -> str:
    """``a, b, c, … (+4)``: the first ``limit`` names of a sequence."""
    names = list(names)
    more = f", … (+{len(names) - limit})" if len(names) > limit else ""
    return ", ".join(map(str, names[:limit])) + more


def number(value, unit: str = "", digits: int = 4) -> str:
    """A float with ``digits`` significant digits and its unit; 'n/a' for NaN/None."""
    if value is None or value != value:
        return "n/a"
    return f"{value:.{digits}g}" + (f" {unit}" if unit else "")
