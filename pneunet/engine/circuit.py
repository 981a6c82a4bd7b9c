"""Circuit: elements joined at named nodes, backed by a networkx graph.

Build one from Python::

    c = Circuit("oscillator")
    c.pressure_source("PH", "supply", 496)           # kPa absolute
    c.valve("X1", "supply", "out", "tank", model="axi")
    c.resistor("Rout", "out", "tank", R=1.132)       # kPa·s/mg
    c.volume("V1", "tank", V="200mL")
    c.resistor("Rvent", "tank", "atm", R=3)
    sol = c.tran(20)

Numbers are in pneunet's internal units (kPa, mg/s, kPa·s/mg, mL, mm, s);
strings carry their own unit (``"4.96bar"``, ``"200kPag"``).  The reference
nodes ``0``, ``gnd`` and ``atm`` are at the ambient pressure.
"""
from __future__ import annotations

import difflib
import os
import re
from typing import Any

from ..physics import elements
from ..common.errors import ParameterError, SourceSpan, TopologyError
from ..physics.elements.base import ElementSpec
from .options import SimulationOptions
from ..physics.units import split_quantity, to_internal
from ..physics.waveforms import Waveform, as_waveform

REFERENCE_NODES = ("0", "gnd", "atm")
#: what a netlist word cannot hold (white space, control characters, its punctuation):
#: a name with one would not parse back from :func:`~pneunet.netlist.print_circuit`
_NOT_IN_NAME = re.compile(r'[\s=(){},;"\x00-\x1f\x7f-\x9f]')


def _check_name(name: str, what: str, where: str) -> None:
    """A ParameterError unless ``name`` is one netlist word (as ``print_circuit`` writes it)."""
    bad = _NOT_IN_NAME.search(name) if name else None
    if not name or bad or name[0] in "*+.;":
        char = bad.group() if bad else name[:1]
        raise ParameterError(
            f"{what} {name!r} cannot be written in a netlist"
            + (f" (it holds {char!r})" if name else " (it is empty)"), where=where,
            hint="use letters, digits and _ . : [ ] # - (no spaces, control characters, "
                 "quotes, '=', ',', ';', parentheses or braces; not starting with * + . ;)")


def _check_distinct(family, nodes, where: str) -> None:
    """A TopologyError when two of the ports that pass flow share a node (``R1 x x 1``:
    a flow from a node into itself)."""
    flow = family.passing_flow(len(nodes))
    same = ["atm" if n in REFERENCE_NODES else n for n in nodes]  # 0, gnd, atm: one node
    for i, a in enumerate(flow):
        for b in flow[i + 1:]:
            if same[a] == same[b]:
                node = repr(nodes[a]) if nodes[a] == nodes[b] else \
                    f"{nodes[a]!r} = {nodes[b]!r} (the ambient)"
                raise TopologyError(
                    f"{family.kind} has its ports {family.ports[a]} and {family.ports[b]} on "
                    f"the same node {node}: a flow from a node into itself",
                    where=where, hint="connect them to different nodes, or remove the element")


