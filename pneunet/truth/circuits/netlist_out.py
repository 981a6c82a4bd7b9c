"""The corrected circuit as a netlist: a trace fit's values and effects written back.

:func:`corrected_netlist` writes the user's own netlist with the fitted values in their
``.param`` lines, then every other difference between that netlist and the circuit the
fit simulated (:meth:`~pneunet.truth.circuits.model.TraceModel.circuit`: ``ELEMENT.PARAM`` values,
the elements the accepted effects add or re-route, the start state's ``.ic`` and the
fit's solver tolerances) edited into the element lines or appended, each effect under a
comment naming it, its parameters with their 95 % intervals and the recording.  The text
is parsed back and compared with the fitted circuit element by element; when an edit
cannot be made in place (an element inside a subcircuit or an included file) the whole
circuit is written out instead (:func:`~pneunet.netlist.printer.print_circuit`) and a
comment says why.  A circuit built in Python (no netlist file) is always written out.
"""
from __future__ import annotations

import copy
import math
from pathlib import Path

from ...physics import elements
from ...common.errors import PneunetError

#: units of effect parameters (by name before '@') and of the start's p0@NODE, for comments
UNITS = {"V_dead": "mL", "R_tube": "kPa·s/mg", "V_tube": "mL", "tau": "s", "n": "",
         "p0": "kPa"}


def corrected_netlist(model, values: dict, *, ci: dict | None = None, recording: str = "",
                      times=None, verdict: str | None = None, caveat: str = "") -> str:
    """Netlist text of ``model`` (a :class:`~pneunet.truth.circuits.model.TraceModel`) at ``values``.

    ``ci`` {name: (low, high)} the 95 % intervals for the comments; ``recording`` its
    name; ``times`` the recording's times (s from its first sample) for the ``.tran``
    that covers it; ``verdict`` of a diagnosis, for the header; ``caveat`` a note on
    the values (parameters the recording does not determine separately)."""
    from ...netlist.builder import NetlistBuilder

    target = model.circuit(values)
    notes = _header(model, values, ci or {}, recording, verdict)
    if caveat:
        notes.append(f"* caution: {caveat}")
    if isinstance(model.build, NetlistBuilder) and not model.build.options:
        try:
            return _edited(model, values, target, notes, times)
        except _CannotEdit as why:
            notes.append(f"* written out element by element: {why}")
    return _printed(model, target, notes, times)


class _CannotEdit(Exception):
    """An edit the writer cannot make in the user's text."""


def circuit_differences(a, b, rel: float = 1e-12) -> list[str]:
    """What differs between circuits ``a`` and ``b`` (elements, parameters, nodes,
    initial pressures, options); empty when they simulate alike."""
    out = []
    for name in sorted(set(a.elements) | set(b.elements)):
        if name not in a.elements or name not in b.elements:
            out.append(f"element {name} only in the {'second' if name in b.elements else 'first'}")
            continue
        x, y = a.elements[name], b.elements[name]
        if x.kind != y.kind or tuple(x.nodes) != tuple(y.nodes):
            out.append(f"{name}: {x.kind} {x.nodes} against {y.kind} {y.nodes}")
        for key in set(x.params) | set(y.params):
            if not _same_value(x.params.get(key), y.params.get(key), rel):
                out.append(f"{name}.{key}: {x.params.get(key)!r} against {y.params.get(key)!r}")
    for node in set(a.initial) | set(b.initial):
        if not _same_value(a.initial.get(node), b.initial.get(node), rel):
            out.append(f".ic {node}: {a.initial.get(node)} against {b.initial.get(node)}")
    if a.options != b.options:
        out.append(f"options: {a.options} against {b.options}")
    return out


def _same_value(u, v, rel) -> bool:
    if isinstance(u, float) and isinstance(v, float):
        return (math.isnan(u) and math.isnan(v)) or math.isclose(u, v, rel_tol=rel)
    if hasattr(u, "card_params") or hasattr(v, "card_params"):
        cu = u.card_params() if hasattr(u, "card_params") else getattr(u, "as_dict", dict)()
        cv = v.card_params() if hasattr(v, "card_params") else getattr(v, "as_dict", dict)()
        return cu.keys() == cv.keys() and all(math.isclose(cu[k], cv[k], rel_tol=rel) for k in cu)
    try:
        return bool(u == v)
    except (ValueError, TypeError):
        import numpy as np

        return all(np.array_equal(p, q) for p, q in zip(u, v)) and len(u) == len(v)


