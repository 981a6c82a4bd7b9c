"""Circuit effects: physics a recording may show that the netlist lacks.

An effect adds free parameters ({name: (guess, low, high)}, positive, fitted in log
space) and edits a built circuit in place (``apply(circuit, values)``).  An effect
*kind* may act at many sites of a circuit; ``candidates(circuit)`` returns one bound
effect per site (a dead volume at each node, a tube on each line).

Built in, each in its published forms:

* heat exchange in volumes: the static polytropic exponent n (1 isothermal … 1.4
  adiabatic), and the gas energy balance with wall heat transfer of time constant τ
  (Simscape Gas / Modelica volumes; :mod:`pneunet.physics.elements.thermal`);
* a dead volume at any node without one (tubing, fittings, valve cavities);
* a tube on any line, control lines included: a resistance R and a volume V between a
  node and the element port it feeds (on a volume's own line, R alone).

Your own: subclass :class:`CircuitEffect` (or give a netlist fragment with free
parameters, :class:`NetlistEffect`) and :func:`register` it; see docs/diagnose.md.
"""
from __future__ import annotations

import copy
from abc import ABC, abstractmethod

from ...common.errors import ParameterError

#: screening grid points per parameter, for effects with 1, 2 (or more) parameters
GRID_POINTS = (5, 3, 2)
#: a tube at a port of these is a dead volume inside a series resistance: the same
#: physics as a dead volume at a node plus a refitted resistance, so not offered there
#: (a thermal_inlet is a zero-resistance link into a chamber: a tube there is a tube at
#: the line it joins)
SERIES_KINDS = ("resistor", "pipe", "thermal_inlet")


class CircuitEffect(ABC):
    """Base class of circuit effects.

    Set ``name`` (unique id), ``family`` (the physics) and ``form`` (which published
    form), ``description``, ``params`` {name: (guess, low, high)} with (low, high) the
    physically plausible range (the screen tries points across it, :meth:`grid`), and
    implement
    :meth:`apply`.  Override :meth:`candidates` when the effect acts at sites.
    """

    name = ""
    family = ""
    form = ""
    description = ""
    params: dict = {}

    def candidates(self, circuit) -> list["CircuitEffect"]:
        """The bound effects this kind offers for ``circuit`` (default: itself)."""
        return [self]

    def limits(self, circuit, values: dict) -> list[tuple[str, dict]]:
        """Simpler effects this one becomes in a limit of its parameters: (the simpler
        effect's name, its parameters' values taken from ``values``, this effect's
        fitted ones) each.  The diagnosis fits those the screen left out from there
        (default: none)."""
        return []

    def grid(self) -> list[dict]:
        """Parameter points the screen tries: per parameter :data:`GRID_POINTS` values
        log-spaced inside (low, high) (at 1/2n, 3/2n … of the log range), all
        combinations."""
        import itertools

        import numpy as np

        n = self._grid_points()
        axes = [np.exp(np.log(lo) + (np.arange(n) + 0.5) / n * np.log(hi / lo))
                for _, lo, hi in self.params.values()]
        return [dict(zip(self.params, map(float, point))) for point in itertools.product(*axes)]

    def grid_steps(self) -> dict:
        """{parameter: the spacing of :meth:`grid` along it, in ln value}."""
        import math

        return {k: math.log(hi / lo) / self._grid_points()
                for k, (_, lo, hi) in self.params.items()}

    def _grid_points(self) -> int:
        return GRID_POINTS[min(len(self.params), len(GRID_POINTS)) - 1] if self.params else 0

    @abstractmethod
    def apply(self, circuit, values: dict) -> None:
        """Edit ``circuit`` in place with parameter ``values``."""

    def to_json(self) -> dict:
        return {"effect": self.name, "family": self.family, "form": self.form,
                "description": self.description,
                "params": {k: list(v) for k, v in self.params.items()}}

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r})"


def _gas_volumes(circuit, names=None):
    """The isothermal volumes and actuators of ``circuit`` (what heat exchange edits), only
    those named in ``names`` when given."""
    return [s for s in circuit.elements.values() if s.kind in ("volume", "actuator")
            and (names is None or s.name in names)]


