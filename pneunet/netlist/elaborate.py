"""Statements -> Deck: parameters, options, elements, subcircuit instances and ``.ic``.

The parts of the meaning that have their own statements live beside it: ``.model`` cards
(:mod:`.models`), analyses (:mod:`.analyses`), ``.meas`` (:mod:`.measures`), the file
structure (:mod:`.structure`: includes, ``.subckt``).  Every error is a
:class:`NetlistError` with the span of the offending item (line and column), so the CLI can
draw a caret under it.
"""
from __future__ import annotations

import itertools
import math
import re

from ..physics import elements
from ..common.errors import NetlistError, PneunetError, SourceSpan
from .analyses import AnalysisStatements
from . import plausible
from .arrays import split_range
from .datafiles import inline_table, read_data_file
from .deck import Deck, Instance, Op
from ..engine.options import SimulationOptions
from .expr import Scope, evaluate
from .fluid_cards import read_fluid_cards
from .includes import KEYWORDS as INCLUDE_KEYWORDS
from .located import did_you_mean as _close, error_at as _err
from .measures import MeasureStatements
from .models import ModelCards
from .size import check_size
from .structure import Source
from .waveform_calls import WaveformCalls
from .syntax import Call, Pair, Str, Word
from .values import (SCALE, check_number, convert, convert_magnitude, dimension_of,
                     number_in_expression, set_expression_ambient, split)

REFERENCE = ("0", "gnd", "atm")
DIRECTIVES = (".param", ".subckt", ".ends", *INCLUDE_KEYWORDS, ".model", ".ic", ".options",
              ".option", ".fluid", ".tran", ".op", ".dc", ".step", ".meas", ".measure", ".save", ".print",
              ".title", ".end")

#: .options name -> (SimulationOptions field, slot)
OPTIONS = {
    "rtol": ("rtol", "dimensionless"), "reltol": ("rtol", "dimensionless"),
    "atol": ("atol", "pressure_difference"), "abstol": ("atol", "pressure_difference"),
    "ambient": ("ambient", "pressure"), "temperature": ("temperature", "temperature"),
    "temp": ("temperature", "temperature"), "gas": ("gas", None),
    "fluid": ("fluid", None), "method": ("method", None),
    "flow_band": ("flow_band", "dimensionless"), "dead_volume": ("dead_volume", "volume"),
    "max_step": ("max_step", "time"), "fold_threshold": ("fold_threshold", "dimensionless"),
}

_BRACES = re.compile(r"\{[^{}]*\}")


# -- elaboration -------------------------------------------------------------------------
def elaborate(source: Source, overrides: dict | None = None) -> Deck:
    return _Builder(source, overrides or {}).build()