# -- comments --------------------------------------------------------------------------
def _value_text(name, value, ci) -> str:
    unit = UNITS.get(name.split("@")[0] if "@" in name else name, "")
    unit = f" {unit}" if unit else ""
    lo, hi = ci.get(name, (float("nan"), float("nan")))
    interval = f" [{_g(lo)}, {_g(hi)}]" if name in ci else ""
    return f"{name} = {value:.5g}{unit}{interval}"


def _g(x) -> str:
    return f"{x:.4g}" if x is not None and math.isfinite(x) else "unbounded"


def _header(model, values, ci, recording, verdict) -> list[str]:
    effect_params = {k for e in model.effects for k in e.params}
    own = [k for k in values if k not in effect_params and not k.startswith("p0@")]
    lines = [f"* corrected by pneunet fit-trace to the recording {recording or '(unnamed)'}"]
    if verdict:
        lines.append(f"* diagnosis: {verdict}")
    if own:
        lines.append("* fitted values (95 % CI): " + "; ".join(_value_text(k, values[k], ci)
                                                              for k in own))
    for eff in model.effects:
        lines += _effect_comment(eff, values, ci, recording)
    state = model.state
    if state is not None:
        lines.append(f"* start: {state.describe()}")
        fitted = [k for k in values if k.startswith("p0@")]
        if fitted:
            lines.append("* fitted initial pressures: " + "; ".join(
                _value_text(k, values[k], ci) for k in fitted))
        if state.first_time:
            lines.append(f"* the recording's time t is netlist time t + {state.first_time:g} s")
    return lines


def _effect_comment(eff, values, ci, recording) -> list[str]:
    params = "; ".join(_value_text(k, values.get(k, eff.params[k][0]), ci) for k in eff.params)
    return [f"* effect {eff.name} ({eff.family}: {eff.form})",
            f"*   {params} (95 % CI), fitted to {recording or 'the recording'}"]


# -- the netlist edited in place --------------------------------------------------------
def _edited(model, values, target, notes, times) -> str:
    from ...netlist import parse_netlist
    from ...netlist.syntax import parse_text

    build = model.build
    path = Path(build.path)
    text = path.read_text(encoding="utf-8").replace("\t", " ").replace("\r\n", "\n")
    lines = text.split("\n")
    statements = [st for st in parse_text(text, str(path), path).statements]
    top = _top_level(statements)
    # 1. plain names: the .param lines
    point = {**model.fixed, **{k: v for k, v in values.items() if not model._effect_param(k)}}
    edits = _param_edits(top, {k: v for k, v in point.items() if "." not in k})
    lines = _apply(lines, edits)
    text1 = "\n".join(lines)
    deck = parse_netlist(text1, str(path), **_parse_args(build))
    # 2. every other difference, element by element
    top = _top_level(parse_text(text1, str(path), path).statements)
    owned = _attribution(model, values)
    edits, appended = _element_edits(top, lines, deck.circuit, target, owned)
    out = _apply(lines, edits)
    out += _tail(model, deck, target, appended, times, owned, values)
    lead = next((k for k, line in enumerate(out) if not line.lstrip().startswith("*")), len(out))
    result = "\n".join(out[:lead] + notes + out[lead:]).rstrip("\n") + "\n"
    back = parse_netlist(result, str(path), **_parse_args(build))
    diff = circuit_differences(back.circuit, target)
    if diff:
        raise _CannotEdit("; ".join(diff[:3]))
    return result


def _parse_args(build) -> dict:
    return {k: v for k, v in build.parse.items() if k in ("limits", "include_path")}


def _top_level(statements) -> list:
    """The statements outside ``.subckt`` blocks."""
    out, depth = [], 0
    for st in statements:
        kw = st.keyword if st.is_directive else ""
        if kw == ".subckt":
            depth += 1
        elif kw == ".ends":
            depth = max(depth - 1, 0)
        elif depth == 0:
            out.append(st)
    return out