class Circuit:
    """A pneumatic circuit; see the module docstring for an example."""

    def __init__(self, title: str = "", options: SimulationOptions | None = None, **option_values):
        self.title = title
        self.options = (options or SimulationOptions()).replace(**option_values) \
            if option_values else (options or SimulationOptions())
        self.elements: dict[str, ElementSpec] = {}
        self.initial: dict[str, float] = {}

    def __repr__(self) -> str:
        return (f"<Circuit {self.title!r}: {len(self.nodes)} nodes, {len(self.elements)} "
                "elements; .summary(), .tran(t_stop), .op()>")

    # -- building ---------------------------------------------------------------
    def add(self, kind: str, name: str, nodes, *, span: SourceSpan | None = None,
            **params) -> ElementSpec:
        """Add an element of a registered kind; parameters are checked and converted."""
        family = elements.family(kind)
        shown = repr(name) if _NOT_IN_NAME.search(name) else name
        where = f"{span}: element {shown}" if span else f"element {shown}"
        if not name:
            raise ParameterError("an element needs a name", where=str(span) if span else None)
        _check_name(name, "element name", where)
        if name in self.elements:
            first = self.elements[name].span
            raise TopologyError(f"duplicate element name {name!r}", where=where,
                                hint=f"first defined at {first}" if first else "names must be unique")
        fluid = "gas" if self.options.liquid is None else "liquid"
        if fluid not in family.fluids:
            fitting = [k for k in elements.known_kinds() if fluid in elements.family(k).fluids]
            raise ParameterError(
                f"{family.kind} is a {' or '.join(family.fluids)} element; this circuit's fluid is "
                f"{self.options.fluid}", where=where,
                hint=f"{fluid} circuits: " + ", ".join(fitting)
                     + ("" if fluid == "liquid" else "; liquids need .options fluid=water"))
        nodes = tuple(str(n) for n in nodes)
        if len(nodes) != len(family.ports):
            raise TopologyError(
                f"{family.kind} needs {len(family.ports)} node(s) ({' '.join(family.ports)}), "
                f"got {len(nodes)}", where=where)
        for node in nodes:
            _check_name(node, "node name", where)
        _check_distinct(family, nodes, where)
        values = self._convert_params(family, params, where)
        spec = ElementSpec(family.kind, name, nodes, values, span)
        family.check_spec(spec)
        parts = family.expand(spec)
        taken = [p.name for p in parts if p.name != name and p.name in self.elements]
        if taken:
            raise TopologyError(f"{name}'s part {taken[0]!r} takes the name of an element",
                                where=where, hint=f"first defined at {self.elements[taken[0]].span}")
        self.elements.update((part.name, part) for part in parts)
        return spec

    def _convert_params(self, family, params, where) -> dict[str, Any]:
        unknown = [k for k in params if k not in family.params]
        if unknown:
            close = difflib.get_close_matches(unknown[0], family.params, n=1)
            raise ParameterError(
                f"unknown parameter {unknown[0]!r} for {family.kind}", where=where,
                hint=f"did you mean {close[0]!r}?" if close else
                "known: " + ", ".join(family.params))
        out = {}
        for key, spec in family.params.items():
            if key not in params or params[key] is None:
                if spec.required:
                    raise ParameterError(f"missing parameter {key} ({spec.doc})", where=where)
                out[key] = spec.default
                continue
            value = params[key]
            if spec.kind == "object":
                out[key] = value
            elif spec.kind == "table" and isinstance(value, (str, os.PathLike)):
                from ..physics.tables import read_table

                out[key] = read_table(value, family.table_slots, strict=None,
                                      ambient_kpa=self.options.ambient,
                                      gas=self.options.volume_flow_fluid)
            elif spec.kind == "table":
                out[key] = value
            elif spec.kind == "waveform" and (isinstance(value, Waveform) or callable(value)):
                out[key] = as_waveform(value)
            else:
                number = self._number(value, spec.slot, f"{key}", where)
                spec.check(number, where, key)
                out[key] = as_waveform(number) if spec.kind == "waveform" else number
        return out

    def _number(self, value, slot, name, where) -> float:
        if isinstance(value, str):
            try:
                q = split_quantity(value)
                return float(to_internal(q.magnitude, q.unit, slot, gauge=q.gauge,
                                         ambient_kpa=self.options.ambient,
                                         gas=self.options.volume_flow_fluid, name=name))
            except ParameterError as err:
                raise ParameterError(err.message, where=where, hint=err.hint) from None
        try:
            return float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be a number, got {value!r}", where=where) from None

    # -- convenience constructors (one per built-in family) -------------------------
    def pressure_source(self, name, node, value, **kw):
        """Absolute pressure (kPa, a :mod:`~pneunet.physics.waveforms` waveform or a function of
        time t in s returning kPa) at ``node``."""
        return self.add("pressure_source", name, (node,), value=value, **kw)

    def flow_source(self, name, a, b, value, **kw):
        """Mass flow (mg/s, ``"40L/min"`` in normal litres at 0 °C and 101.325 kPa, a
        waveform or a function of time returning mg/s) from node ``a`` to node ``b``."""
        return self.add("flow_source", name, (a, b), value=value, **kw)

    def resistor(self, name, a, b, R, **kw):
        """Quadrature resistor of resistance ``R`` (kPa·s/mg)."""
        return self.add("resistor", name, (a, b), R=R, **kw)

    def pipe(self, name, a, b, length, diameter, f=None, **kw):
        """Tube resistor from length and diameter (mm) and Fanning friction factor."""
        return self.add("pipe", name, (a, b), length=length, diameter=diameter, f=f, **kw)

    def tube(self, name, a, b, length, diameter, segments=None, f=None, roughness=None,
             volume=None, **kw):
        """Gas or liquid line with its own volume: ``length`` and inner ``diameter`` (mm) in
        ``segments`` lumped segments (default from L/D); Fanning ``f`` (default: laminar
        blended with turbulent flow: Blasius, or Haaland with wall ``roughness`` in mm and
        in a liquid circuit); ``volume`` (mL) replaces the bore's, 0: none."""
        return self.add("tube", name, (a, b), length=length, diameter=diameter,
                        segments=segments, f=f, roughness=roughness, volume=volume, **kw)

    def volume(self, name, node, V, n=None, p0=None, **kw):
        """Rigid volume ``V`` (mL), polytropic exponent ``n``, initial pressure ``p0``."""
        return self.add("volume", name, (node,), V=V, n=n, p0=p0, **kw)

    def actuator(self, name, node, V=None, length=None, diameter=None, p0=None, **kw):
        """McKibben actuator as a volume: ``V`` (mL) or cylinder ``length`` × ``diameter`` (mm)."""
        return self.add("actuator", name, (node,), V=V, length=length, diameter=diameter,
                        p0=p0, **kw)

    def valve(self, name, inlet, outlet, ctrl, model, backward=None, **kw):
        """Membrane valve; ``model`` is a ValveParams, a paper valve name or a flow model."""
        return self.add("valve", name, (inlet, outlet, ctrl), model=model, backward=backward, **kw)

    def check_valve(self, name, a, b, R, pcrack=None, width=None, Rleak=None, **kw):
        """Check valve a→b: open resistance ``R``, cracking pressure ``pcrack`` and opening
        range ``width`` (kPa), leak resistance ``Rleak`` when closed (default: none)."""
        return self.add("check_valve", name, (a, b), R=R, pcrack=pcrack, width=width,
                        Rleak=Rleak, **kw)

    def hysteretic_check_valve(self, name, a, b, state, R, pcrack, preseat, width=None,
                               Rleak=None, tau=None, **kw):
        """Check valve a→b cracking at ``pcrack`` and reseating at ``preseat`` (kPa); its
        open fraction relaxes with time constant ``tau`` (s) at the internal node ``state``."""
        return self.add("hysteretic_check_valve", name, (a, b, state), R=R, pcrack=pcrack,
                        preseat=preseat, width=width, Rleak=Rleak, tau=tau, **kw)

    def accumulator(self, name, node, V0, k, pref=None, p0=None, **kw):
        """Elastic volume V = V0 + k·(p − pref): ``V0`` (mL) at ``pref`` (kPa, default
        ambient), compliance ``k`` (mL/kPa), initial pressure ``p0``."""
        return self.add("accumulator", name, (node,), V0=V0, k=k, pref=pref, p0=p0, **kw)

    def pv_volume(self, name, node, table, p0=None, V0=None, **kw):
        """Elastic volume from a pressure–volume ``table``: (p kPa, V mL) arrays or a CSV file
        (columns ``p_<unit>,V_<unit>``), interpolated by a monotone cubic (PCHIP).  Pressures
        not monotone (V increasing): p(V), the volume a state starting at ``V0`` (mL;
        default the smallest volume at ``p0``)."""
        return self.add("pv_volume", name, (node,), table=table, p0=p0, V0=V0, **kw)

    def orifice(self, name, a, b, diameter, Cd=None, K=None, **kw):
        """Liquid orifice of ``diameter`` (mm), discharge coefficient ``Cd`` (default 0.61)
        or minor-loss factor ``K`` (Cd = 1/√K)."""
        return self.add("orifice", name, (a, b), diameter=diameter, Cd=Cd, K=K, **kw)

    def laminar_tube(self, name, a, b, length, diameter, **kw):
        """Liquid tube in laminar flow: ``length`` and inner ``diameter`` in mm."""
        return self.add("laminar_tube", name, (a, b), length=length, diameter=diameter, **kw)

    def set_initial(self, node: str, pressure) -> None:
        """Initial pressure of a node (netlist ``.ic``), kPa or a string with unit."""
        _check_name(str(node), "node name", f"node {node!r}")
        self.initial[node] = self._number(pressure, "pressure", f"initial pressure of {node}",
                                          f"node {node}")

    def subcircuit(self, element_names, nodes, title: str | None = None) -> "Circuit":
        """A circuit of its own made of the elements ``element_names`` (their specs
        shared, same options), with the ``.ic`` values of ``nodes``."""
        sub = Circuit(self.title if title is None else title, self.options)
        for name in element_names:
            sub.elements[name] = self.elements[name]
        nodes = set(nodes)
        sub.initial.update({n: v for n, v in self.initial.items() if n in nodes})
        return sub

    # -- inspection ---------------------------------------------------------------
    @property
    def nodes(self) -> list[str]:
        seen = dict.fromkeys(n for e in self.elements.values() for n in e.nodes)
        return list(seen)

    def is_reference(self, node: str) -> bool:
        return node.lower() in REFERENCE_NODES

    def graph(self):
        """networkx MultiGraph: nodes are circuit nodes, edges join an element's ports."""
        import networkx as nx

        g = nx.MultiGraph()
        g.add_nodes_from(self.nodes)
        for e in self.elements.values():
            for i in range(len(e.nodes)):
                for j in range(i + 1, len(e.nodes)):
                    g.add_edge(e.nodes[i], e.nodes[j], element=e.name)
        return g

    def validate(self) -> None:
        """Raise :class:`TopologyError` for a circuit that cannot be simulated."""
        from ..common.gcpause import collector_paused
        from .topology import check_topology

        with collector_paused():
            check_topology(self)

    def summary(self) -> str:
        """A short human-readable description of nodes and elements."""
        kinds: dict[str, int] = {}
        for e in self.elements.values():
            kinds[e.kind] = kinds.get(e.kind, 0) + 1
        lines = [f"circuit {self.title!r}: {len(self.nodes)} nodes, {len(self.elements)} elements"]
        lines += [f"  {k}: {v}" for k, v in sorted(kinds.items())]
        lines.append("  nodes: " + " ".join(self.nodes))
        return "\n".join(lines)

    def draw(self, path=None, *, results=None):
        """The schematic (:func:`pneunet.interfaces.schematic.draw`), written to ``path`` (.svg, .png,
        .pdf) if given; ``results``: an operating point or ``(solution, t)`` to annotate."""
        from ..common.views import view

        return view("schematic")(self, path, results=results)

    def _repr_svg_(self) -> str:
        """Jupyter shows a circuit as its schematic."""
        return self.draw().svg

    # -- analyses -------------------------------------------------------------------
    def tran(self, t_stop: float, **kwargs):
        """Transient analysis; see :func:`pneunet.engine.simulate.transient`.  Times are
        seconds or strings with a unit (``"30s"``, ``t_step="10ms"``)."""
        from .simulate import transient

        for key in ("t_step", "t_start"):
            if kwargs.get(key) is not None:
                kwargs[key] = self._number(kwargs[key], "time", key, None)
        return transient(self, self._number(t_stop, "time", "t_stop", None), **kwargs)

    def op(self, **kwargs):
        """Operating point; see :func:`pneunet.engine.simulate.operating_point`."""
        from .simulate import operating_point

        if "t" in kwargs:
            kwargs["t"] = self._number(kwargs["t"], "time", "t", None)
        return operating_point(self, **kwargs)
