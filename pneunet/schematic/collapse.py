"""What a schematic shows: a circuit's elements as parts, with arrays drawn once.

Elements of an array or of arrayed subcircuit instances (``Xcell[3].X0``) whose names and
nodes differ only in their indices become one :class:`Part` with a count (``Xcell[0:7].X0
×8``); a tube's segments (``T1.s1`` … ``T1.sN``) become the tube.  Nodes are collapsed
the same way (``act[0:7]``).  Reference nodes (``0``, ``gnd``, ``atm``) are not nodes of
the drawing: each port on one gets its own exhaust symbol.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from .. import elements

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
    spec: object                    # the first element's ElementSpec
    segments: int = 1               # a tube's segment count

    @property
    def count(self) -> int:
        return len(self.names) // self.segments


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


def collapse(circuit) -> Schematic:
    """The parts and nodes of ``circuit`` (a :class:`~pneunet.Circuit`)."""

    tubes: dict[str, list] = {}
    plain = []
    for spec in circuit.elements.values():
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
    node_index: dict[str, list] = {}
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
