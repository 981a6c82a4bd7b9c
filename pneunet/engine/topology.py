"""Graph checks that make a circuit simulable, with errors naming the culprits."""
from __future__ import annotations

from ..common.errors import TopologyError


def _where(spec) -> str:
    return spec.where


def check_topology(circuit) -> None:
    """Raise :class:`TopologyError` for circuits the solver cannot handle.

    * no elements, or no defined pressure (no source and no reference node);
    * two pressure sources (or a source and a reference) on one node;
    * a node that only touches control ports (nothing sets its pressure);
    * a group of nodes joined by flow paths with neither a defined pressure nor
      a volume (their pressures are undetermined);
    * ``.ic`` on a node that does not exist.
    """
    from ..physics import elements

    if not circuit.elements:
        raise TopologyError("the circuit has no elements")
    nodes = circuit.nodes  # a property that walks every element: once here
    pinned: dict[str, str] = {n: "reference" for n in nodes if circuit.is_reference(n)}
    storage: set[str] = set()  # and elements' state nodes: neither floats
    flow_edges: list[tuple[str, str]] = []
    touched_by_flow: set[str] = set()
    for spec in circuit.elements.values():
        family = elements.family(spec.kind)
        for port in family.pinned_ports:
            node = spec.nodes[port]
            if node in pinned:
                other = pinned[node]
                raise TopologyError(
                    f"node {node!r} has its pressure set twice (by {spec.name} and by {other})",
                    where=_where(spec), hint="a node takes at most one pressure source; "
                    "reference nodes 0/gnd/atm are already at ambient pressure")
            pinned[node] = spec.name
        storage.update(spec.nodes[p] for p in family.storage_ports + family.state_ports)
        ports = family.passing_flow(len(spec.nodes))
        flow_nodes = [spec.nodes[p] for p in ports]
        touched_by_flow.update(flow_nodes)
        flow_edges += zip(flow_nodes, flow_nodes[1:])
    if not pinned:
        raise TopologyError("no node has a defined pressure",
                            hint="add a pressure source, or connect a vent to 'atm' (or '0')")
    floating = [n for n in nodes
                if n not in touched_by_flow and n not in pinned and n not in storage]
    if floating:
        users = [s.name for s in circuit.elements.values() if floating[0] in s.nodes]
        raise TopologyError(
            f"node {floating[0]!r} is floating: it only connects to control ports ({', '.join(users)})",
            where=f"node {floating[0]}", hint="connect it to a source, a volume or a resistor")
    for group in _components([n for n in nodes if n in touched_by_flow], flow_edges):
        if pinned.keys().isdisjoint(group) and storage.isdisjoint(group):
            names = ", ".join(sorted(group))
            raise TopologyError(f"nodes {names} have no path to a defined pressure and no volume",
                                where=f"node {sorted(group)[0]}",
                                hint="connect them to a source or reference node, or add a volume")
    known = set(nodes)
    unknown = [n for n in circuit.initial if n not in known]
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0], nodes, n=1)
        raise TopologyError(f"initial condition for unknown node {unknown[0]!r}",
                            where=f"node {unknown[0]}",
                            hint=f"did you mean {close[0]!r}?" if close else None)


def _components(nodes, edges) -> list[set[str]]:
    """Connected components of an undirected graph (union-find), in order of first node."""
    parent = {n: n for n in nodes}

    def root(n):
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n
    for a, b in edges:
        parent[root(a)] = root(b)
    groups: dict[str, set[str]] = {}
    for n in nodes:
        groups.setdefault(root(n), set()).add(n)
    return list(groups.values())


#: name comparisons spent on did-you-means (each compares one name with every node's)
COMPARISONS = 50_000


def dangling_nodes(circuit) -> list[str]:
    """Warnings for nodes with a single connection (a misspelt node name makes one, as
    in SPICE): ``file:line: node 'tnak' has one connection (Rvent); did you mean 'tank'?``.
    The first ones get a did-you-mean among the connected nodes (at least one, as many as
    :data:`COMPARISONS` name comparisons allow)."""
    import difflib

    seen: dict[str, list] = {}
    for spec in circuit.elements.values():
        for node in spec.nodes:
            seen.setdefault(node, []).append(spec)
    dangling = [n for n, specs in seen.items() if len(specs) == 1 and
                not circuit.is_reference(n) and not _internal_state(specs[0], n)]
    if not dangling:
        return []
    connected = [n for n, specs in seen.items() if len(specs) > 1 and not circuit.is_reference(n)]
    suggested = max(1, COMPARISONS // max(len(connected), 1))
    out = []
    for i, node in enumerate(dangling):
        spec = seen[node][0]
        close = difflib.get_close_matches(node, connected, n=1, cutoff=0.6) \
            if i < suggested else []
        where = f"{spec.span}: " if spec.span else ""
        out.append(f"{where}node {node!r} has one connection ({spec.name})"
                   + (f"; did you mean {close[0]!r}?" if close else ""))
    return out


def _internal_state(spec, node) -> bool:
    """A node where the element keeps a state of its own (a storage port passing no flow,
    e.g. a hysteretic check valve's open fraction): one connection is all it has."""
    from ..physics import elements

    family = elements.family(spec.kind)
    port = spec.nodes.index(node)
    return (port in family.storage_ports + family.state_ports
            and port not in family.passing_flow(len(spec.nodes)))
