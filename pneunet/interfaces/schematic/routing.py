"""From ranked, ordered and vertically placed vertices to a drawing: column positions,
each part's symbol (mirrored where its flow runs right to left), exhausts on reference
ports, labels, and orthogonal wires with one vertical channel per net and gap."""
from __future__ import annotations

import functools

from . import boxes as _boxes
from .boxes import is_control
from .geometry import CHANNEL, GAP_X, LINE_H, MARGIN, Layout, text_box
from .symbols import EXHAUST_W, exhaust

PILOT_X = 26       # x of a valve's pilot in its symbol


def _mirror(vertices) -> None:
    """Flip a part whose flow runs right to left (its inlet's node ranks after it)."""
    for v in vertices.values():
        part = v.part
        if part is None or part.pins:
            continue
        nodes = [n for p, n in part.ports.items() if p != "ctrl"]
        ranks = [vertices[("node", n)].rank if n != "atm" else None for n in nodes]
        if v.sym.port == "both" and len(ranks) == 2:
            a = ranks[0] if ranks[0] is not None else v.rank - 1
            b = ranks[1] if ranks[1] is not None else v.rank + 1
            v.mirror = a > b
        elif ranks and ranks[0] is not None:
            v.mirror = (ranks[0] < v.rank) if v.sym.port == "right" else (ranks[0] > v.rank)


def _side(v, port) -> int:
    """-1 if ``port`` of part vertex ``v`` is on the symbol's left, +1 right, 0 the pilot."""
    if port == "ctrl":
        return 0
    ports = [p for p in v.part.ports if p != "ctrl"]
    if v.sym.port == "both" and len(ports) == 2:
        side = -1 if ports.index(port) == 0 else 1
    else:
        side = 1 if v.sym.port == "right" else -1
    return -side if v.mirror else side


def _geometry(v):
    """Absolute symbol origin (x, y) of part vertex ``v``."""
    bx = v.x + (v.w - v.body) / 2
    left_ex = any(n == "atm" and _side(v, p) == -1 for p, n in v.part.ports.items())
    return bx + (EXHAUST_W + 2 if left_ex else 0), v.y + v.top


def _port_point(v, port):
    if v.part is None:
        return v.x + v.w / 2, v.y + v.anchor
    sx, sy = _geometry(v)
    if v.part.pins:
        return _boxes.pin_point(v, sx, port)
    side = _side(v, port)
    if side == 0:
        return sx + PILOT_X, sy
    return (sx if side < 0 else sx + v.sym.w), v.y + v.anchor


def _draw_part(v, prims, boxes):
    sx, sy = _geometry(v)
    sym = v.sym

    def place(pt):
        x, y = pt
        return (sx + (sym.w - x if v.mirror else x), sy + y)

    for prim in sym.prims:
        if prim[0] == "path":
            prims.append(("path", tuple(place(p) for p in prim[1]), *prim[2:]))
        else:
            prims.append(("circle", place(prim[1]), *prim[2:]))
    box = [sx, sy, sx + sym.w, sy + sym.h]
    if v.part.pins:
        box = _boxes.draw(v, sx, prims, box)
    for port, node in v.part.ports.items():
        if node != "atm":
            continue
        x, y = _port_point(v, port)
        more, ebox = exhaust(x, y, _side(v, port))
        prims.extend(more)
        box = [min(box[0], ebox[0]), min(box[1], ebox[1]), max(box[2], ebox[2]), max(box[3], ebox[3])]
    boxes.append(("symbol", v.part.label, tuple(box)))
    _draw_lines(v, sy + sym.h + 4, prims, boxes)


def _draw_lines(v, top, prims, boxes):
    cx = v.x + v.w / 2
    for i, (text, cls) in enumerate(v.lines):
        base = top + LINE_H * (i + 1) - 3
        prims.append(("text", (cx, base), text, cls))
        boxes.append(("label", text, text_box(cx, base, text)))


def _channel_order(nets):
    """Left-to-right order of the vertical wires of ``nets`` ({net: (ys left, ys right)})
    in a gap: net i before j costs the crossings of i's right stubs with j's vertical and
    of j's left stubs with i's vertical."""
    span = {n: (min(l + r), max(l + r)) for n, (l, r) in nets.items()}

    def cost(i, j):
        (lo, hi), (li, hj) = span[j], span[i]
        return (sum(lo < y < hi for y in nets[i][1]) + sum(li < y < hj for y in nets[j][0]))

    return sorted(nets, key=functools.cmp_to_key(lambda i, j: cost(i, j) - cost(j, i)))