class _VolumesEffect(CircuitEffect):
    """An effect on the gas volumes of a circuit: bound by :meth:`candidates` to the
    volumes the circuit has, so that a volume another effect adds (a tube's, a dead
    volume) is not changed with them, whatever order the effects are applied in.

    With ``site`` the effect acts on its one volume alone (``name@volume``, parameters
    ``param@volume``): where a circuit has several volumes, one may show the effect
    while the others do not (a small fast volume beside a large slow one), or each with
    its own value (two site effects fitted as a pair).  Offered as candidates only by
    kinds with ``per_volume``."""

    #: whether :meth:`candidates` also offers each volume on its own (several volumes)
    per_volume = False

    def __init__(self, volumes: tuple | None = None, site: bool = False):
        self.volumes = None if volumes is None else tuple(volumes)
        self.site = site
        if site:
            if self.volumes is None or len(self.volumes) != 1:
                raise ParameterError(f"{self.name}: a site effect acts on one volume, "
                                     f"got {self.volumes}")
            (v,) = self.volumes
            self.name = f"{type(self).name}@{v}"
            self.params = {f"{k}@{v}": r for k, r in type(self).params.items()}

    def candidates(self, circuit):
        """Every volume at once, and each on its own where there are several (a site
        effect: itself)."""
        if self.site:
            return [self]
        names = tuple(s.name for s in _gas_volumes(circuit))
        if not names:
            return []
        return [type(self)(names)] + ([type(self)((n,), site=True) for n in names]
                                      if self.per_volume and len(names) > 1 else [])

    def _targets(self, circuit):
        return _gas_volumes(circuit, self.volumes)

    def _value(self, values, key) -> float:
        return float(values[f"{key}@{self.volumes[0]}" if self.site else key])


class PolytropicVolume(_VolumesEffect):
    """Every volume of the netlist compresses polytropically with one exponent n (not
    offered per volume: on the inverter chain an exponent per volume absorbed a leak of
    one output within the tolerance, benchmarks/README.md)."""

    name = "polytropic_volume"
    family = "heat exchange in volumes"
    form = "static polytropic exponent n (1 isothermal … 1.4 adiabatic)"
    description = "volumes exchange only part of their compression heat (p·V^n constant)"
    params = {"n": (1.02, 1.0, 1.67)}

    def apply(self, circuit, values):
        for spec in self._targets(circuit):
            spec.params["n"] = self._value(values, "n")


class VolumeHeatTransfer(_VolumesEffect):
    """Every volume of the netlist with a gas energy balance and wall heat transfer of time
    constant τ; where there are several, also each on its own."""

    per_volume = True

    name = "volume_heat_transfer"
    family = "heat exchange in volumes"
    form = ("gas energy balance with constant wall conductance hA = m_ref·c_v/τ "
            "(Simscape/Modelica)")
    description = "gas temperature in the volumes follows compression and relaxes to the wall"
    params = {"tau": (0.01, 0.002, 50.0)}

    def apply(self, circuit, values):
        """A volume with one line becomes a ``thermal_volume``; one filled and emptied
        through several becomes a ``thermal_chamber`` with a ``thermal_inlet`` per line,
        so that each line carries its own enthalpy."""
        import numpy as np

        for spec in self._targets(circuit):
            p = spec.params
            V = p["V"]
            if spec.kind == "actuator" and np.isnan(V):
                V = np.pi / 4 * p["diameter"] ** 2 * p["length"] * 1e-3
            node, heat = spec.nodes[0], f"{spec.name}__T"
            p0 = None if np.isnan(p["p0"]) else float(p["p0"])
            del circuit.elements[spec.name]
            lines = _lines_at(circuit, node)
            kind = "thermal_volume" if len(lines) <= 1 else "thermal_chamber"
            circuit.add(kind, spec.name, (node, heat), V=float(V),
                        tau=self._value(values, "tau"), p0=p0)
            if kind == "thermal_chamber":
                for line, k in lines:
                    nodes = list(line.nodes)
                    nodes[k] = f"{node}__{line.name}"
                    line.nodes = tuple(nodes)
                    circuit.add("thermal_inlet", f"I{spec.name}_{line.name}",
                                (nodes[k], node, heat), p0=p0)


