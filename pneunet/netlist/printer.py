"""Write a Circuit (or a Deck) back as netlist text that parses to the same circuit.

Numbers are written in internal units with full precision (``repr``), so a round
trip is exact.  Elements whose name does not start with their kind's letter are
written in keyword form (``resistor X1.R1 a b R=0.5``).
"""
from __future__ import annotations

import math
from dataclasses import fields

from ..physics import elements
from ..common.errors import printable
from ..engine.options import SimulationOptions
from ..physics.valve_params import PAPER_VALVES, ValveParams
from ..physics.waveforms import Waveform

_PREFERRED = ("axi_0p6mm", "mirror", "mirror_backward")


def _num(x) -> str:
    x = float(x)
    if x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    try:
        return bool(a == b)
    except Exception:  # noqa: BLE001
        return False


def waveform_text(w: Waveform) -> str:
    from ..physics import waveforms as wf

    if isinstance(w, wf.Constant):
        return _num(w.level)
    if isinstance(w, wf.PiecewiseLinear):
        return "PWL(" + " ".join(f"{_num(a)} {_num(b)}" for a, b in zip(w.times, w.values)) + ")"
    name = {wf.Step: "STEP", wf.Pulse: "PULSE", wf.Sine: "SIN"}.get(type(w))
    if name is None:
        return w.netlist()
    vals = [getattr(w, f.name) for f in fields(w)]
    if name == "PULSE" and not math.isfinite(w.width):
        vals = vals[:5]
    return f"{name}(" + " ".join(_num(v) for v in vals) + ")"


def _letter(kind: str) -> str | None:
    fam = elements.family(kind)
    letters = [a for a in fam.aliases if len(a) == 1]
    return letters[0].lower() if letters else None


def _fluid_card(fluid) -> str:
    """The ``.fluid`` line of a user's liquid or gas (pneunet.netlist.fluid_cards)."""
    if hasattr(fluid, "bulk_modulus"):
        return (f".fluid {fluid.name} rho={_num(fluid.density)}kg/m^3 "
                f"mu={_num(fluid.viscosity)}Pa*s K={_num(fluid.bulk_modulus)}kPa")
    card = f".fluid {fluid.name} M={_num(fluid.molar_mass_g_mol)}g/mol"
    if not math.isnan(fluid.mu0):
        card += f" mu={_num(fluid.mu0)}Pa*s T0={_num(fluid.t0)}K"
    if not math.isnan(fluid.sutherland):
        card += f" S={_num(fluid.sutherland)}K"
    return card + (f" gamma={_num(fluid.gamma)}" if fluid.gamma != 1.4 else "")


def print_circuit(circuit, *, header: bool = True) -> str:
    """Netlist text (options, models, elements, .ic) for ``circuit``."""
    lines = []
    if header:
        # a title's every line a comment, its control characters escaped: never a statement
        lines += [f"* {printable(t)}" for t in circuit.title.splitlines()] or \
            ["* pneunet circuit"]
    defaults = SimulationOptions()
    lines += [_fluid_card(fluid) for fluid in circuit.options.fluids]
    opts = [f"{f.name}={getattr(circuit.options, f.name)}" if f.name in ("gas", "fluid") else
            f"{f.name}={_num(getattr(circuit.options, f.name))}"
            for f in fields(circuit.options) if f.name != "fluids"
            and not _same(getattr(circuit.options, f.name), getattr(defaults, f.name))]
    if opts:
        lines.append(".options " + " ".join(opts))
    models: dict[int, str] = {}
    cards = []

    def model_name(model):
        if isinstance(model, ValveParams):
            for key in _PREFERRED:
                if model == PAPER_VALVES[key]:
                    return key
        if id(model) in models:
            return models[id(model)]
        for other_id, name in models.items():
            pass
        name = f"valve{len(models) + 1}"
        models[id(model)] = name
        if isinstance(model, ValveParams):
            params = model.as_dict()
        elif hasattr(model, "card_params"):
            params = model.card_params()
        else:
            from ..common.errors import NetlistError

            raise NetlistError(f"cannot write valve model {model!r} as a .model card")
        cards.append(f".model {name} VALVE(" + " ".join(f"{k}={_num(v)}" for k, v in params.items()) + ")")
        return name

    body = []
    for spec in circuit.elements.values():
        fam = elements.family(spec.kind)
        letter = _letter(spec.kind)
        head = spec.name if letter and spec.name[0].lower() == letter and \
            not (letter == "x" and False) else f"{spec.kind} {spec.name}"
        parts = [head, *spec.nodes]
        for key, p in fam.params.items():
            value = spec.params.get(key)
            if _same(value, p.default) or value is None or value is False:
                continue
            if p.kind == "object":
                parts.append(f"{key}={model_name(value)}")
            elif p.kind == "table":
                parts.append(f"{key}=TABLE(" + " ".join(f"{_num(a)} {_num(b)}"
                                                        for a, b in zip(*value)) + ")")
            elif isinstance(value, Waveform):
                parts.append(f"{key}={waveform_text(value)}")
            else:
                parts.append(f"{key}={_num(value)}")
        body.append(" ".join(parts))
    lines += cards + body
    for node, p in circuit.initial.items():
        lines.append(f".ic {node}={_num(p)}")
    return "\n".join(lines) + "\n"


def print_deck(deck) -> str:
    """The deck's circuit plus its analyses and measurements (as written)."""
    out = [print_circuit(deck.circuit).rstrip("\n")]
    for a in deck.analyses:
        if a.kind == "tran":
            out.append(".tran " + (f"{_num(a.t_step)} " if a.t_step else "") + _num(a.t_stop)
                       + (f" {_num(a.t_start)}" if a.t_start else ""))
        elif a.kind == "op":
            out.append(".op")
        elif a.kind == "dc":
            out.append(f".dc {a.source} list " + " ".join(_num(v) for v in a.values))
    for s in deck.steps:
        out.append(f".step param {s.param} list " + " ".join(_num(v) for v in s.values))
    if deck.saves:
        out.append(".save " + " ".join(str(s) for s in deck.saves))
    for m in deck.measures:
        out.append(m.text)
    return "\n".join(out) + "\n"