class _Builder(ModelCards, AnalysisStatements, MeasureStatements, WaveformCalls):
    def __init__(self, source: Source, overrides: dict):
        self.source = source
        self.limits = source.limits
        self.kind_words = _kind_keywords()  # once per netlist, not per element
        self.overrides = dict(overrides)
        self.models: dict[str, object] = {}
        self.model_spans: dict[str, SourceSpan] = {}
        self.converted: dict[tuple[str, str], float] = {}  # (literal, slot) -> value
        self.node_set: set[str] = set()  # the nodes of the first node_count elements
        self.node_count = 0
        self.instances: list[list] = []   # [Instance, index of its first element, of its end]

    # ---- top level
    def build(self) -> Deck:
        from ..engine.circuit import Circuit

        top = self.source.top
        for st in top:
            if st.is_directive and st.keyword not in DIRECTIVES:
                raise _err(f"unknown directive {st.head!r}", st.items[0],
                           _close(st.keyword, DIRECTIVES))
        fluids = read_fluid_cards([st for st in top if st.keyword == ".fluid"],
                                  lambda word, slot, key: self._number(
                                      word, slot, key, Scope(), SimulationOptions()))
        self.options = self._options([st for st in top if st.keyword in (".options", ".option")],
                                     fluids)
        set_expression_ambient(self.options.ambient)
        self._check_overrides()
        self.scope = Scope(dict(self.overrides))
        for st in top:
            if st.keyword == ".param":
                self._param(st, self.scope, self.overrides)
        for st in top:
            if st.keyword == ".model":
                self._model(st, self.scope)
        for sub in self.source.subckts.values():
            for st in sub.body:
                if st.keyword == ".model":
                    self._model(st, self.scope)
        self.circuit = Circuit(self.source.title, options=self.options)
        check_size(self.source, self.kind_words, self.limits)
        self._body(top, self.scope, "", {}, [])
        if not self.circuit.elements:
            last = self.source.top[-1].span if self.source.top else \
                SourceSpan(self.source.file, 1, 1)
            raise _err(f"{self.source.file} has no elements" + (" (the file is empty)" if not
                       self.source.top else ""), last,
                       "write one element per line, e.g. 'P1 supply 400kPa' (docs/netlist.md)")
        deck = Deck(self.circuit, title=self.source.title, file=self.source.file,
                    params=dict(self.scope.values), overrides=dict(self.overrides),
                    source=self.source, instances=self._instances(), elaborator=elaborate)
        for st in top:
            kw = st.keyword
            if kw == ".tran":
                deck.analyses.append(self._tran(st))
            elif kw == ".op":
                if len(st.items) > 1:
                    raise _err(".op takes no arguments", st.items[1])
                deck.analyses.append(Op(st.span))
            elif kw == ".dc":
                deck.analyses.append(self._dc(st))
            elif kw == ".step":
                deck.steps.append(self._step(st))
            elif kw in (".meas", ".measure"):
                m = self._meas(st, deck.measures)
                if any(x.name.lower() == m.name.lower() for x in deck.measures):
                    raise _err(f"duplicate measurement name {m.name!r}", st.items[2]
                               if len(st.items) > 2 else st.span)
                deck.measures.append(m)
            elif kw in (".save", ".print"):
                deck.saves.extend(self._saves(st))
        names = [s.param for s in deck.steps]
        for i, n in enumerate(names):
            if n in names[:i]:
                raise _err(f"parameter {n!r} is stepped twice", deck.steps[i].span)
        if math.prod(len(s.values) for s in deck.steps) > self.limits.max_sweep_points:
            raise _err(f"the .step lines make {math.prod(len(s.values) for s in deck.steps)} "
                       f"points ({self.limits.exceeded('max_sweep_points')})",
                       deck.steps[-1].span, self.limits.hint("max_sweep_points"))
        return deck

    def declared_params(self) -> list:
        """The names the top level's ``.param`` lines define (what may be overridden)."""
        return [it.key.text for st in self.source.top if st.keyword == ".param"
                for it in st.items[1:] if isinstance(it, Pair) and isinstance(it.key, Word)]

    def _check_overrides(self):
        """Every overridden name (``--param``, ``--set``, ``.step`` values) is a ``.param``."""
        declared = self.declared_params()
        for name, value in self.overrides.items():
            if name not in declared:
                raise NetlistError(f"parameter {name!r} is not defined by a .param line",
                                   where=self.source.file, hint=_close(name, declared) or
                                   ("parameters: " + ", ".join(declared) if declared else
                                    "the netlist has no .param lines"))
            if not math.isfinite(value):
                raise NetlistError(f"parameter {name} = {value}: not a finite number",
                                   where=self.source.file)

    def _options(self, statements, fluids=()):
        values, opts = ({"fluids": fluids} if fluids else {}), SimulationOptions()
        for st in statements:
            for it in st.items[1:]:
                if not isinstance(it, Pair) or not isinstance(it.key, Word):
                    raise _err(f"{st.head} expects name=value, got {it}", it,
                               "e.g. .options ambient=96kPa rtol=1e-6")
                key = it.key.text.lower()
                if key not in OPTIONS:
                    raise _err(f"unknown option {it.key.text!r}", it.key,
                               _close(key, OPTIONS) or "known: " + ", ".join(sorted(OPTIONS)))
                field_name, slot = OPTIONS[key]
                if not isinstance(it.value, Word):
                    raise _err(f"option {key} expects a value", it.value)
                if slot is None:
                    values[field_name] = it.value.text
                    continue
                if slot == "pressure" and split(it.value.text) and \
                        split(it.value.text)[1].endswith("g") and split(it.value.text)[1] != "g":
                    raise _err("ambient must be an absolute pressure", it.value, "e.g. ambient=96kPa")
                values[field_name] = self._number(it.value, slot, key, Scope(), opts)
                plausible.check_option(key, values[field_name], it.value)
        try:
            return opts.replace(**values)
        except PneunetError as err:  # no .options line: a .fluid card's fault
            where = statements[-1].span if statements else self.source.top[0].span
            raise _err(err.message, where, err.hint) from None

    def _param(self, st, scope, fixed=()):
        if len(st.items) < 2:
            raise _err(".param needs name=value", st.span, "e.g. .param Rout={2*0.566}")
        for it in st.items[1:]:
            if not isinstance(it, Pair) or not isinstance(it.key, Word) or \
                    not isinstance(it.value, Word):
                raise _err(f".param expects name=value, got {it}", it, "e.g. .param Rout={2*0.566}")
            name = it.key.text
            if not re.fullmatch(r"[A-Za-z_][A-Za-z_0-9]*", name):
                raise _err(f"bad parameter name {name!r}", it.key,
                           "names start with a letter or '_' and contain letters, digits, '_'")
            if name in fixed:
                continue  # set by .step (or the caller)
            scope.values[name] = self._scalar(it.value, scope)

    def _scalar(self, word: Word, scope) -> float:
        """A value without a slot: expression, number with scale factor or unit, or a name."""
        if not isinstance(word, Word):
            raise _err(f"expected a number, got {word}", word,
                       "write a number, or an expression in {}")
        text = word.text
        if text.startswith("{") and text.endswith("}") and _BRACES.fullmatch(text):
            return evaluate(text[1:-1], scope, word.span, word.span.column + 1,
                            limits=self.limits)
        text = self._subst(word, scope)
        if split(text) is not None:
            return check_number(number_in_expression(text, word.span, self.options.ambient),
                                text, word.span, tiny=False)
        value = scope.lookup(text)
        if value is None:
            raise _err(f"cannot read {text!r} as a number", word,
                       _close(text, scope.names()) or "write a number, or an expression in {}")
        return value

    def _subst(self, word: Word, scope) -> str:
        """Replace each {expr} inside a word by its value."""
        if "{" not in word.text:
            return word.text

        def repl(m):
            column = word.span.column + m.start() + 1
            value = evaluate(m.group(0)[1:-1], scope, word.span, column, self.limits)
            return _fmt_int(value)
        return _BRACES.sub(repl, word.text)

    def _number(self, word, slot, name, scope, options=None) -> float:
        opts = options or self.options
        if not isinstance(word, Word):
            raise _err(f"{name} expects a number, got {word}", word)
        text = word.text
        if text.startswith("{") and text.endswith("}") and _BRACES.fullmatch(text):
            return evaluate(text[1:-1], scope, word.span, word.span.column + 1,
                            limits=self.limits)
        text = self._subst(word, scope)
        if options is None and (text, slot) in self.converted:  # an array repeats its literals
            return self.converted[text, slot]
        if split(text) is None:
            value = scope.lookup(text)
            if value is None:
                if dimension_of(text) or text.lower() in SCALE:
                    raise _err(f"{name}: unit {text!r} without a number", word,
                               "remove the space between the number and its unit: 250mL, "
                               "not 250 mL")
                raise _err(f"{name}: cannot read {text!r} as a number", word,
                           _close(text, scope.names()) or
                           "write a number with its unit, e.g. " + _example(slot))
            return value
        value = check_number(convert(text, slot, word.span, name=name, ambient=opts.ambient,
                                     gas=opts.volume_flow_fluid), text, word.span, name)
        if options is None:
            self.converted[text, slot] = value
        return value

    def _converter(self, name):
        """``convert(magnitudes, unit, slot, span)`` of a TABLE or PWL column
        (:func:`.datafiles.column`): :meth:`_number`'s conversion for many values at once."""
        return lambda m, unit, slot, span: convert_magnitude(
            m, unit, slot, span, name=name, ambient=self.options.ambient,
            gas=self.options.volume_flow_fluid)

    def has_node(self, node: str) -> bool:
        """Whether an element added so far touches ``node``; the set grows with the circuit
        (``circuit.nodes`` walks every element: once per ``.ic`` in an array was O(N²))."""
        specs = self.circuit.elements
        added = len(specs) - self.node_count
        for spec in itertools.islice(reversed(specs.values()), added):
            self.node_set.update(spec.nodes)
        self.node_count = len(specs)
        return node in self.node_set

    # ---- models
    def _fail_value(self, arg):
        raise _err(f"{arg.key} expects a number", arg.value)

    # ---- elements and subcircuits
    def _body(self, statements, scope, prefix, nodemap, stack):
        for st in statements:
            if st.is_directive:
                kw = st.keyword
                if kw == ".ic":
                    self._ic(st, scope, prefix, nodemap)
                continue
            self._element(st, scope, prefix, nodemap, stack)

    def _node(self, text, prefix, nodemap):
        if text.lower() in REFERENCE:
            return text
        if text in nodemap:
            return nodemap[text]
        return prefix + text

    def _element(self, st, scope, prefix, nodemap, stack):
        head = st.items[0]
        if not isinstance(head, Word):
            raise _err(f"a line must start with an element name or a directive, got {head}", head)
        rest = st.items[1:]
        kind_kw = head.text.lower()
        if not (len(rest) >= 1 and len(kind_kw) > 1 and kind_kw in self.kind_words):
            return self._elements(st, head, head, None, rest, scope, prefix, nodemap, stack)
        family = elements.family(kind_kw)
        if not isinstance(rest[0], Word):
            raise _err(f"{head.text} needs an element name", rest[0])
        try:
            return self._elements(st, head, rest[0], family, rest[1:], scope, prefix, nodemap,
                                  stack)
        except NetlistError as err:
            # `Vt tank 50mL`: the first word is a short kind word (VT) and an element name
            if len(kind_kw) > 3 or not _element_letter(head.text):
                raise
            try:
                return self._elements(st, head, head, None, rest, scope, prefix, nodemap, stack)
            except NetlistError:
                pass
            read = (f"the line was read as a {family.kind} (kind word {head.text!r}) named "
                    f"{rest[0].text!r}; as an element named {head.text!r} it fails too")
            raise NetlistError(err.message, span=err.span,
                               hint=f"{err.hint}; {read}" if err.hint else read) from None

    def _elements(self, st, head, name_item, family, rest, scope, prefix, nodemap, stack):
        """The element (or array of elements) named by ``name_item``."""
        name_text = self._subst(name_item, scope)
        base, indices = split_range(name_text, name_item, self.limits) or (name_text, [None])
        for idx in indices:
            sc = scope if idx is None else scope.child({"index": float(idx)})
            name = base if idx is None else f"{base}[{idx}]"
            self._one_element(st, head, name_item, name, family, rest, sc, prefix, nodemap,
                              stack, idx, indices)

    def _expand_node(self, item, scope, idx, indices):
        text = self._subst(item, scope)
        split = split_range(text, item, self.limits)
        if split is None:
            return text
        if idx is None:
            raise _err(f"node range {text!r} on an element that is not an array", item,
                       "give the element name a range too, e.g. X[1:8]")
        base, nodes = split
        if len(nodes) != len(indices):
            raise _err(f"node range {text!r} has {len(nodes)} entries, the element array "
                       f"{len(indices)}", item)
        return f"{base}[{nodes[indices.index(idx)]}]"

    def _one_element(self, st, head, name_item, name, family, rest, scope, prefix, nodemap,
                     stack, idx, indices):
        positional = [it for it in rest if not isinstance(it, Pair)]
        pairs = [it for it in rest if isinstance(it, Pair)]
        # subcircuit instance: X... whose last positional word names a subcircuit
        if family is None and name[0].lower() == "x" and positional and \
                isinstance(positional[-1], Word) and \
                positional[-1].text.lower() in self.source.subckts:
            return self._instance(st, name_item, name, positional, pairs, scope, prefix, nodemap,
                                  stack, idx, indices)
        if family is None:
            try:
                family = elements.family(name[0])
            except PneunetError:
                letters = sorted({a for k in elements.known_kinds()
                                  for a in (*elements.family(k).aliases, k) if len(a) == 1})
                raise _err(f"unknown element type {name[0]!r} of {name!r}", name_item,
                           "the first letter gives the type: " + ", ".join(letters) +
                           " (X also instantiates a .subckt); or start the line with a kind: "
                           + ", ".join(elements.known_kinds())) from None
        n_ports = len(family.ports)
        full = prefix + name
        if name[0].lower() == "x" and len(positional) > n_ports + 1 and \
                isinstance(positional[-1], Word) and family.kind == "valve":
            raise _err(f"undefined subcircuit {positional[-1].text!r}", positional[-1],
                       _close(positional[-1].text.lower(), self.source.subckts) or
                       "define it with .subckt NAME ports ... .ends")
        for it in positional[:n_ports]:
            if not isinstance(it, Word):
                raise _err(f"{family.kind} {full}: expected node name, got {it}", it)
        if len(positional) < n_ports:
            where = positional[-1] if positional else name_item
            hint = None
            if family.kind == "valve" and positional and isinstance(positional[-1], Word):
                hint = f"is {positional[-1].text!r} an undefined subcircuit?" \
                    if len(positional) == n_ports + 1 else None
            raise _err(f"{family.kind} {full} needs {n_ports} node(s) ({' '.join(family.ports)}), "
                       f"got {len(positional)}", where, hint)
        nodes = [self._node(self._expand_node(it, scope, idx, indices), prefix, nodemap)
                 for it in positional[:n_ports]]
        names = list(family.params)
        canon = {k.lower(): k for k in names}
        given: dict[str, object] = {}
        items: dict[str, object] = {}
        extra = positional[n_ports:]
        for i, it in enumerate(extra):  # `length=3 m`, `R1 a b 1 kPa*s/mg`: a unit apart
            if i < len(names) and family.params[names[i]].kind == "object":
                continue  # a model name (`X1 a b c m`)
            if isinstance(it, Word) and split(it.text) is None and "{" not in it.text and \
                    (dimension_of(it.text) or it.text.lower() in SCALE) and \
                    scope.lookup(it.text) is None:
                raise _err(f"{family.kind} {full}: unit {it.text!r} without a number", it,
                           f"remove the space between the number and its unit: 3{it.text}, "
                           f"not 3 {it.text} (also after key=)")
        if len(extra) > len(names):
            bad = extra[len(names)]
            hint = None
            if family.kind == "valve" and len(positional) > n_ports + 1:
                hint = f"a valve has {n_ports} nodes; is {positional[-1]} an undefined subcircuit?"
            raise _err(f"{family.kind} {full}: unexpected value {bad}", bad,
                       hint or f"{family.kind} takes {n_ports} nodes then "
                               + ", ".join(names) + " (in this order, or as key=value)")
        if len(extra) > 1 and isinstance(extra[0], Word) and extra[0].text.lower() in REFERENCE:
            self._node_read_as_value(family, full, names, extra)
        for key, it in zip(names, extra):
            items[key] = it
        for it in pairs:
            if not isinstance(it.key, Word):
                raise _err(f"unexpected {it.key} before '='", it.key)
            k = it.key.text
            key = k if k in family.params else canon.get(k.lower())
            if key is None:
                raise _err(f"unknown parameter {k!r} for {family.kind} {full}", it.key,
                           _close(k, names) or "known: " + ", ".join(names))
            if key in items:
                raise _err(f"parameter {key} given twice", it.key)
            items[key] = it.value
        for key, it in items.items():
            given[key] = self._param_value(family, key, it, scope, full)
        if len(self.circuit.elements) >= self.limits.max_elements:
            raise _err(f"more than {len(self.circuit.elements)} elements "
                       f"({self.limits.exceeded('max_elements')})", name_item,
                       self.limits.hint("max_elements"))
        try:
            self.circuit.add(family.kind, full, nodes, span=name_item.span, **given)
        except PneunetError as err:
            if "duplicate element name" in err.message:
                raise _err(err.message, name_item, err.hint) from None
            raise _err(f"{family.kind} {full}: {err.message}", name_item, err.hint) from None

    def _node_read_as_value(self, family, full, names, extra):
        """``V1 a 0 200kPa``: a reference node where the first value goes, then a value of
        another dimension — the element was taken for one with more nodes."""
        from ..physics.units import SLOTS, pretty

        parts = split(extra[1].text) if isinstance(extra[1], Word) else None
        got = dimension_of(parts[1]) if parts and parts[1] else None
        want = family.params[names[0]].slot
        if got is None or got == want.split("_")[0]:
            return
        hint = (f"{family.kind} {full} has {len(family.ports)} node(s) "
                f"({' '.join(family.ports)}), so {extra[0].text!r} was read as its {names[0]}")
        if family.kind == "volume" and got == "pressure":
            hint += "; V is a volume in pneunet, a pressure source is P: P1 a 200kPa"
        raise _err(f"{full} needs a {want.replace('_', ' ')} ({pretty(SLOTS[want])}), got a "
                   f"{got} ({parts[1]})", extra[1], hint)

    def _param_value(self, family, key, item, scope, full):
        spec = family.params[key]
        label = f"{full}: {key}"
        if spec.kind == "object":
            if family.kind == "valve" or key in ("model", "backward"):
                if isinstance(item, Call) and item.name.upper() == "VALVE":
                    return self._valve_card(item, scope, f"{full}.{key}")
                if not isinstance(item, Word):
                    raise _err(f"{label} expects a model name", item)
                return self._lookup_model(item)
            return item.text if isinstance(item, (Word, Str)) else str(item)
        if spec.kind == "table" and isinstance(item, Call) and item.name.upper() == "TABLE":
            return inline_table(item, family.table_slots,
                                lambda a, slot: self._number(a, slot, label, scope),
                                self._converter(label))
        if spec.kind == "table":
            return read_data_file(item, self.source.policy, family.table_slots, self.options,
                                  label, strict=None)
        if isinstance(item, Call) and spec.kind == "waveform":
            return self._waveform(item, spec.slot, scope, label)
        if isinstance(item, Call):
            raise _err(f"{label} expects a number, got {item.name}(...)", item,
                       "waveforms (STEP, PULSE, PWL, SIN) only drive sources")
        value = self._number(item, spec.slot, key, scope)
        try:
            spec.check(value, label, key)
        except PneunetError as err:
            raise _err(f"{family.kind} {full}: {err.message}", item, err.hint) from None
        plausible.check(spec, key, value, item.text, item.span, key)
        return value

    def _instance(self, st, name_item, name, positional, pairs, scope, prefix, nodemap, stack,
                  idx, indices):
        sub_word = positional[-1]
        sub = self.source.subckts[sub_word.text.lower()]
        full = prefix + name
        if sub.name.lower() in stack:
            loop = " -> ".join(stack + [sub.name.lower()])
            raise _err(f"recursive subcircuit: {loop}", sub_word,
                       "a subcircuit cannot contain an instance of itself")
        if len(stack) >= self.limits.max_subckt_depth:
            raise _err(f"subcircuits nested {len(stack) + 1} deep "
                       f"({self.limits.exceeded('max_subckt_depth')})", sub_word,
                       "flatten some levels; " + self.limits.hint("max_subckt_depth"))
        nodes = positional[:-1]
        if len(nodes) != len(sub.ports):
            raise _err(f"subcircuit {sub.name} has {len(sub.ports)} port(s) "
                       f"({' '.join(sub.ports)}), instance {full} gives {len(nodes)}", sub_word)
        for it in nodes:
            if not isinstance(it, Word):
                raise _err(f"expected node name, got {it}", it)
        actual = {port: self._node(self._expand_node(it, scope, idx, indices), prefix, nodemap)
                  for port, it in zip(sub.ports, nodes)}
        # parameters: global scope <- defaults <- instance values <- local .param
        inner = Scope({}, self.scope)
        for d in sub.defaults:
            inner.values[d.key.text] = self._scalar(d.value, inner) if isinstance(d.value, Word) \
                else self._fail_value(d)
        for it in pairs:
            if not isinstance(it.key, Word) or not isinstance(it.value, Word):
                raise _err(f"expected name=value, got {it}", it)
            k = it.key.text
            if k not in inner.values:
                known = [d.key.text for d in sub.defaults]
                raise _err(f"subcircuit {sub.name} has no parameter {k!r}", it.key,
                           _close(k, known) or ("parameters: " + ", ".join(known) if known else
                                                "it declares no parameters"))
            inner.values[k] = self._scalar(it.value, scope)
        if idx is not None:
            inner.values.setdefault("index", float(idx))
        inst = Instance(full, sub.name, actual, {d.key.text: inner.values[d.key.text]
                                                 for d in sub.defaults}, len(stack),
                        span=name_item.span)
        made = [inst, len(self.circuit.elements), None]
        self.instances.append(made)
        for s in sub.body:
            if s.keyword == ".param":
                self._param(s, inner)
        self._body(sub.body, inner, full + ".", actual, stack + [sub.name.lower()])
        made[2] = len(self.circuit.elements)

    def _instances(self) -> list[Instance]:
        """The instances, each with the names of the elements it made."""
        names = list(self.circuit.elements)
        for inst, start, stop in self.instances:
            inst.elements = tuple(names[start:stop])
        return [inst for inst, _, _ in self.instances]

    def _ic(self, st, scope, prefix, nodemap):
        if len(st.items) < 2:
            raise _err(".ic needs node=pressure", st.span, "e.g. .ic tank=200kPag or .ic p(tank)=296kPa")
        for it in st.items[1:]:
            if not isinstance(it, Pair):
                raise _err(f".ic expects node=pressure, got {it}", it)
            key = it.key
            if isinstance(key, Call) and key.name.lower() in ("p", "v") and len(key.args) == 1 \
                    and isinstance(key.args[0], Word):
                node = key.args[0].text
            elif isinstance(key, Word):
                node = key.text
            else:
                raise _err(f".ic expects node=pressure, got {key}", key)
            value = self._number(it.value, "pressure", f"initial pressure of {node}", scope)
            if value <= 0:
                raise _err(f"initial pressure of {node} = {value:g} kPa: an absolute pressure "
                           "must be > 0 (as for p0)", it.value,
                           "pressures are absolute; a gauge pressure carries a g: 100kPag")
            plausible.check_level(value, it.value, node)
            node = self._node(node, prefix, nodemap)
            if not self.has_node(node):
                raise _err(f"initial condition for unknown node {node!r}", key,
                           _close(node, self.circuit.nodes))
            self.circuit.set_initial(node, value)

    # ---- analyses
def _kind_keywords():
    out = set()
    for k in elements.known_kinds():
        fam = elements.family(k)
        out.add(k.lower())
        out.update(a.lower() for a in fam.aliases if len(a) > 1)
    return out


def _element_letter(word: str) -> bool:
    """Whether ``word``'s first letter names an element family (``Vt``: a volume)."""
    try:
        elements.family(word[0])
    except PneunetError:
        return False
    return True


def _fmt_int(value: float) -> str:
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(float(value))


def _example(slot):
    from ..physics.units import example

    return example(slot)
