"""Split a large circuit into a *hub* and many loosely coupled *cells*.

A hub node is an unknown node that many elements share (a supply line feeding
thousands of valves); the cells are the connected pieces that remain when the hub
nodes and every fixed node (references, source-pinned nodes) are cut out.  Every
element that touches a cell's node belongs to that cell; elements that touch only
hub and fixed nodes form the hub.  A pressure source whose node several cells (or
the hub) use is copied into each of them: a pinned pressure is a boundary, so the
copy is exact.

Cells with the same structure (the same element kinds joined the same way; their
parameters and the hub nodes they sit on may differ) form a *group*, integrated together as arrays by
:mod:`pneunet.engine.multirate`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..physics import elements

#: an unknown node with at least this many element ports is a hub candidate
HUB_DEGREE = 16
#: fewest cells for which ``method=auto`` partitions a circuit
AUTO_MIN_CELLS = 64
#: most unknowns a cell, and the hub, may have
MAX_CELL_UNKNOWNS = 32
MAX_HUB_UNKNOWNS = 64


@dataclass
class Cell:
    """One cell: its elements (in circuit order), unknown nodes and boundary nodes."""

    elements: list[str]
    nodes: list[str]                       # the cell's unknown nodes, first use first
    hub_nodes: list[str]                   # hub nodes its elements touch
    sources: list[str]                     # pressure sources of pinned nodes it touches
    signature: tuple = ()


@dataclass
class Partition:
    """Hub and cells of a circuit (see the module docstring)."""

    hub_nodes: list[str]
    hub_elements: list[str]
    hub_sources: list[str]
    cells: list[Cell]
    groups: list[list[int]] = field(default_factory=list)  # cell indices with one signature
    #: no cell element passes flow at a hub node (e.g. valves whose control ports alone
    #: sit on the hub): the hub does not depend on the cells
    read_only_hub: bool = False

    @property
    def largest_cell(self) -> int:
        return max((len(c.nodes) for c in self.cells), default=0)


def partition(circuit, hub_degree: int = HUB_DEGREE) -> Partition:
    """The hub and cells of ``circuit`` (hub nodes: unknown nodes with ≥ ``hub_degree``
    element ports)."""
    specs = list(circuit.elements.values())
    pinned_by = {}
    for spec in specs:
        fam = elements.family(spec.kind)
        for port in fam.pinned_ports:
            pinned_by[spec.nodes[port]] = spec.name
    fixed = set(pinned_by) | {n for n in circuit.nodes if circuit.is_reference(n)}
    degree: dict[str, int] = {}
    for spec in specs:
        for node in spec.nodes:
            if node not in fixed:
                degree[node] = degree.get(node, 0) + 1
    hub = {n for n, d in degree.items() if d >= hub_degree}

    parent = {n: n for n in degree if n not in hub}

    def root(n):
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n
    for spec in specs:
        own = [n for n in spec.nodes if n in parent]
        for other in own[1:]:
            a, b = root(own[0]), root(other)
            if a != b:
                parent[b] = a

    cells: dict[str, Cell] = {}
    hub_elements, hub_sources = [], set()
    for spec in specs:
        fam = elements.family(spec.kind)
        if fam.pinned_ports:
            continue
        own = [n for n in spec.nodes if n in parent]
        if not own:
            hub_elements.append(spec.name)
            hub_sources.update(pinned_by[n] for n in spec.nodes if n in pinned_by)
            continue
        cell = cells.setdefault(root(own[0]), Cell([], [], [], []))
        cell.elements.append(spec.name)
        for n in spec.nodes:
            if n in parent and n not in cell.nodes:
                cell.nodes.append(n)
            elif n in hub and n not in cell.hub_nodes:
                cell.hub_nodes.append(n)
            elif n in pinned_by and pinned_by[n] not in cell.sources:
                cell.sources.append(pinned_by[n])
    out = Partition(sorted(hub, key=list(degree).index), hub_elements,
                    sorted(hub_sources), list(cells.values()))
    out.read_only_hub = bool(hub) and not any(
        spec.nodes[port] in hub
        for cell in out.cells for spec in (circuit.elements[name] for name in cell.elements)
        for port in elements.family(spec.kind).passing_flow(len(spec.nodes)))
    groups: dict[tuple, list[int]] = {}
    for k, cell in enumerate(out.cells):
        cell.signature = _signature(circuit, cell, hub_as_sources=out.read_only_hub)
        groups.setdefault(cell.signature, []).append(k)
    out.groups = list(groups.values())
    return out


def _signature(circuit, cell: Cell, hub_as_sources=False) -> tuple:
    """The cell's structure: element kinds with their nodes numbered by first use
    (hub nodes apart: cells of one structure on different hub nodes are one group;
    references as 'ref', pinned nodes by first use too).  ``hub_as_sources``: hub nodes
    count as pinned nodes (a read-only hub pins them for the cells)."""
    local: dict[str, str] = {}
    hubs: dict[str, str] = {}
    parts = []
    for name in cell.elements:
        spec = circuit.elements[name]
        nodes = []
        for n in spec.nodes:
            if n in cell.hub_nodes and not hub_as_sources:
                nodes.append(hubs.setdefault(n, f"hub{len(hubs)}"))
            elif circuit.is_reference(n):
                nodes.append("ref")
            else:
                nodes.append(local.setdefault(n, f"n{len(local)}"))
        parts.append((spec.kind, tuple(nodes)))
    return tuple(parts)


def time_dependent(kind: str) -> bool:
    """Whether a family's flows depend on time itself (a waveform that pins no node)."""
    fam = elements.family(kind)
    return not fam.pinned_ports and any(p.kind == "waveform" for p in fam.params.values())


def worth_partitioning(part: Partition, algebraic: set[str]) -> str:
    """'' if ``method=auto`` should integrate this partition by cells, else why not."""
    if len(part.cells) < AUTO_MIN_CELLS:
        return f"{len(part.cells)} cell(s), fewer than {AUTO_MIN_CELLS}"
    return unsupported(part, algebraic)


def unsupported(part: Partition, algebraic: set[str]) -> str:
    """'' if the multirate method can integrate this partition, else why not;
    ``algebraic``: the circuit's nodes without a volume."""
    if not part.cells:
        return "the circuit has no cells"
    if part.largest_cell > MAX_CELL_UNKNOWNS:
        return f"a cell has {part.largest_cell} unknowns (more than {MAX_CELL_UNKNOWNS})"
    if len(part.hub_nodes) > MAX_HUB_UNKNOWNS:
        return f"the hub has {len(part.hub_nodes)} nodes (more than {MAX_HUB_UNKNOWNS})"
    hub_algebraic = [n for n in part.hub_nodes if n in algebraic]
    if hub_algebraic:
        return f"hub node {hub_algebraic[0]} has no volume"
    if part.hub_nodes and not part.read_only_hub:
        for cell in part.cells:
            without = [n for n in cell.nodes if n in algebraic]
            if without:
                return (f"node {without[0]} has no volume, and cells coupled through hub "
                        "nodes must have a volume at every node")
    return ""