def _lines_at(circuit, node):
    """(element spec, port index) of every port at ``node`` that passes flow."""
    from ...physics import elements

    out = []
    for s in circuit.elements.values():
        out += [(s, k) for k in elements.family(s.kind).passing_flow(len(s.nodes))
                 if s.nodes[k] == node]
    return out


class DeadVolume(CircuitEffect):
    """A volume at a node that has none (tubing, fittings, a valve cavity)."""

    name = "dead_volume"
    family = "dead volume"
    form = "isothermal volume V at a node"
    description = "gas volume at a node the netlist models without storage"
    params = {"V_dead": (0.05, 0.005, 200.0)}

    def __init__(self, node: str | None = None):
        self.node = node
        if node is not None:
            self.name = f"dead_volume@{node}"
            self.params = {f"V_dead@{node}": DeadVolume.params["V_dead"]}

    def candidates(self, circuit):
        from ...physics import elements

        stored, pinned = set(), set()
        for s in circuit.elements.values():
            fam = elements.family(s.kind)
            stored.update(s.nodes[p] for p in fam.storage_ports + fam.state_ports)
            pinned.update(s.nodes[p] for p in fam.pinned_ports)
            if fam.link_ports:  # a link's line node is at its volume's pressure: a dead
                stored.add(s.nodes[fam.link_ports[0]])  # volume there is more of that volume
        return [DeadVolume(n) for n in circuit.nodes
                if n not in stored and n not in pinned and not circuit.is_reference(n)]

    def apply(self, circuit, values):
        if self.node is None:
            raise ParameterError("dead_volume: bind it to a node (DeadVolume('out'))")
        circuit.volume(f"Vdead_{self.node}", self.node, V=float(values[f"V_dead@{self.node}"]))


class Tube(CircuitEffect):
    """A tube (resistance + volume) on the line from a node to an element's port."""

    name = "tube"
    family = "tube on a line"
    form = "quadrature resistance R then volume V at the element's port"
    description = "tubing between a node and the port it feeds (control lines included)"
    params = {"R_tube": (0.02, 0.002, 20.0), "V_tube": (0.05, 0.005, 200.0)}

    def __init__(self, element: str | None = None, port: str | None = None,
                 with_volume: bool = True):
        self.element, self.port, self.with_volume = element, port, with_volume
        if element is not None:
            site = f"{element}.{port}"
            self.name = f"tube@{site}"
            self.params = {f"R_tube@{site}": Tube.params["R_tube"]}
            if with_volume:
                self.params[f"V_tube@{site}"] = Tube.params["V_tube"]

    def candidates(self, circuit):
        from ...physics import elements

        stored, pinned, attached = set(), set(), {}
        for s in circuit.elements.values():
            fam = elements.family(s.kind)
            stored.update(s.nodes[p] for p in fam.storage_ports)
            pinned.update(s.nodes[p] for p in fam.pinned_ports)
            for node in s.nodes:
                attached.setdefault(node, []).append(s.kind)
        out = []
        for s in circuit.elements.values():
            fam = elements.family(s.kind)
            if fam.pinned_ports or len(fam.ports) != len(s.nodes) or s.kind in SERIES_KINDS:
                continue
            for k, port in enumerate(fam.ports):
                node = s.nodes[k]
                if port == "heat" or k in fam.state_ports or circuit.is_reference(node):
                    continue
                # a node where this element meets only series resistances: the tube is
                # a dead volume there plus a refitted resistance
                others = list(attached[node])
                others.remove(s.kind)
                if node not in stored | pinned and all(o in SERIES_KINDS for o in others):
                    continue
                # a tube before a volume: its own volume merges with the vessel's
                out.append(Tube(s.name, port, with_volume=k not in fam.storage_ports))
        return out

    def limits(self, circuit, values):
        """A tube of vanishing resistance is its volume at the node it joins: the dead
        volume there (the driven amplifier's 4 mL between its valves was named
        ``tube@Xin.out``, R 0.0073, V 3.997 mL, where the dead volume's best grid point,
        1.0 mL, had it screened out)."""
        from ...physics import elements

        if not self.with_volume:
            return []
        spec = circuit.elements[self.element]
        node = spec.nodes[elements.family(spec.kind).ports.index(self.port)]
        return [(f"dead_volume@{node}",
                 {f"V_dead@{node}": values[f"V_tube@{self.element}.{self.port}"]})]

    def apply(self, circuit, values):
        from ...physics import elements

        if self.element is None:
            raise ParameterError("tube: bind it to a line (Tube('X1', 'ctrl'))")
        spec = circuit.elements[self.element]
        k = elements.family(spec.kind).ports.index(self.port)
        site = f"{self.element}.{self.port}"
        node = spec.nodes[k]
        inner = f"{node}__{self.element}_{self.port}"
        nodes = list(spec.nodes)
        nodes[k] = inner
        spec.nodes = tuple(nodes)
        circuit.resistor(f"Rtube_{self.element}_{self.port}", node, inner,
                         R=float(values[f"R_tube@{site}"]))
        if self.with_volume:
            circuit.volume(f"Vtube_{self.element}_{self.port}", inner,
                           V=float(values[f"V_tube@{site}"]))