def _extent(item, lines) -> tuple[int, int, int]:
    """(line index, first column, column after the end) of a one-line item (0-based)."""
    from ...netlist.syntax import Call, Group, Pair, Str

    row, col = item.span.line - 1, item.span.column - 1
    if isinstance(item, Pair):
        _, _, end = _extent(item.value, lines)
        return row, col, end
    if isinstance(item, Str):
        return row, col, col + len(item.text) + 2
    if isinstance(item, (Call, Group)):
        line, depth = lines[row], 0
        for k in range(col, len(line)):
            depth += {"(": 1, ")": -1}.get(line[k], 0)
            if line[k] == ")" and depth == 0:
                return row, col, k + 1
        raise _CannotEdit(f"{item} spans several lines")
    return row, col, col + len(item.text)


def _apply(lines, edits) -> list[str]:
    """``lines`` with ``edits`` [(row, start, end, text)] made (right to left per line)."""
    out = list(lines)
    for row, start, end, new in sorted(edits, key=lambda e: (e[0], -e[1])):
        out[row] = out[row][:start] + new + out[row][end:]
    return out


def _param_edits(top, point) -> list:
    from ...netlist.syntax import Pair, Word

    edits = []
    for st in top:
        if st.keyword != ".param":
            continue
        for it in st.items[1:]:
            if isinstance(it, Pair) and isinstance(it.key, Word) and it.key.text in point:
                if not isinstance(it.value, Word):
                    raise _CannotEdit(f".param {it.key.text}: not a plain value")
                row, col = it.value.span.line - 1, it.value.span.column - 1
                edits.append((row, col, col + len(it.value.text), _num(point[it.key.text])))
    return edits


def _num(x) -> str:
    from ...netlist.printer import _num as num

    return num(x)


def _attribution(model, values) -> dict:
    """{element name: effect} of the elements each effect adds or changes (applied in
    turn to the netlist's circuit, as the fit does)."""
    c = model.base_circuit(values)
    owned = {}
    for eff in model.effects:
        before = copy.deepcopy(c.elements)
        eff.apply(c, {k: values.get(k, eff.params[k][0]) for k in eff.params})
        for name, spec in c.elements.items():
            old = before.get(name)
            if old is None or old.kind != spec.kind or old.nodes != spec.nodes or \
                    circuit_differences_spec(old, spec):
                owned.setdefault(name, eff)
    return owned


def circuit_differences_spec(a, b) -> bool:
    return any(not _same_value(a.params.get(k), b.params.get(k), 1e-12)
               for k in set(a.params) | set(b.params))


def _element_statements(top) -> dict:
    """{element name: (statement, family, name item, rest items)} of plain element lines."""
    from ...netlist.syntax import Word

    kind_words = {w.lower() for k in elements.known_kinds()
                  for w in (k, *elements.family(k).aliases) if len(w) > 1}
    out = {}
    for st in top:
        if st.is_directive or not st.items or not isinstance(st.items[0], Word):
            continue
        head, rest = st.items[0], st.items[1:]
        if rest and head.text.lower() in kind_words and isinstance(rest[0], Word):
            family, name_item, rest = elements.family(head.text.lower()), rest[0], rest[1:]
        else:
            try:
                family, name_item = elements.family(head.text[0]), head
            except PneunetError:
                continue  # a subcircuit instance
        if "{" in name_item.text or "[" in name_item.text:
            continue
        out[name_item.text] = (st, family, name_item, rest)
    return out


