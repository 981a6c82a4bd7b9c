"""Subcircuit instances drawn as boxes: an instance, or an array of them drawn once with its
count, is one box titled with its subcircuit's name, a pin per port (an array whose members
reach different nodes on one port has a pin per node), its parameters written under it.

A pin's role sets the direction the layered layout gives its wire: ``"out"`` where another
port or a source inside lies upstream through the subcircuit's own flow paths (and, but for
the first port, none downstream), ``"in"`` otherwise (flow on to another port or an
exhaust, or a load), ``"ctrl"`` where the port reaches only valves' control ports (drawn
dashed).  Which side of the box a pin sits on is chosen once the layers are
known: the side of the node it is wired to, pins ordered as their neighbours are.
"""
from __future__ import annotations

from dataclasses import dataclass

import networkx as nx

from ...physics import elements
from .geometry import CHAR_W, LINE_H
from .symbols import EXHAUST_W, Symbol, exhaust

TITLE_H = 16       # px for the subcircuit's name inside the box
PIN_GAP = 16       # px between two pins on a side


@dataclass(frozen=True)
class Pin:
    """One wire of a box: the subcircuit's ``port`` on a node key (or ``"atm"``)."""

    port: str
    node: str
    role: str       # "in", "out" or "ctrl"


def is_control(port) -> bool:
    """A part's valve pilot port or a box's control pin: its line is drawn dashed."""
    return port == "ctrl" or getattr(port, "role", "") == "ctrl"


def roles(circuit, inst, aux_ports) -> dict[str, str]:
    """``{port: "in" | "out" | "ctrl"}`` of instance ``inst`` from its own elements."""
    flow, ctrl = nx.DiGraph(), set()
    source, exhaust = ("source",), ("exhaust",)          # not node names
    for name in inst.elements:
        spec = circuit.elements[name]
        ports = [(p, exhaust if circuit.is_reference(n) else n) for p, n in
                 zip(elements.family(spec.kind).ports, spec.nodes) if p not in aux_ports]
        ctrl.update(n for p, n in ports if p == "ctrl")
        lines = [n for p, n in ports if p != "ctrl"]
        flow.add_nodes_from(lines)
        if len(lines) == 2:
            flow.add_edge(*lines)
        elif spec.kind in ("pressure_source", "flow_source") and lines:
            flow.add_edge(source, lines[-1])
    out = {}
    for i, (port, node) in enumerate(inst.ports.items()):
        if node not in flow or node == exhaust:
            out[port] = "ctrl" if node in ctrl else "in"
            continue
        others = {n for p, n in inst.ports.items() if n != node}
        down = bool(others & nx.descendants(flow, node))
        up = bool((others | {source}) & nx.ancestors(flow, node))
        out[port] = "out" if up and (not down or i > 0) else "in"
    return out


def params_line(members) -> str:
    """``Rp=20``, or ``V=100…298`` where an array's members differ."""
    shown = []
    for key in members[0].params:
        vals = [m.params[key] for m in members if isinstance(m.params.get(key), (int, float))]
        if not vals:
            continue
        lo, hi = min(vals), max(vals)
        shown.append(f"{key}={lo:.4g}" if lo == hi else f"{key}={lo:.4g}…{hi:.4g}")
    return " ".join(shown)


def finish(v, sides: dict) -> None:
    """Size box vertex ``v`` once each pin's side is known: ``sides`` maps a pin to
    ``(-1 | +1, order)``; sets ``v.pin_y`` (pin -> y from the vertex's top) and
    ``v.pin_side``, its symbol (the box), size and anchor (the first pin's y)."""
    part = v.part
    first: dict = {}                  # (side, node) -> the order of its first pin's wire
    for p, (side, order) in sides.items():
        first[side, p.node] = min(order, first.get((side, p.node), order))

    def on(side):                     # a node's pins together, in the subcircuit's port order
        pins = [p for p in part.pins if p in sides and sides[p][0] == side]
        return sorted(pins, key=lambda p: (first[side, p.node], part.pins.index(p)))

    ref = [p for p in part.pins if p.node == "atm"]
    left, right = on(-1), on(1) + ref
    v.pin_side = {p: -1 for p in left} | {p: 1 for p in right}
    v.pin_y = {}
    for pins in (left, right):
        for i, p in enumerate(pins):
            v.pin_y[p] = TITLE_H + PIN_GAP * (i + 0.5)
    width = max(CHAR_W * len(part.subckt) + 10,
                CHAR_W * (max((len(p.port) for p in left), default=0)
                          + max((len(p.port) for p in right), default=0) + 2) + 10, 48)
    height = TITLE_H + PIN_GAP * max(len(left), len(right), 1) + 2
    rect = ("path", ((0, 0), (width, 0), (width, height), (0, height)), True, None, False)
    v.sym, v.top = Symbol(width, height, (rect,)), 0
    v.body = width + (EXHAUST_W + 2 if ref else 0)
    v.w = max(v.body, max(CHAR_W * len(t) for t, _ in v.lines)) + 4
    v.h = height + 4 + LINE_H * len(v.lines)
    v.anchor = min(v.pin_y.values(), default=height / 2)


def pin_point(v, sx, pin):
    """Where ``pin``'s wire meets box vertex ``v`` whose box's top left is ``(sx, v.y)``."""
    return (sx if v.pin_side[pin] < 0 else sx + v.sym.w), v.y + v.pin_y[pin]


def draw(v, sx, prims, box) -> list:
    """The title, pin names and exhausts of box vertex ``v``; returns ``box`` grown by
    the exhausts."""
    prims.append(("text", (sx + v.sym.w / 2, v.y + TITLE_H - 4), v.part.subckt, "name"))
    for pin, side in v.pin_side.items():
        x, y = pin_point(v, sx, pin)
        prims.append(("text", (x - side * (CHAR_W * len(pin.port) / 2 + 4), y + 4), pin.port,
                      "value"))
        if pin.node == "atm":
            more, ebox = exhaust(x, y, 1)
            prims.extend(more)
            box = [min(box[0], ebox[0]), min(box[1], ebox[1]), max(box[2], ebox[2]),
                   max(box[3], ebox[3])]
    return box