class NetlistEffect(CircuitEffect):
    """An effect written as a netlist fragment whose ``.param`` values are fitted.

    ``fragment`` is netlist text (``.param`` lines with defaults, then elements using
    ``{name}``), naming nodes of the base circuit; its elements are added to it.
    ``params`` {name: (guess, low, high)} are the fragment parameters to fit."""

    def __init__(self, name: str, fragment: str, params: dict, description: str = "",
                 family: str = "user", form: str = "netlist fragment"):
        self.name, self.fragment, self.params = name, fragment, dict(params)
        self.description, self.family, self.form = description, family, form

    def apply(self, circuit, values):
        from ...common.errors import TopologyError
        from ...netlist import parse_netlist

        deck = parse_netlist(self.fragment, name=f"<effect {self.name}>",
                             overrides={k: float(v) for k, v in values.items()})
        for spec in deck.circuit.elements.values():
            if spec.name in circuit.elements:
                raise TopologyError(f"effect {self.name}: element {spec.name} already exists "
                                    "in the circuit", hint="rename it in the fragment")
            circuit.elements[spec.name] = copy.deepcopy(spec)


_REGISTRY: dict[str, CircuitEffect] = {}


def register(effect):
    """Make a circuit effect (an instance, or a class with a no-argument constructor)
    a default candidate of every trace diagnosis; returns it (usable as decorator)."""
    inst = effect() if isinstance(effect, type) else effect
    if not isinstance(inst, CircuitEffect) or not inst.name:
        raise ParameterError(f"{effect!r} is not a named CircuitEffect")
    _REGISTRY[inst.name] = inst
    return effect


def unregister(name: str) -> None:
    """Remove a registered effect (for tests and notebooks)."""
    _REGISTRY.pop(name, None)


def registered_effects() -> list[CircuitEffect]:
    """The registered effect kinds, built-in first."""
    return list(_REGISTRY.values())


def candidates_for(circuit, effects=None) -> list[CircuitEffect]:
    """Bound candidate effects for ``circuit``: from ``effects`` (kinds or bound
    effects; default all registered), expanded to their sites, names unique."""
    kinds = registered_effects() if effects is None else list(effects)
    every = None
    out, seen = [], set()
    for kind in kinds:
        if isinstance(kind, str):
            if kind in _REGISTRY:
                bound = _REGISTRY[kind].candidates(circuit)
            else:  # a bound name such as tube@X1.ctrl
                if every is None:
                    every = {e.name: e for k in _REGISTRY.values() for e in k.candidates(circuit)}
                if kind not in every:
                    raise ParameterError(f"unknown circuit effect {kind!r}",
                                         hint="known: " + ", ".join(sorted(set(_REGISTRY)
                                                                          | set(every))))
                bound = [every[kind]]
        else:
            bound = kind.candidates(circuit)
        for eff in bound:
            if eff.name not in seen:
                seen.add(eff.name)
                out.append(eff)
    return out


for _kind in (PolytropicVolume, VolumeHeatTransfer, DeadVolume, Tube):
    register(_kind)
