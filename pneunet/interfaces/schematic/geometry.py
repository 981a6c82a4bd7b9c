"""Sizes of text and gaps, the positioned drawing (:class:`Layout`), and the two measures
of its legibility: overlapping boxes and crossing wires."""
from __future__ import annotations

from dataclasses import dataclass

FONT = 11          # px, monospace
CHAR_W = 6.6       # px per character of FONT (DejaVu Sans Mono: 0.602 em)
LINE_H = 13        # px between label lines
GAP_Y = 14         # px between two vertices of a layer
GAP_X = 26         # px between two columns, plus CHANNEL per channel
CHANNEL = 8        # px between two vertical wires in a gap
MARGIN = 16        # px around the drawing


def text_box(x, y, text):
    """Box (x0, y0, x1, y1) of a line of text centred on x with its baseline at y."""
    w = CHAR_W * len(text)
    return (x - w / 2, y - FONT * 0.8, x + w / 2, y + FONT * 0.25)


@dataclass
class Layout:
    """A positioned drawing in px (y down): ``prims`` are the symbols' paths and circles and
    the texts ``("text", (x, y), text, css_class)``; ``boxes`` are ``(what, name, (x0, y0,
    x1, y1))``, no two of which may overlap; ``wires`` are ``(net, points, dashed)``."""

    width: float
    height: float
    prims: list
    boxes: list
    wires: list

    def overlaps(self) -> list[tuple[str, str]]:
        """Names of each pair of boxes that overlap (touching is not overlapping)."""
        boxes = sorted(self.boxes, key=lambda b: b[2][0])
        out = []
        for i, (wa, na, a) in enumerate(boxes):
            for wb, nb, b in boxes[i + 1:]:
                if b[0] >= a[2]:
                    break
                if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                    out.append((f"{wa} {na}", f"{wb} {nb}"))
        return out

    def crossings(self) -> int:
        """Points where a horizontal wire crosses a vertical wire of another net."""
        horizontal, vertical = [], []
        for net, points, _ in self.wires:
            for (x0, y0), (x1, y1) in zip(points, points[1:]):
                if abs(y0 - y1) < 1e-6 and abs(x0 - x1) > 1e-6:
                    horizontal.append((net, min(x0, x1), max(x0, x1), y0))
                elif abs(x0 - x1) < 1e-6 and abs(y0 - y1) > 1e-6:
                    vertical.append((net, x0, min(y0, y1), max(y0, y1)))
        return sum(1 for hn, xa, xb, y in horizontal for vn, x, ya, yb in vertical
                   if hn != vn and xa < x < xb and ya < y < yb)
