"""What a schematic shows: a circuit's elements as parts, with arrays drawn once.

Elements of an array or of arrayed subcircuit instances (``Xcell[3].X0``) whose names and
nodes differ only in their indices become one :class:`Part` with a count (``Xcell[0:7].X0
×8``); a tube's segments (``T1.s1`` … ``T1.sN``) become the tube.  Nodes are collapsed
the same way (``act[0:7]``).  Reference nodes (``0``, ``gnd``, ``atm``) are not nodes of
the drawing: each port on one gets its own exhaust symbol.  Given a netlist's subcircuit
instances, each top-level instance (or array of them) is one box (:mod:`.boxes`) in place of
its elements.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from ...physics import elements
from .boxes import Pin, params_line, roles

_INDEX = re.compile(r"\[(\d+)\]")
_SEGMENT = re.compile(r"^(.*)\.s(\d+)$")

#: ports that are not pneumatic lines (mechanical or thermal states, a check valve's state)
AUX_PORTS = {"x", "v", "heat", "state"}


@dataclass
class Part:
    """One symbol: an element, or an array of them drawn once."""

    key: str
    kind: str
    label: str                      # the name as drawn (``Xcell[0:7].X0``)
    names: list[str]                # every element it stands for
    ports: dict[str, str]           # port name -> node key (or a reference node)
    spec: object                    # the first element's ElementSpec (None: a box)
    segments: int = 1               # a tube's segment count
    pins: tuple = ()                # a subcircuit box's pins (:class:`.boxes.Pin`)
    subckt: str = ""                # a box's subcircuit
    params: str = ""                # a box's parameters
    instances: int = 0              # a box's count of instances

    @property
    def count(self) -> int:
        return self.instances or len(self.names) // self.segments


@dataclass
class Schematic:
    """Parts and the nodes that join them (keys collapsed as the parts are)."""

    parts: dict[str, Part] = field(default_factory=dict)
    nodes: dict[str, list[str]] = field(default_factory=dict)   # node key -> circuit nodes
    labels: dict[str, str] = field(default_factory=dict)        # node key -> label

    def is_reference(self, key: str) -> bool:
        return key not in self.nodes


def _pattern(name: str) -> tuple[str, tuple[int, ...]]:
    """``Xcell[3].n1`` -> (``Xcell[#].n1``, (3,))."""
    return _INDEX.sub("[#]", name), tuple(int(i) for i in _INDEX.findall(name))


def _ranges(indices) -> str:
    """``[0, 1, 2, 5]`` -> ``0:2,5``; more than three runs -> ``0,2,…,62``."""
    values = sorted(set(indices))
    runs, start = [], values[0]
    for prev, v in zip(values, values[1:] + [None]):
        if v != prev + 1:
            runs.append(str(start) if start == prev else f"{start}:{prev}")
            start = v
    return ",".join(runs) if len(runs) <= 3 else f"{runs[0]},{runs[1]},…,{runs[-1]}"


def _label(pattern: str, indices: list[tuple[int, ...]]) -> str:
    """The pattern with each ``[#]`` replaced by the range of its indices."""
    parts = pattern.split("[#]")
    text = parts[0]
    for i, rest in enumerate(parts[1:]):
        text += "[" + _ranges([ix[i] for ix in indices]) + "]" + rest
    return text


def _boxes(circuit, instances):
    """Box parts of the top-level ``instances``, one per array, and the nodes they reach
    ``[(index, node)]`` by node pattern."""
    groups: dict[tuple, list] = {}
    for inst in instances:
        if inst.depth == 0:
            groups.setdefault((_pattern(inst.name)[0], inst.subckt), []).append(inst)
    parts, nodes = [], {}
    for (pat, subckt), members in groups.items():
        role = roles(circuit, members[0], AUX_PORTS)
        pins = {}
        for m in members:
            for port, node in m.ports.items():
                ref = circuit.is_reference(node)
                p, i = ("atm", ()) if ref else _pattern(node)
                pins.setdefault(Pin(port, p, role[port]), None)
                if not ref:
                    nodes.setdefault(p, []).append((i, node))
        label = _label(pat, [_pattern(m.name)[1] for m in members]) if "[#]" in pat else pat
        names = [n for m in members for n in m.elements]
        parts.append(Part(label, "subckt", label, names, {}, None, pins=tuple(pins),
                          subckt=subckt, params=params_line(members), instances=len(members)))
    return parts, nodes


def collapse(circuit, instances=None) -> Schematic:
    """The parts and nodes of ``circuit`` (a :class:`~pneunet.Circuit`); each top-level
    subcircuit instance of ``instances`` (a netlist's, :class:`~pneunet.netlist.deck.
    Instance`) a box."""

    boxes, node_index = _boxes(circuit, instances or [])
    inside = {n for b in boxes for n in b.names}
    tubes: dict[str, list] = {}
    plain = []
    for spec in circuit.elements.values():
        if spec.name in inside:
            continue
        m = _SEGMENT.match(spec.name)
        if spec.kind == "tube" and m:
            tubes.setdefault(m.group(1), []).append((int(m.group(2)), spec))
        else:
            plain.append((spec.name, spec, spec.nodes, 1))
    for name, segs in tubes.items():
        segs.sort(key=lambda s: s[0])
        first, last = segs[0][1], segs[-1][1]
        plain.append((name, first, (first.nodes[0], last.nodes[1]), len(segs)))
        plain[-1] = plain[-1] + ([s.name for _, s in segs],)

    groups: dict[tuple, list] = {}
    for item in plain:
        name, spec, nodes, segments = item[:4]
        pat, idx = _pattern(name)
        node_pats = tuple(_pattern(n)[0] for n in nodes)
        groups.setdefault((pat, spec.kind, node_pats, segments), []).append((idx, item))
        for port, n in zip(elements.family(spec.kind).ports, nodes):
            if port not in AUX_PORTS and not circuit.is_reference(n):
                p, i = _pattern(n)
                node_index.setdefault(p, []).append((i, n))

    sch = Schematic()
    for pat, members in node_index.items():
        names = list(dict.fromkeys(n for _, n in members))
        sch.nodes[pat] = names
        sch.labels[pat] = _label(pat, [_pattern(n)[1] for n in names]) if "[#]" in pat else pat
    used: dict[str, int] = {}
    for box in boxes:
        sch.parts[box.key] = box
        used[box.label] = 1
    for (pat, kind, node_pats, segments), members in groups.items():
        family = elements.family(kind)
        names = [n for _, item in members for n in (item[4] if len(item) > 4 else [item[0]])]
        label = _label(pat, [idx for idx, _ in members]) if "[#]" in pat else pat
        key = label if label not in used else f"{label}#{used[label]}"
        used[label] = used.get(label, 0) + 1
        ports = {}
        for port, node, npat in zip(family.ports, members[0][1][2], node_pats):
            if port not in AUX_PORTS:
                ports[port] = "atm" if circuit.is_reference(node) else npat
        sch.parts[key] = Part(key, kind, label, names, ports, members[0][1][1], segments)
    return sch
