"""``.tran``, ``.dc``, ``.step`` and ``.save``/``.print``: the analysis part of the elaboration."""
from __future__ import annotations

import math
import re

from .deck import DC, Signal, Step, Tran
from .located import did_you_mean as _close, error_at as _err
from .syntax import Call, Word


def signal_quantities(spec, options) -> list | None:
    """The signal quantities (``mdot``, ``volume`` …) of element ``spec``: what its family
    reports for one instance at ambient pressure (None if that cannot be asked)."""
    import numpy as np

    from ..physics import elements

    family = elements.family(spec.kind)
    found = ["mdot"] if family.pinned_ports else []   # a source's flow (the solution's)
    try:
        fam = family([spec], elements.FamilyContext(options))
        p = np.full((1, 1, len(spec.nodes)), options.ambient)
        found += [q for q in fam.signals(np.zeros(1), p) if q not in found]
    except Exception:  # noqa: BLE001 - a plug-in that cannot be asked: not checked here
        return None
    return found


class AnalysisStatements:
    """Mixin of the elaboration builder: analyses, sweeps and signal lists."""

    def _positional_numbers(self, st, slot, label):
        out = []
        for it in st.items[1:]:
            if not isinstance(it, Word):
                raise _err(f"{st.head} expects numbers, got {it}", it)
            out.append(self._number(it, slot, label, self.scope))
        return out

    def _tran(self, st):
        values = self._positional_numbers(st, "time", ".tran time")
        if not values or len(values) > 3:
            raise _err(f".tran takes [tstep] tstop [tstart], got {len(values)} value(s)", st.span,
                       "e.g. .tran 10ms 5s")
        step, stop, start = (None, values[0], 0.0) if len(values) == 1 else \
            (values[0], values[1], values[2] if len(values) == 3 else 0.0)
        if stop <= 0:
            raise _err(f"t_stop must be > 0 s, got {stop:g}", st.items[2 if len(values) > 1 else 1])
        if step is not None and step <= 0:
            raise _err(f"t_step must be > 0 s, got {step:g}", st.items[1])
        if start < 0 or start >= stop:
            raise _err("t_start must lie in [0, t_stop)", st.items[3])
        if step is not None and (stop - start) / step > self.limits.max_output_points:
            raise _err(f".tran {step:g} {stop:g} asks for {(stop - start) / step:.3g} output "
                       f"points ({self.limits.exceeded('max_output_points')})", st.items[1],
                       "a larger output step (the solver's own steps are not limited by it); "
                       + self.limits.hint("max_output_points"))
        return Tran(stop, step, start, st.span)

    def _dc(self, st):
        items = st.items[1:]
        if not items or not isinstance(items[0], Word):
            raise _err(".dc needs a source name", st.span, "e.g. .dc PH 96kPa 596kPa 25kPa")
        name = items[0].text
        spec = self.circuit.elements.get(name)
        if spec is None or spec.kind not in ("pressure_source", "flow_source"):
            sources = [n for n, e in self.circuit.elements.items()
                       if e.kind in ("pressure_source", "flow_source")]
            raise _err(f".dc sweeps a source; {name!r} is " +
                       ("not a source" if spec else "not defined"), items[0],
                       _close(name, sources) or ("sources: " + ", ".join(sources)))
        from ..physics import elements

        slot = elements.family(spec.kind).params["value"].slot
        values = self._sweep_values(st, items[1:], lambda w: self._number(w, slot, name, self.scope))
        return DC(name, values, st.span)

    def _sweep_values(self, st, items, conv):
        if items and isinstance(items[0], Word) and items[0].text.lower() == "list":
            if len(items) < 2:
                raise _err("list needs at least one value", items[0])
            if len(items) - 1 > self.limits.max_sweep_points:
                raise _err(f"a list of {len(items) - 1} values "
                           f"({self.limits.exceeded('max_sweep_points')})", items[0],
                           self.limits.hint("max_sweep_points"))
            return [conv(w) for w in items[1:]]
        if items and isinstance(items[0], Word) and items[0].text.lower() == "lin":
            items = items[1:]
        if len(items) != 3:
            raise _err(f"{st.head} needs start stop step (or list v1 v2 ...), got {len(items)} "
                       "value(s)", items[-1] if items else st.span)
        start, stop, step = (conv(w) for w in items)
        if step == 0 or (stop - start) / step < 0:
            raise _err(f"step {step:g} does not go from {start:g} to {stop:g}", items[2])
        n = (stop - start) / step + 1
        if n > self.limits.max_sweep_points:
            raise _err(f"{n:.3g} sweep points ({self.limits.exceeded('max_sweep_points')})",
                       items[2], self.limits.hint("max_sweep_points"))
        n = int(math.floor(n - 1 + 1e-9)) + 1
        return [start + i * step for i in range(n)]

    def _step(self, st):
        items = list(st.items[1:])
        if items and isinstance(items[0], Word) and items[0].text.lower() in ("lin", "list") \
                and len(items) > 2 and isinstance(items[1], Word) and items[1].text.lower() == "param":
            items = [items[1], items[2], items[0]] + items[3:]
        if items and isinstance(items[0], Word) and items[0].text.lower() == "param":
            items = items[1:]
        if not items or not isinstance(items[0], Word) or \
                not re.fullmatch(r"[A-Za-z_][A-Za-z_0-9]*", items[0].text):
            raise _err(".step needs a parameter name", items[0] if items else st.span,
                       "e.g. .step param Rout list 0.566 1.132")
        name = items[0].text
        declared = self.declared_params()
        if name not in declared:
            raise _err(f".step of {name!r}, which no .param line defines", items[0],
                       _close(name, declared) or "define it first: .param NAME=value")
        values = self._sweep_values(st, items[1:], lambda w: self._scalar(w, self.scope))
        return Step(name, values, st.span)

    def _signal(self, item, label="signal"):
        if isinstance(item, Call) and len(item.args) == 1 and isinstance(item.args[0], Word):
            # p and mdot by any of their names; an element's own signal (T, opening …)
            # as its family spells it
            q = {"p": "p", "v": "p", "pressure": "p", "mdot": "mdot", "m": "mdot", "i": "mdot",
                 "flow": "mdot"}.get(item.name.lower(), item.name)
            target = item.args[0].text
            if q == "p":
                if not self.has_node(target):
                    raise _err(f"unknown node {target!r}", item.args[0],
                               _close(target, self.circuit.nodes))
            else:
                target = self._element_signal(q, target, item)
            return Signal(q, target)
        raise _err(f"expected a {label} like p(node) or mdot(element), got {item}", item)

    def _element_signal(self, q, target, item) -> str:
        """The element whose signal ``q(target)`` names (a tube's flow: its first segment),
        or an error at ``item`` listing the signals the element has, as written."""
        elements = self.circuit.elements
        if target not in elements and q == "mdot" and f"{target}.s1" in elements:
            return f"{target}.s1"  # a tube: the flow at its first node
        if target not in elements:
            raise _err(f"unknown element {target!r}", item.args[0], _close(target, elements))
        has = signal_quantities(elements[target], self.circuit.options)
        if has is not None and q not in has:
            raise _err(f"element {target!r} ({elements[target].kind}) has no signal "
                       f"{item.name}(...)", item,
                       "its signals: " + ", ".join(f"{s}({target})" for s in has)
                       if has else f"a {elements[target].kind} has no signals of its own")
        return target

    def _saves(self, st):
        items = st.items[1:]
        if items and isinstance(items[0], Word) and items[0].text.lower() in ("tran", "op", "dc"):
            items = items[1:]
        if len(items) == 1 and isinstance(items[0], Word) and items[0].text.lower() == "all":
            return []
        if not items:
            raise _err(f"{st.head} needs signals", st.span, "e.g. .save p(tank) mdot(X1)")
        return [self._signal(it) for it in items]