def _element_edits(top, lines, have, target, owned):
    """(token edits, {effect: new element lines}) that turn circuit ``have`` (the
    netlist as parsed) into ``target``."""
    from ...netlist.syntax import Pair

    found = _element_statements(top)
    edits, appended = [], {}
    for name, spec in target.elements.items():
        old = have.elements.get(name)
        if old is None:
            appended.setdefault(owned.get(name), []).append(spec)
            continue
        if old.kind == spec.kind and old.nodes == spec.nodes and \
                not circuit_differences_spec(old, spec):
            continue
        if name not in found:
            raise _CannotEdit(f"{name} is not on an element line of the netlist file")
        st, family, name_item, rest = found[name]
        eff = owned.get(name)
        why = f"* effect {eff.name}: " if eff is not None else "* fitted: "
        row = st.span.line - 1
        if old.kind != spec.kind:  # the new line goes where the fit's circuit has it
            appended.setdefault(eff, []).append(_rewrite(st, lines, spec, old, rest, family))
            edits.append((row, 0, 0, f"{why}{name} becomes a {spec.kind} (was a {old.kind}), "
                                     "written below\n* "))
            continue
        changed = [f"{port} at {b} (was {a})" for port, a, b
                   in zip(family.ports, old.nodes, spec.nodes) if a != b]
        changed += [f"{key} = {_brief(spec.params[key])} (was {_brief(old.params.get(key))})"
                    for key in family.params
                    if not _same_value(old.params.get(key), spec.params.get(key), 1e-12)]
        edits.append((row, 0, 0, f"{why}{name} {', '.join(changed)}\n"))
        positional = [it for it in rest if not isinstance(it, Pair)]
        pairs = {it.key.text.lower(): it for it in rest if isinstance(it, Pair)}
        for k, (a, b) in enumerate(zip(old.nodes, spec.nodes)):
            if a != b:
                r, c0, c1 = _extent(positional[k], lines)
                edits.append((r, c0, c1, b))
        names = list(family.params)
        extra = positional[len(family.ports):]
        last = rest[-1] if rest else name_item
        for key in family.params:
            if _same_value(old.params.get(key), spec.params.get(key), 1e-12):
                continue
            text = _param_text(spec.params[key])
            if key in names[:len(extra)]:
                r, c0, c1 = _extent(extra[names.index(key)], lines)
                edits.append((r, c0, c1, text))
            elif key.lower() in pairs:
                r, c0, c1 = _extent(pairs[key.lower()].value, lines)
                edits.append((r, c0, c1, text))
            else:
                r, _, c1 = _extent(last, lines)
                edits.append((r, c1, c1, f" {key}={text}"))
    for name in have.elements:
        if name not in target.elements:
            raise _CannotEdit(f"the fitted circuit has no element {name}")
    return edits, appended


def _brief(value) -> str:
    return f"{value:.5g}" if isinstance(value, float) else str(value)


def _rewrite(st, lines, spec, old, rest, family) -> str:
    """The line of ``spec`` (another kind than the element line ``st``) in keyword form;
    the text of values it keeps under the same name is kept."""
    from ...netlist.syntax import Pair

    first = st.items[0]
    last = rest[-1] if rest else st.items[-1]
    r0, _, _ = _extent(first, lines)
    r1, _, _ = _extent(last, lines)
    if r0 != r1:
        raise _CannotEdit(f"{spec.name} spans several lines")
    positional = [it for it in rest if not isinstance(it, Pair)]
    given = dict(zip(list(family.params), positional[len(family.ports):]))
    given.update({it.key.text: it.value for it in rest if isinstance(it, Pair)})
    new_family = elements.family(spec.kind)
    parts = [spec.kind, spec.name, *spec.nodes]
    for key, p in new_family.params.items():
        value = spec.params.get(key)
        if value is None or value is False or _same_value(value, p.default, 1e-15):
            continue
        if key in given and _same_value(old.params.get(key), value, 1e-12):
            parts.append(f"{key}={given[key]}")
        else:
            parts.append(f"{key}={_param_text(value)}")
    return " ".join(parts)


def _param_text(value) -> str:
    from ...netlist.printer import waveform_text
    from ...physics.waveforms import Waveform

    if isinstance(value, Waveform):
        return waveform_text(value)
    if hasattr(value, "card_params") or hasattr(value, "as_dict"):
        card = value.card_params() if hasattr(value, "card_params") else value.as_dict()
        return "VALVE(" + " ".join(f"{k}={_num(v)}" for k, v in card.items()) + ")"
    if isinstance(value, (int, float)):
        return _num(value)
    raise _CannotEdit(f"cannot write the value {value!r}")


