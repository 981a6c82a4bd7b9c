"""A netlist file with its includes expanded and its ``.subckt`` blocks collected."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..common.errors import SourceSpan
from .includes import IncludePolicy, expand
from .limits import DEFAULT as DEFAULT_LIMITS, Limits
from .located import error_at as _err
from .syntax import Pair, SourceText, Word


@dataclass
class Subckt:
    name: str
    ports: list
    defaults: list  # Pair items
    body: list
    span: SourceSpan


@dataclass
class Source:
    """A netlist file with includes expanded and subcircuits separated."""

    file: str
    title: str
    top: list
    subckts: dict = field(default_factory=dict)
    limits: Limits = DEFAULT_LIMITS
    policy: IncludePolicy | None = None  # also where data files (tables, recordings) may be


def load(src: SourceText, policy: IncludePolicy | None = None,
         limits: Limits = DEFAULT_LIMITS) -> Source:
    """Expand ``.include`` (see :mod:`.includes`) and collect ``.subckt`` blocks."""
    if policy is None:
        policy = IncludePolicy.for_netlist(Path(src.name) if src.name != "<netlist>" else None)
    statements = list(expand(src, policy, limits))
    title = src.title
    top, subckts, stack = [], {}, []
    for st in statements:
        kw = st.keyword if st.is_directive else ""
        if kw == ".end":
            break
        if kw == ".title":
            title = " ".join(str(i) for i in st.items[1:])
            continue
        if kw == ".subckt":
            if len(st.items) < 2 or not isinstance(st.items[1], Word):
                raise _err(".subckt needs a name", st.span, "e.g. .subckt CELL in out k=1")
            ports, defaults = [], []
            for it in st.items[2:]:
                if isinstance(it, Pair):
                    defaults.append(it)
                elif isinstance(it, Word) and it.text.lower() == "params:":
                    continue
                elif isinstance(it, Word):
                    if defaults:
                        raise _err(f"port {it.text!r} after parameters", it,
                                   "list the ports first, then key=value defaults")
                    ports.append(it.text)
                else:
                    raise _err(f"unexpected {it} in .subckt line", it)
            stack.append(Subckt(st.items[1].text, ports, defaults, [], st.span))
            continue
        if kw == ".ends":
            if not stack:
                raise _err(".ends without .subckt", st.span)
            sub = stack.pop()
            if len(st.items) > 1 and isinstance(st.items[1], Word) and \
                    st.items[1].text.lower() != sub.name.lower():
                raise _err(f".ends {st.items[1].text} closes .subckt {sub.name}", st.items[1])
            key = sub.name.lower()
            if key in subckts:
                raise _err(f"subcircuit {sub.name!r} defined twice", sub.span,
                           f"first defined at {subckts[key].span}")
            subckts[key] = sub
            continue
        if stack:
            if kw in (".tran", ".op", ".dc", ".step", ".meas", ".measure", ".options", ".option",
                      ".fluid", ".save", ".print"):
                raise _err(f"{st.head} is not allowed inside .subckt {stack[-1].name}", st.span,
                           "put analyses and options at the top level")
            stack[-1].body.append(st)
        else:
            top.append(st)
    if stack:
        raise _err(f".subckt {stack[-1].name} has no .ends", stack[-1].span)
    return Source(src.name, title, top, subckts, limits, policy)
