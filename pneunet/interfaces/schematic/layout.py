"""Layered (Sugiyama) layout of a schematic: flow from the supply (left) to the exhaust
(right), symbols and labels that never overlap, wires routed orthogonally in channels.

Ranks and the order within each rank (crossing reduction by barycenters) come from
``grandalf``; the rest is here: which edges point backwards (feedback and control lines,
chosen so that flow edges keep their direction), y coordinates (each layer an isotonic
fit to its neighbours' barycentres, so order and spacing are kept exactly), and the wires:
through the columns at the height of their dummy vertices, vertically in one channel per
net in the gap between two columns.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field

import networkx as nx

from . import boxes
from .boxes import is_control
from .collapse import Schematic
from .labels import name_line, value_line
from .geometry import CHAR_W, GAP_Y, LINE_H, MARGIN
from .routing import route
from .symbols import EXHAUST_W, symbol

SOURCES = ("pressure_source", "flow_source")
ATTEMPTS = 4      # edge orders tried (fewer if one draws without crossings)


@dataclass
class Vertex:
    """A part or a node of the drawing, with its size and its geometry relative to its top
    left corner; ``anchor`` is the y of its flow line."""

    key: tuple
    w: float
    h: float
    anchor: float
    lines: list = field(default_factory=list)
    part: object = None
    mirror: bool = False
    x: float = 0.0
    y: float = 0.0
    rank: int = 0


def _part_vertex(part, extra: str | None):
    lines = [(t, cls) for t, cls in ((name_line(part), "name"), (value_line(part), "value"),
                                     (extra, "result")) if t]
    if part.pins:                     # a subcircuit box: sized once its pins' sides are known
        return Vertex(("part", part.key), 0, 0, 0, lines, part)
    sym = symbol(part.kind)
    ports = list(part.ports.items())
    left_ex = any(n == "atm" for p, n in ports[:1]) and sym.port == "both"
    right_ex = any(n == "atm" for p, n in ports[1:2]) and sym.port == "both"
    top = 20 if sym.pilot and part.ports.get("ctrl") == "atm" else 6 if sym.pilot else 0
    body = (EXHAUST_W + 2) * (left_ex + right_ex) + sym.w
    w = max(body, max(CHAR_W * len(t) for t, _ in lines)) + 4
    h = top + sym.h + 4 + LINE_H * len(lines)
    v = Vertex(("part", part.key), w, h, top + sym.flow_y, lines, part)
    v.sym, v.top, v.body = sym, top, body
    return v


def _node_vertex(key, label, extra: str | None):
    lines = [(label, "node")] + ([(extra, "result")] if extra else [])
    w = max(CHAR_W * len(t) for t, _ in lines) + 4
    return Vertex(("node", key), w, 8 + LINE_H * len(lines), 4, lines)


def _edges(sch: Schematic):
    """(node vertex key, part vertex key, port) for each port on a node, directed along the
    flow: node -> part for a part's inlet or a load, part -> node for an outlet or a source;
    control ports are ``"ctrl"``."""
    out = []
    for part in sch.parts.values():
        for pin in part.pins:
            if pin.node != "atm":
                pk, nk = ("part", part.key), ("node", pin.node)
                out.append((pk, nk, pin) if pin.role == "out" else (nk, pk, pin))
        if part.pins:
            continue
        sym = symbol(part.kind)
        ports = list(part.ports.items())
        for i, (port, node) in enumerate(ports):
            if node == "atm":
                continue
            pk, nk = ("part", part.key), ("node", node)
            if port == "ctrl":
                out.append((nk, pk, "ctrl"))
            elif len(ports) == 1 or sym.port != "both":
                out.append((pk, nk, port) if part.kind in SOURCES or sym.port == "right"
                           else (nk, pk, port))
            else:
                out.append((nk, pk, port) if i == 0 else (pk, nk, port))
    return out


def _feedback(vertices, edges):
    """Edges to reverse for a DAG: flow loops broken by depth-first search from the sources;
    then each control edge that would close a cycle."""
    g = nx.DiGraph()
    g.add_nodes_from(vertices)
    flow = [(a, b) for a, b, p in edges if not is_control(p)]
    g.add_edges_from(flow)
    roots = [v for v in vertices if v[0] == "part" and vertices[v].part.kind in SOURCES]
    removed = []
    while not nx.is_directed_acyclic_graph(g):     # a flow loop: drop the edge closing it
        a, b = nx.find_cycle(g, source=roots or None)[-1][:2]
        g.remove_edge(a, b)
        removed.append((a, b, "flow"))
    reverse = set()
    for a, b, p in removed + [e for e in edges if is_control(e[2])]:
        if nx.has_path(g, b, a):      # forward would close a cycle: draw it reversed
            g.add_edge(b, a)
            reverse.add((a, b))
        else:
            g.add_edge(a, b)
    return reverse, g


def _isotonic(targets, sizes, gap):
    """Tops closest (least squares) to ``targets`` with each top at least the previous
    top + its size + gap (pool-adjacent-violators on the shifted targets)."""
    shift, s = [], 0.0
    for size in sizes:
        shift.append(s)
        s += size + gap
    blocks = []                       # [mean, weight, count]
    for t, sh in zip(targets, shift):
        blocks.append([t - sh, 1.0, 1])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            m2, w2, c2 = blocks.pop()
            m1, w1, c1 = blocks.pop()
            blocks.append([(m1 * w1 + m2 * w2) / (w1 + w2), w1 + w2, c1 + c2])
    out = []
    for mean, _, count in blocks:
        out += [mean] * count
    return [z + sh for z, sh in zip(out, shift)]


def _place_y(layers, neighbours, anchor, size, sweeps=6):
    """y of each layer item's anchor: stacked, then pulled to its neighbours' barycentre
    (``neighbours[v]``: ``(u, off)``, a straight wire wants v's anchor at u's + off)."""
    y = {}
    for layer in layers:
        tops = _isotonic([0.0] * len(layer), [size[v] for v in layer], GAP_Y)
        y.update({v: t + anchor[v] for v, t in zip(layer, tops)})
    order = list(range(len(layers)))
    for sweep in range(sweeps):
        for r in (order if sweep % 2 == 0 else order[::-1]):
            layer = layers[r]
            targets = []
            for v in layer:
                near = [y[u] + off for u, off in neighbours[v]]
                targets.append((sum(near) / len(near) if near else y[v]) - anchor[v])
            tops = _isotonic(targets, [size[v] for v in layer], GAP_Y)
            y.update({v: t + anchor[v] for v, t in zip(layer, tops)})
    return y


def _finish_boxes(vertices, chains, sug) -> None:
    """Each box's pins on the side of the node they are wired to, in the order of the
    wires' next items in their layer; then the box's size."""
    sides: dict = {}
    for (a, b, port), chain in chains:
        for end, near in ((chain[0], chain[1]), (chain[-1], chain[-2])):
            v = vertices.get(getattr(end, "data", None))
            if v is not None and v.part is not None and v.part.pins:
                side = -1 if sug.grx[near].rank < sug.grx[end].rank else 1
                sides.setdefault(v.key, {})[port] = (side, sug.grx[near].pos)
    for key, pins in sides.items():
        boxes.finish(vertices[key], pins)
    for v in vertices.values():
        if v.part is not None and v.part.pins and v.key not in sides:
            boxes.finish(v, {})


def _pin_offset(vertices, item, edge) -> float:
    """y of a box's pin for ``edge`` below the box's anchor (0 for any other end)."""
    v = vertices.get(getattr(item, "data", None))
    if v is None or v.part is None or not v.part.pins:
        return 0.0
    return v.pin_y[edge[2]] - v.anchor


def _components(gv, gedges):
    """grandalf graphs of the connected parts, vertices and edges in the schematic's order
    (grandalf's ``Graph.C`` collects edges in a set: layouts that change from run to run)."""
    from grandalf.graphs import graph_core

    g = nx.Graph()
    g.add_nodes_from(gv)
    g.add_edges_from(e.data[:2] for e in gedges)
    index = {k: i for i, k in enumerate(gv)}
    comps = sorted((sorted(c, key=index.get) for c in nx.connected_components(g)),
                   key=lambda c: index[c[0]])
    out = []
    for keys in comps:
        inside = set(keys)
        out.append(graph_core([gv[k] for k in keys], [e for e in gedges if e.data[0] in inside]))
    return out


def layout(sch: Schematic, node_notes=None, part_notes=None) -> "Layout":
    """Place the parts and nodes of ``sch``; ``node_notes``/``part_notes`` add a line of
    text (results) under a node's or a part's label.  grandalf's barycentric ordering
    depends on the order it meets the edges: the drawing with the fewest crossings of
    ``ATTEMPTS`` orders is kept (the schematic's own first, then seeded shuffles)."""
    node_notes, part_notes = node_notes or {}, part_notes or {}
    vertices = {}
    for part in sch.parts.values():
        v = _part_vertex(part, part_notes.get(part.key))
        vertices[v.key] = v
    for key, label in sch.labels.items():
        v = _node_vertex(key, label, node_notes.get(key))
        vertices[v.key] = v
    edges = _edges(sch)
    reverse, dag = _feedback(vertices, edges)
    best = None
    for attempt in range(ATTEMPTS):
        rng = random.Random(attempt)
        keys = rng.sample(list(vertices), len(vertices)) if attempt else list(vertices)
        order = rng.sample(edges, len(edges)) if attempt else edges
        lay = _attempt(vertices, keys, order, reverse, dag)
        if best is None or lay.crossings() < best.crossings():
            best = lay
        if best.crossings() == 0:
            break
    return best


def _attempt(vertices, keys, edges, reverse, dag):
    """One layout, grandalf's crossing reduction started from the vertices ``keys`` and the
    ``edges`` in their order."""
    from grandalf.graphs import Edge, Vertex as GVertex
    from grandalf.layouts import SugiyamaLayout

    gv = {k: GVertex(k) for k in keys}
    for k, v in gv.items():
        v.view = type("View", (), {"w": vertices[k].h, "h": vertices[k].w})()
    gedges, inverted = [], []
    for a, b, port in edges:
        e = Edge(gv[a], gv[b], data=(a, b, port))
        gedges.append(e)
        if (a, b) in reverse:
            inverted.append(e)

    items_y, size, anchor, neighbours, columns = {}, {}, {}, {}, []
    chains = []
    y_offset = float(MARGIN)
    for comp in _components(gv, gedges):
        sug = SugiyamaLayout(comp)
        roots = [v for v in comp.sV if dag.in_degree(v.data) == 0]
        sug.init_all(roots=roots, inverted_edges=[e for e in inverted if e in comp.sE])
        for _ in range(4):
            for _ in sug.ordering_step():
                pass
        layers = [list(layer) for layer in sug.layers]
        comp_chains = []
        for e in comp.sE:
            ctrl = sug.ctrls.get(e)
            lo, hi = sorted((e.v[0], e.v[1]), key=lambda x: sug.grx[x].rank)
            comp_chains.append((e.data, [ctrl[r] for r in sorted(ctrl)] if ctrl else [lo, hi]))
        _finish_boxes(vertices, comp_chains, sug)
        for r, layer in enumerate(layers):
            for item in layer:
                real = getattr(item, "data", None)
                if real in vertices:
                    vertices[real].rank = r
                    size[item], anchor[item] = vertices[real].h, vertices[real].anchor
                else:
                    size[item], anchor[item] = 2.0, 1.0
                neighbours[item] = []
        for edge, chain in comp_chains:
            offset = {item: _pin_offset(vertices, item, edge) for item in (chain[0], chain[-1])}
            for p, q in zip(chain, chain[1:]):
                dp, dq = offset.get(p, 0.0), offset.get(q, 0.0)
                neighbours[p].append((q, dq - dp))
                neighbours[q].append((p, dp - dq))
        chains += comp_chains
        y = _place_y(layers, {k: [] for k in neighbours} | neighbours, anchor, size)
        low = min(y[v] - anchor[v] for layer in layers for v in layer)
        high = max(y[v] - anchor[v] + size[v] for layer in layers for v in layer)
        for v in y:
            items_y[v] = y[v] - low + y_offset
        while len(columns) < len(layers):
            columns.append([])
        for r, layer in enumerate(layers):
            columns[r] += layer
        y_offset += high - low + 3 * GAP_Y
    return route(vertices, chains, columns, items_y)