def _fragment(eff, values, params) -> list[str] | None:
    """A :class:`~pneunet.truth.circuits.effects.NetlistEffect`'s own text with its ``.param``
    values fitted, or None (another effect, or its parameter names clash with the
    netlist's)."""
    import textwrap

    from ...netlist.syntax import parse_text
    from .effects import NetlistEffect

    if not isinstance(eff, NetlistEffect):
        return None
    text = textwrap.dedent(eff.fragment).strip("\n").replace("\t", " ")
    top = parse_text(text, f"<effect {eff.name}>").statements
    declared = {it.key.text for st in top if st.keyword == ".param" for it in st.items[1:]
                if hasattr(it, "key") and hasattr(it.key, "text")}
    if declared & set(params):
        return None
    point = {k: values.get(k, eff.params[k][0]) for k in eff.params}
    return _apply(text.split("\n"), _param_edits(top, point))


def _printed_elements(specs) -> list[str]:
    from ...engine.circuit import Circuit
    from ...netlist.printer import print_circuit

    c = Circuit("effect")
    for spec in specs:
        c.elements[spec.name] = copy.deepcopy(spec)
    return print_circuit(c, header=False).rstrip("\n").split("\n")


def _tail(model, deck, target, appended, times, owned, values) -> list[str]:
    """The lines appended to the netlist: new elements per effect, options, .ic, .tran."""
    out = []
    for eff, specs in appended.items():
        if eff is None:
            out += ["", "* elements of the fitted circuit"]
        else:
            out += ["", f"* effect {eff.name}" + (f": {eff.description}" if eff.description
                                                   else "")]
        fragment = _fragment(eff, values, deck.params) if eff is not None else None
        if fragment:
            out += fragment
            continue
        for spec in specs:
            out += [spec] if isinstance(spec, str) else _printed_elements([spec])
    opts = _options_line(deck.circuit.options, target.options)
    if opts:
        out += ["", "* the fit's solver settings", opts]
    ic = {n: p for n, p in target.initial.items()
          if not _same_value(deck.circuit.initial.get(n), p, 1e-12)}
    if ic:
        out += ["", "* " + _ic_comment(model)]
        out += [f".ic {n}={_num(p)}" for n, p in ic.items()]
    tran = _tran_line(model, deck.analyses, times)
    if tran:
        out += ["", "* the recording's span (the netlist's own .tran does not cover it)", tran]
    return out


def _ic_comment(model) -> str:
    state = model.state
    if state is not None and state.mode == "record":
        return ("start state read from the recording (record mode): storage at its fitted "
                "initial pressures, a branch's guess; storage an effect adds starts at its "
                "node's pressure")
    return "storage an effect adds starts at the settled pressure of its node"


def _options_line(have, want) -> str:
    from dataclasses import fields

    parts = []
    for f in fields(want):
        a, b = getattr(have, f.name), getattr(want, f.name)
        if not _same_value(a, b, 1e-15):
            parts.append(f"{f.name}={b}" if f.name in ("gas", "fluid") else
                         f"{f.name}={_num(b)}")
    return ".options " + " ".join(parts) if parts else ""


def _tran_line(model, analyses, times) -> str:
    """A ``.tran`` over the recording (from the netlist time of the start) when no
    analysis of the netlist starts there and covers it; '' otherwise."""
    if times is None or len(times) < 2:
        return ""
    import numpy as np

    state = model.state
    t0 = state.time_offset if state is not None else 0.0
    t_end = model.first_time + float(times[-1])
    for a in analyses:
        if getattr(a, "kind", "") == "tran" and math.isclose(a.t_start, t0, abs_tol=1e-12) \
                and a.t_stop >= t_end - 1e-9:
            return ""
    dt = float(f"{np.median(np.diff(times)):.6g}")
    return f".tran {_num(dt)} {_num(t_end)}" + (f" {_num(t0)}" if t0 else "")


# -- the circuit written out ------------------------------------------------------------
def _printed(model, target, notes, times) -> str:
    from ...netlist.printer import print_circuit

    body = print_circuit(target, header=False).rstrip("\n").split("\n")
    tran = _tran_line(model, [], times)
    title = f"* {target.title}" if target.title else "* pneunet circuit"
    return "\n".join([title] + notes + body + ([tran] if tran else [])) + "\n"
