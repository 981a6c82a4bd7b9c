"""``.meas`` statements: the measurement part of the elaboration."""
from __future__ import annotations

import re

from .deck import Measure
from .expr import check_names
from .located import did_you_mean as _close, error_at as _err
from .syntax import Pair, Word

#: the unit slot of a signal quantity (``p(node)``, ``contraction(M1)``…): its levels are
#: read in it and its measurements printed in its unit; other signals are plain numbers
SIGNAL_SLOTS = {"p": "pressure", "mdot": "flow", "contraction": "length", "force": "force",
                "volume": "volume", "V": "volume", "T": "temperature"}


class MeasureStatements:
    """Mixin of the elaboration builder: ``.meas`` statements and their options."""

    def _meas(self, st, earlier=()) -> Measure:
        """The ``.meas`` statement ``st``; ``earlier``: the measurements above it (the
        names a PARAM expression may use)."""
        items = list(st.items[1:])
        analysis = "tran"
        if items and isinstance(items[0], Word) and items[0].text.lower() in ("tran", "op", "dc"):
            analysis = items.pop(0).text.lower()
        if len(items) < 2 or not isinstance(items[0], Word):
            raise _err(".meas needs a name and a measurement", st.span,
                       "e.g. .meas tran period PERIOD p(tank)")
        name = items[0].text
        if not re.fullmatch(r"[A-Za-z_][A-Za-z_0-9]*", name):
            raise _err(f"bad measurement name {name!r}", items[0])
        kind_item = items[1]
        if not isinstance(kind_item, Word):
            raise _err(f"expected a measurement kind, got {kind_item}", kind_item)
        kind = kind_item.text.lower()
        rest = items[2:]
        m = Measure(name, kind, analysis, span=st.span,
                    text=" ".join(str(i) for i in st.items))
        kinds = ("find", "min", "max", "avg", "pp", "rms", "integ", "when", "trig", "period",
                 "freq", "risetime", "falltime", "filltime", "param")
        if kind not in kinds:
            raise _err(f"unknown measurement {kind_item.text!r}", kind_item,
                       _close(kind, kinds) or "known: " + ", ".join(k.upper() for k in kinds))
        time_slot = "time"
        if analysis == "dc":
            time_slot = None  # sweep values (in the source's unit)
        if kind == "param":
            if len(rest) != 1 or not isinstance(rest[0], Word):
                raise _err("PARAM needs one {expression} of other measurements", kind_item)
            m.args["expr"] = word = rest[0]
            text = word.text[1:-1] if word.text.startswith("{") else word.text
            check_names(text, [x.name for x in earlier], word.span, word.span.column + 1,
                        "PARAM uses the measurements above it: "
                        + (", ".join(x.name for x in earlier) or "none here"))
            return m
        if kind == "when":
            if not rest or not isinstance(rest[0], Pair):
                raise _err("WHEN needs signal=value", rest[0] if rest else kind_item,
                           "e.g. .meas t1 WHEN p(tank)=296kPa RISE=1")
            m.signal = self._signal(rest[0].key)
            m.args["level"] = self._level(m.signal, rest[0].value)
            self._meas_keys(m, rest[1:], ("rise", "fall", "cross", "from", "to", "td"), time_slot)
            return m
        if kind == "trig":
            targ = next((i for i, it in enumerate(rest) if isinstance(it, Word)
                         and it.text.lower() == "targ"), None)
            if targ is None or not rest:
                raise _err("TRIG needs ... TARG ...", kind_item,
                           "e.g. .meas dt TRIG p(a) VAL=150kPa RISE=1 TARG p(b) VAL=150kPa RISE=1")
            m.kind = "trig_targ"
            for part, label in ((rest[:targ], "trig"), (rest[targ + 1:], "targ")):
                if not part:
                    raise _err(f"{label.upper()} needs a signal", kind_item)
                sig = self._signal(part[0])
                sub = Measure(label, label, analysis)
                sub.signal = sig
                self._meas_keys(sub, part[1:], ("val", "rise", "fall", "cross", "td"), time_slot)
                if "val" not in sub.args:
                    raise _err(f"{label.upper()} needs VAL=", part[0])
                m.args[label] = sub
            return m
        if not rest:
            raise _err(f"{kind.upper()} needs a signal", kind_item)
        m.signal = self._signal(rest[0])
        tail = rest[1:]
        if kind == "find":
            if tail and isinstance(tail[0], Word) and tail[0].text.lower() == "when":
                if len(tail) < 2 or not isinstance(tail[1], Pair):
                    raise _err("FIND ... WHEN needs signal=value", tail[0])
                m.kind = "find_when"
                sig = self._signal(tail[1].key)
                m.args["when"] = sig
                m.args["level"] = self._level(sig, tail[1].value)
                self._meas_keys(m, tail[2:], ("rise", "fall", "cross", "from", "to", "td"), time_slot)
                return m
            self._meas_keys(m, tail, ("at",), time_slot)
            if "at" not in m.args and analysis != "op":
                raise _err("FIND needs AT=time or WHEN signal=value", kind_item,
                           "e.g. .meas p5 FIND p(tank) AT=5s")
            return m
        if kind in ("risetime", "falltime", "filltime"):
            self._meas_keys(m, tail, ("low", "high", "from", "to"), time_slot, signal=m.signal)
            if "low" not in m.args or "high" not in m.args:
                raise _err(f"{kind.upper()} needs LOW= and HIGH=", kind_item,
                           "e.g. .meas fill FILLTIME p(act) LOW=96kPa HIGH=296kPa")
            return m
        if kind in ("period", "freq"):
            self._meas_keys(m, tail, ("level", "from", "to", "cycles"), time_slot, signal=m.signal)
            return m
        self._meas_keys(m, tail, ("from", "to"), time_slot)
        return m

    def _level(self, sig, word):
        slot = SIGNAL_SLOTS.get(sig.quantity, "dimensionless")
        return self._number(word, slot, f"level of {sig}", self.scope)

    def _meas_keys(self, m, items, allowed, time_slot, signal=None):
        for it in items:
            if not isinstance(it, Pair) or not isinstance(it.key, Word):
                raise _err(f"unexpected {it} in .meas", it,
                           "options are key=value: " + ", ".join(a.upper() + "=" for a in allowed))
            k = it.key.text.lower()
            if k not in allowed:
                raise _err(f"unknown .meas option {it.key.text!r}", it.key,
                           _close(k, allowed) or "known here: " + ", ".join(a.upper() for a in allowed))
            if k in ("rise", "fall", "cross", "cycles"):
                if isinstance(it.value, Word) and it.value.text.lower() == "last":
                    m.args["edge"], m.args["n"] = (k if k != "cycles" else "rise"), -1
                    continue
                v = self._number(it.value, "dimensionless", k.upper(), self.scope)
                if v != int(v) or v < 1:
                    raise _err(f"{k.upper()} must be a whole number >= 1 (or LAST)", it.value)
                if k == "cycles":
                    m.args["cycles"] = int(v)
                else:
                    m.args["edge"], m.args["n"] = k, int(v)
            elif k in ("val", "level", "low", "high"):
                sig = signal or m.signal
                m.args[k] = self._level(sig, it.value) if sig else \
                    self._number(it.value, "dimensionless", k, self.scope)
            else:  # at, from, to, td
                key = "from" if k == "td" else k
                if time_slot is None:
                    m.args[key] = self._scalar(it.value, self.scope)
                else:
                    m.args[key] = self._number(it.value, time_slot, k.upper(), self.scope)
