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


#: sources loaded in this process by unpickled builders (a sweep's points sent to a
#: worker), by the token of the builder they copy: the file is parsed once per worker and
#: builder, not once per point; the last LOADED_KEPT builders' are kept
_LOADED: dict = {}
LOADED_KEPT = 4


class NetlistBuilder:
    """``build(point)`` for a netlist: plain names override ``.param`` values, dotted
    names set element parameters.  The file (and its includes) is read and parsed once
    per builder and process (:func:`pneunet.netlist.load_file`), elaborated per point:
    a fit's trial points and a sweep's points cost no parsing."""

    def __init__(self, path, parse: dict | None = None, **options):
        import uuid

        self.path = str(path)
        self.parse = dict(parse or {})  # parse_file's limits and include_path
        self.options = options
        self._source = None
        self._token = uuid.uuid4().hex  # the same in every pickled copy

    def __getstate__(self):  # workers parse for themselves, once (_LOADED)
        return {**self.__dict__, "_source": None, "_copy": True}

    def _loaded(self):
        from . import load_file

        if self._source is None:
            copy = self.__dict__.get("_copy", False)
            self._source = (_LOADED.get(self._token) if copy else None) or \
                load_file(self.path, **self.parse)
            if copy and self._token not in _LOADED:
                _LOADED[self._token] = self._source
                for token in list(_LOADED)[:-LOADED_KEPT]:
                    _LOADED.pop(token, None)  # (another thread may have dropped it)
        return self._source

    def __call__(self, point: dict):
        circuit = apply_overrides(self.deck(point).circuit, point)
        if self.options:
            circuit.options = circuit.options.replace(**self.options)
        return circuit

    def deck(self, point: dict | None = None):
        """The netlist's :class:`~pneunet.netlist.deck.Deck` with ``point``'s ``.param``
        values (its circuit without the dotted names set)."""
        from . import elaborate_source

        return elaborate_source(self._loaded(), {k: v for k, v in (point or {}).items()
                                                 if "." not in k})

    def __repr__(self):
        return f"NetlistBuilder({self.path!r})"