def route(vertices, chains, columns, items_y) -> Layout:
    """The drawing of placed vertices; ``chains`` are ``((a, b, port), items)`` with the
    items of each edge from its lower rank to its higher, ``columns`` the items per rank."""
    _mirror(vertices)
    real = {v.key: v for v in vertices.values()}
    item_vertex = {}
    for column in columns:
        for item in column:
            key = getattr(item, "data", None)
            if key in real:
                item_vertex[item] = real[key]
                real[key].y = items_y[item] - real[key].anchor

    def end_y(item, edge):
        v = item_vertex.get(item)
        if v is None:
            return items_y[item]
        port = edge[2]
        if v.part is not None and (port == "ctrl" or v.part.pins):
            return _port_point(v, port)[1]
        return v.y + v.anchor

    gaps = [dict() for _ in columns]              # rank -> net -> (left ys, right ys)
    for edge, chain in chains:
        net = edge[0][1] if edge[0][0] == "node" else edge[1][1]
        for r, (p, q) in enumerate(zip(chain, chain[1:])):
            rank = next(i for i, c in enumerate(columns) if p in c) if r == 0 else rank + 1
            y1, y2 = end_y(p, edge), end_y(q, edge)
            if abs(y1 - y2) > 0.5:
                left, right = gaps[rank].setdefault(net, ([], []))
                left.append(y1)
                right.append(y2)
    x, col_x = MARGIN, []
    for r, column in enumerate(columns):
        width = max([item_vertex[i].w for i in column if i in item_vertex] + [4])
        col_x.append((x, x + width))
        for item in column:
            if item in item_vertex:
                item_vertex[item].x = x + (width - item_vertex[item].w) / 2
        x += width + GAP_X + CHANNEL * len(gaps[r])
    channel = {}
    for r, nets in enumerate(gaps):
        for i, net in enumerate(_channel_order(nets)):
            channel[r, net] = col_x[r][1] + GAP_X / 2 + CHANNEL * i

    wires = []
    for edge, chain in chains:
        net = edge[0][1] if edge[0][0] == "node" else edge[1][1]
        rank0 = next(i for i, c in enumerate(columns) if chain[0] in c)
        first, last = item_vertex.get(chain[0]), item_vertex.get(chain[-1])
        pts = [_port_point(first, edge[2] if first.part is not None else None)]
        pts.append((col_x[rank0][1], pts[0][1]))
        for r, (p, q) in enumerate(zip(chain, chain[1:])):
            rank = rank0 + r
            y1, y2 = end_y(p, edge), end_y(q, edge)
            if abs(y1 - y2) > 0.5:
                xc = channel[rank, net]
                pts += [(xc, y1), (xc, y2)]
            pts.append((col_x[rank + 1][0], y2))
            if q is not chain[-1]:
                pts.append((col_x[rank + 1][1], y2))
        end = _port_point(last, edge[2] if last.part is not None else None)
        pts += [(end[0], pts[-1][1])] + ([end] if abs(end[1] - pts[-1][1]) > 0.5 else [])
        wires.append((net, _clean(pts), is_control(edge[2])))

    prims, boxes = [], []
    for v in real.values():
        if v.part is not None:
            _draw_part(v, prims, boxes)
        else:
            cx, cy = v.x + v.w / 2, v.y + v.anchor
            prims.append(("circle", (cx, cy), 3, "black"))
            boxes.append(("node", v.key[1], (cx - 3, cy - 3, cx + 3, cy + 3)))
            _draw_lines(v, v.y + 8, prims, boxes)
    height = max(v.y + v.h for v in real.values()) + MARGIN
    return Layout(x - GAP_X + MARGIN, height, prims, boxes, wires)


def _clean(points):
    """Drop repeated points and the middle one of three on a line."""
    out = []
    for p in points:
        if out and abs(out[-1][0] - p[0]) < 1e-6 and abs(out[-1][1] - p[1]) < 1e-6:
            continue
        if len(out) >= 2 and any(abs(out[-2][k] - out[-1][k]) < 1e-6 and abs(out[-1][k] - p[k]) < 1e-6
                                 for k in (0, 1)):
            out[-1] = p
            continue
        out.append(p)
    return out
