"""A circuit at a parameter point: a netlist re-elaborated with ``.param`` overrides and
element parameters set (``X1.pclose``), or a user's Python builder checked.  Used by
sweeps, fits of recordings and the design search alike.
"""
from __future__ import annotations

from ..common.errors import ParameterError, PneunetError


def require_builder(build, caller: str) -> None:
    """A PneunetError unless ``build`` is a function from a point to a Circuit."""
    if callable(build):
        return
    from ..engine.circuit import Circuit

    got = "a Circuit" if isinstance(build, Circuit) else f"a {type(build).__name__}"
    raise PneunetError(
        f"{caller} takes a function from a point (a dict of parameter values) to a new "
        f"Circuit, got {got}",
        hint="for a netlist pass NetlistBuilder('file.pn'); in Python a function "
             "build(point) that returns a new Circuit, e.g. pneunet.design.circuits.inverter")


def apply_overrides(circuit, point: dict):
    """Set ``ELEMENT.PARAM`` entries of ``point`` on ``circuit`` (in place; returns it)."""
    import dataclasses

    from ..physics.valve_params import ValveParams

    for key, value in point.items():
        if "." not in key:
            continue
        name, param = key.rsplit(".", 1)  # element names of subcircuits contain dots
        if name not in circuit.elements:
            raise ParameterError(f"parameter {key}: no element {name!r}",
                                 hint=name_hint(name, circuit.elements, "elements"))
        spec = circuit.elements[name]
        model = spec.params.get("model")
        if param not in spec.params and isinstance(model, ValveParams) and hasattr(model, param):
            spec.params["model"] = dataclasses.replace(model, **{param: float(value)})
        elif param in spec.params:
            old = spec.params[param]
            if hasattr(old, "level") or (param == "value" and spec.kind.endswith("source")):
                from ..physics.waveforms import as_waveform

                spec.params[param] = as_waveform(float(value))
            else:
                spec.params[param] = float(value)
        else:
            known = list(spec.params)
            if isinstance(model, ValveParams):
                known += [f.name for f in dataclasses.fields(model)]
            raise ParameterError(f"parameter {key}: {name} has no parameter {param!r}",
                                 hint=name_hint(param, known, "parameters"))
    return circuit


def name_hint(name, known, what) -> str:
    import difflib

    close = difflib.get_close_matches(name, list(known), n=1)
    return f"did you mean {close[0]!r}?" if close else f"{what}: " + ", ".join(known)


class NetlistBuilder:
    """``build(point)`` for a netlist: plain names override ``.param`` values, dotted
    names set element parameters.  The file (and its includes) is read and parsed once
    per builder and process (:func:`pneunet.netlist.load_file`), elaborated per point:
    a fit's trial points cost no parsing."""

    def __init__(self, path, parse: dict | None = None, **options):
        self.path = str(path)
        self.parse = dict(parse or {})  # parse_file's limits and include_path
        self.options = options
        self._source = None

    def __getstate__(self):  # workers parse for themselves
        return {**self.__dict__, "_source": None}

    def __call__(self, point: dict):
        from . import elaborate_source, load_file

        if self._source is None:
            self._source = load_file(self.path, **self.parse)
        deck = elaborate_source(self._source,
                                {k: v for k, v in point.items() if "." not in k})
        circuit = apply_overrides(deck.circuit, point)
        if self.options:
            circuit.options = circuit.options.replace(**self.options)
        return circuit

    def deck(self, point: dict | None = None):
        from . import parse_file

        return parse_file(self.path, overrides={k: v for k, v in (point or {}).items()
                                                if "." not in k}, **self.parse)

    def __repr__(self):
        return f"NetlistBuilder({self.path!r})"
