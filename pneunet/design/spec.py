"""The specification language of ``pneunet design``: targets, search ranges, tolerances.

Targets (one string each; internal units: s, Hz, kPa absolute, mg/s)::

    period=3s            equality, ±5 % by default
    period=3s±0.1s       equality with an absolute tolerance (also +-)
    duty=0.4±10%         a relative tolerance
    swing>=130kPa        inequality (also <=)
    p_min@out<=190kPa    a built-in metric at a chosen node
    fill_act<=0.2s       any ``.meas`` name of the netlist

Built-in metrics (from the transient at a node, default the control node of the first
valve): ``period``, ``frequency``, ``duty``, ``swing``, ``p_min``, ``p_max``.  A name that
the netlist's ``.meas`` statements define is that measurement (unless ``@node`` is given).

Ranges: ``NAME=LOW:HIGH`` (0 < LOW < HIGH, searched in log).  Tolerances of a spread:
``NAME=±X`` or ``NAME=±X%`` (``X1.pclose=±5kPa``).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..netlist.builder import name_hint
from ..common.errors import ParameterError

#: built-in metric -> (unit slot, unit)
BUILTIN = {"period": ("time", "s"), "frequency": ("frequency", "Hz"),
           "duty": ("dimensionless", ""), "swing": ("pressure_difference", "kPa"),
           "p_min": ("pressure", "kPa"), "p_max": ("pressure", "kPa")}
#: built-in metric -> the values it can take (low, high, low itself allowed)
DOMAIN = {"period": (0.0, math.inf, False), "frequency": (0.0, math.inf, False),
          "duty": (0.0, 1.0, True), "swing": (0.0, math.inf, True),
          "p_min": (0.0, math.inf, False), "p_max": (0.0, math.inf, False)}
#: .meas kind -> the values it can give
MEAS_DOMAIN = {"period": DOMAIN["period"], "freq": DOMAIN["frequency"], "pp": DOMAIN["swing"],
               "risetime": DOMAIN["swing"], "falltime": DOMAIN["swing"],
               "filltime": DOMAIN["swing"]}
ALIASES = {"freq": "frequency", "duty_cycle": "duty", "pmin": "p_min", "pmax": "p_max"}
#: unit of a .meas result -> slot of its target values
MEAS_SLOTS = {"s": "time", "Hz": "frequency", "kPa": "pressure", "mg/s": "flow",
              "kPa*s": "dimensionless", "mg": "dimensionless", "": "dimensionless"}
DEFAULT_REL_TOL = 0.05
_TARGET = re.compile(r"^\s*([A-Za-z_*?][\w.*?]*)(?:@([\w.\[\]]+))?\s*(>=|<=|==|=)\s*(\S.*?)\s*$")
_PM = re.compile(r"±|\+-|\+/-")
_QUANTITY_NUMBER = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")
TARGET_HINT = "e.g. period=3s, period=3s±0.1s, duty=0.4±10%, swing>=130kPa, p_min@out<=190kPa"


@dataclass(frozen=True)
class Target:
    """One requirement on a metric: ``op`` is '=', '>=' or '<='; ``value`` and ``tol`` (the
    half-width of '=', and the miss counted as one unit by the search) in the metric's
    internal unit; ``source`` is 'meas' (a netlist .meas) or 'builtin'."""

    metric: str
    node: str | None
    op: str
    value: float
    tol: float
    unit: str
    source: str
    text: str

    @property
    def key(self) -> str:
        return f"{self.metric}@{self.node}" if self.node else self.metric

    def met(self, m: float) -> bool:
        if m is None or not math.isfinite(m):
            return False
        if self.op == "=":
            return abs(m - self.value) <= self.tol
        return m >= self.value if self.op == ">=" else m <= self.value

    def miss(self, m: float) -> float:
        """How far ``m`` is outside the target, in the metric's unit (0 when met; nan
        when not measured)."""
        if m is None or not math.isfinite(m):
            return math.nan
        if self.op == "=":
            return max(0.0, abs(m - self.value) - self.tol)
        return max(0.0, self.value - m) if self.op == ">=" else max(0.0, m - self.value)

    def residual(self, m: float, margin: float = 0.25) -> float:
        """The search's residual in units of ``tol``: (m − value)/tol for '=', for an
        inequality the shortfall past ``value`` moved ``margin`` tolerances inside."""
        if self.op == "=":
            return (m - self.value) / self.tol
        sign = 1.0 if self.op == ">=" else -1.0
        return max(0.0, margin - sign * (m - self.value) / self.tol)

    def describe(self) -> str:
        tol = f"±{self.tol:.4g}" if self.op == "=" else ""
        return f"{self.key} {self.op} {self.value:.6g}{tol} {self.unit}".rstrip()


def catalogue(measures: dict | None = None) -> dict:
    """Metric name -> (slot, unit, source): the built-ins and a netlist's ``.meas``
    names (``measures``: name -> unit)."""
    out = {k: (slot, unit, "builtin") for k, (slot, unit) in BUILTIN.items()}
    for name, unit in (measures or {}).items():
        out[name] = (MEAS_SLOTS.get(unit, "dimensionless"), unit, "meas")
    return out


def parse_targets(texts, measures: dict | None = None, ambient_kpa: float = 96.0) -> list:
    """Targets from strings; a name with ``*``/``?`` (``sel*>=296kPa``) stands for every
    ``.meas`` name it matches (a truth table's levels), in the netlist's order."""
    import fnmatch

    out = []
    for text in texts:
        if isinstance(text, Target):
            out.append(text)
            continue
        m = _TARGET.match(text)
        if not m or not any(c in m.group(1) for c in "*?"):
            out.append(parse_target(text, measures, ambient_kpa))
            continue
        names = [k for k in measures or {} if fnmatch.fnmatchcase(k, m.group(1))]
        if not names:
            raise ParameterError(f"target {text!r}: no .meas name matches {m.group(1)!r}",
                                 hint=".meas names: " + (", ".join(measures or {}) or "none"))
        rest = text[m.end(1):]
        out += [parse_target(name + rest, measures, ambient_kpa) for name in names]
    return out


def parse_target(text: str, measures: dict | None = None, ambient_kpa: float = 96.0) -> Target:
    """Read one target (module docstring); ``measures`` the netlist's .meas name -> unit."""
    m = _TARGET.match(text)
    if not m:
        raise ParameterError(f"cannot read target {text!r}", hint=TARGET_HINT)
    name, node, op, rhs = m.groups()
    op = "=" if op == "==" else op
    known = catalogue(measures)
    name = ALIASES.get(name, name) if name not in known else name
    if node and name not in BUILTIN:
        raise ParameterError(f"target {text!r}: only a built-in metric takes @node",
                             hint="built-in metrics: " + ", ".join(BUILTIN))
    if name not in known:
        raise ParameterError(f"target {text!r}: unknown metric {name!r}",
                             hint=name_hint(name, list(known) + list(ALIASES), "metrics"))
    slot, unit, source = known[name]
    if node:
        slot, unit, source = BUILTIN[name] + ("builtin",)
    value_text, tol_text = (_PM.split(rhs, maxsplit=1) + [None])[:2]
    value = _quantity(value_text, slot, f"target {text!r}", ambient_kpa)
    _check_domain(text, name, value, unit, DOMAIN.get(name) if source == "builtin" else None)
    if tol_text is None:
        tol = DEFAULT_REL_TOL * abs(value) if value else 1.0
    elif tol_text.strip().endswith("%"):
        tol = _number(tol_text.strip()[:-1], f"target {text!r}") / 100 * abs(value)
    else:
        diff = "pressure_difference" if slot == "pressure" else slot
        tol = _quantity(tol_text, diff, f"target {text!r}", ambient_kpa)
    if not tol > 0:
        raise ParameterError(f"target {text!r}: the tolerance must be positive",
                             hint="e.g. period=3s±0.1s or period=3s±5%")
    return Target(name, node, op, float(value), float(tol), unit, source, text.strip())


def check_meas_targets(targets, kinds: dict) -> None:
    """A ParameterError for a target on a ``.meas`` (``kinds``: name -> its kind, e.g.
    'period') whose value that kind of measurement can never give (``period=-3s``)."""
    for t in targets:
        if t.source == "meas":
            _check_domain(t.text, t.metric, t.value, t.unit, MEAS_DOMAIN.get(kinds.get(t.metric)))


def _check_domain(text, name, value, unit, domain) -> None:
    low, high, closed = domain or (-math.inf, math.inf, True)
    if not (math.isfinite(value) and (value >= low if closed else value > low) and value <= high):
        raise ParameterError(f"target {text!r}: {name} = {value:g} {unit} can never be measured",
                             hint=f"{name} lies in {'[' if closed else '('}{low:g}, {high:g}"
                                  f"{']' if high < math.inf else ')'} {unit}".rstrip())


@dataclass(frozen=True)
class Range:
    """A searched parameter: ``low`` < ``high``, both > 0 (searched in log)."""

    name: str
    low: float
    high: float


def parse_range(text: str) -> Range:
    """``NAME=LOW:HIGH`` with 0 < LOW < HIGH (plain numbers, the parameter's own unit)."""
    name, eq, spec = text.partition("=")
    parts = spec.split(":")
    hint = "NAME=LOW:HIGH with 0 < LOW < HIGH, e.g. Rout=0.6:3"
    if not eq or not name.strip() or len(parts) != 2:
        raise ParameterError(f"cannot read range {text!r}", hint=hint)
    low, high = (_number(p, f"range {text!r}") for p in parts)
    return make_range(name.strip(), low, high)


def make_range(name: str, low: float, high: float) -> Range:
    hint = "NAME=LOW:HIGH with 0 < LOW < HIGH, e.g. Rout=0.6:3"
    if not (math.isfinite(low) and math.isfinite(high)):
        raise ParameterError(f"range of {name}: {low}:{high} is not finite", hint=hint)
    if low <= 0:
        raise ParameterError(f"range of {name}: the low end {low:g} is not positive "
                             "(parameters are searched in log)", hint=hint)
    if low >= high:
        raise ParameterError(f"range of {name}: empty, low {low:g} ≥ high {high:g}", hint=hint)
    return Range(name, float(low), float(high))


@dataclass(frozen=True)
class Tolerance:
    """A stated spread: ``name`` ± ``text`` (a quantity, or a percentage of the nominal)."""

    name: str
    text: str

    def amount(self, nominal: float) -> float:
        """The half-width in the parameter's internal unit (valve-card parameters take
        units: ``±5kPa``; other parameters plain numbers)."""
        from ..netlist.models import VALVE_CARD

        what = f"tolerance {self.name}=±{self.text}"
        if self.text.endswith("%"):
            return _number(self.text[:-1], what) / 100 * abs(nominal)
        slot = VALVE_CARD.get(self.name.rsplit(".", 1)[-1], "dimensionless")
        return _quantity(self.text, slot, what)


def parse_tolerance(text: str) -> Tolerance:
    """``NAME=±X`` (a quantity: ``X1.pclose=±5kPa``) or ``NAME=±X%``."""
    name, eq, spec = text.partition("=")
    hint = "NAME=±X or NAME=±X%, e.g. X1.pclose=±5kPa (also +-5kPa)"
    spec = spec.strip()
    pm = _PM.match(spec)
    if not eq or not name.strip() or not pm:
        raise ParameterError(f"cannot read tolerance {text!r}", hint=hint)
    amount = spec[pm.end():].strip()
    number = _QUANTITY_NUMBER.match(amount)
    if not number or not 0 < float(number.group(1)) < math.inf:
        raise ParameterError(f"tolerance {text!r}: the spread must be a positive number",
                             hint=hint)
    return Tolerance(name.strip(), amount)


def require_whole(what: str, value, at_least: int) -> None:
    """A ParameterError unless ``value`` is an int ≥ ``at_least`` (counts and seeds)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < at_least:
        raise ParameterError(f"{what} must be a whole number ≥ {at_least}, got {value!r}")


def _number(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ParameterError(f"{what}: {text.strip()!r} is not a number") from None


def _quantity(text: str, slot: str, what: str, ambient_kpa: float = 96.0) -> float:
    from ..physics.units import split_quantity, to_internal

    text = text.strip()
    if slot == "dimensionless" and text.endswith("%"):
        return _number(text[:-1], what) / 100
    q = split_quantity(text)
    try:
        return float(to_internal(q.magnitude, q.unit, slot, gauge=q.gauge,
                                 ambient_kpa=ambient_kpa, name=what))
    except ParameterError as err:
        raise ParameterError(err.message, hint=err.hint) from None

