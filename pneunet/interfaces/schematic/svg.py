"""A :class:`~pneunet.interfaces.schematic.geometry.Layout` as SVG text (wires first, then symbols
and labels; control lines dashed), and as PNG or PDF through matplotlib (pneunet.common.plotting)."""
from __future__ import annotations

from xml.sax.saxutils import escape

from .geometry import FONT

STYLE = (f"text{{font-family:'DejaVu Sans Mono',monospace;font-size:{FONT}px;"
         "text-anchor:middle}} .value{{fill:#444}} .result{{fill:#b00000}} .node{{fill:#0050a0}}"
         " .wire{{fill:none;stroke:black;stroke-width:1.2}}"
         " .ctrl{{fill:none;stroke:#0050a0;stroke-width:1;stroke-dasharray:5 3}}")


def _pts(points) -> str:
    return " ".join(f"{x:.1f},{y:.1f}" for x, y in points)


def to_svg(lay, title: str = "") -> str:
    """SVG document of the layout (px units)."""
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{lay.width:.0f}" '
           f'height="{lay.height:.0f}" viewBox="0 0 {lay.width:.1f} {lay.height:.1f}">',
           f"<title>{escape(title)}</title>", f"<style>{STYLE.replace('{{', '{').replace('}}', '}')}</style>",
           f'<rect width="100%" height="100%" fill="white"/>']
    for net, points, dashed in lay.wires:
        out.append(f'<polyline class="{"ctrl" if dashed else "wire"}" points="{_pts(points)}">'
                   f"<title>{escape(net)}</title></polyline>")
    for prim in lay.prims:
        if prim[0] == "path":
            _, points, closed, fill, dashed = prim
            tag = "polygon" if closed else "polyline"
            dash = ' stroke-dasharray="4 2"' if dashed else ""
            out.append(f'<{tag} points="{_pts(points)}" fill="{fill or "none"}" '
                       f'stroke="black" stroke-width="1.2"{dash}/>')
        elif prim[0] == "circle":
            _, (cx, cy), r, fill = prim
            out.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{r}" fill="{fill or "white"}" '
                       f'stroke="black" stroke-width="1.2"/>')
        else:
            _, (x, y), text, cls = prim
            out.append(f'<text class="{cls}" x="{x:.1f}" y="{y:.1f}">{escape(text)}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def save_raster(lay, path: str, title: str = "") -> None:
    """PNG or PDF (by the suffix of ``path``) of the layout, drawn with matplotlib."""
    from ...common.plotting import figure_and_patches

    Figure, patches = figure_and_patches()
    Circle, Polygon = patches.Circle, patches.Polygon

    dpi = 100
    fig = Figure(figsize=(lay.width / dpi, lay.height / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, lay.width)
    ax.set_ylim(lay.height, 0)
    ax.axis("off")
    colours = {"value": "#444444", "result": "#b00000", "node": "#0050a0", "name": "black"}
    for _, points, dashed in lay.wires:
        xs, ys = zip(*points)
        ax.plot(xs, ys, color="#0050a0" if dashed else "black", lw=1.0 if dashed else 1.2,
                ls=(0, (5, 3)) if dashed else "-")
    for prim in lay.prims:
        if prim[0] == "path":
            _, points, closed, fill, dashed = prim
            ax.add_patch(Polygon(points, closed=closed, fill=bool(fill), facecolor=fill or "none",
                                 edgecolor="black", lw=1.2, ls="--" if dashed else "-"))
        elif prim[0] == "circle":
            _, centre, r, fill = prim
            ax.add_patch(Circle(centre, r, facecolor=fill or "white", edgecolor="black", lw=1.2))
        else:
            _, (x, y), text, cls = prim
            ax.text(x, y, text, ha="center", va="baseline", family="DejaVu Sans Mono",
                    size=FONT * 72 / dpi, color=colours.get(cls, "black"))
    fig.savefig(path, metadata={"Title": title} if path.lower().endswith(".pdf") else None)
