"""The :class:`Effect` protocol and the effect registry.

An *effect* is a documented, first-class extension of the six-parameter valve
model (MODEL.md eq. 19).  It owns bounded parameters (with units and a *null
value* at which it changes nothing) and modifies the valve law through one or
more of four hooks, applied by :class:`pneunet.physics.valve_effects.ValveModel` in this order:

1. ``pressures(x, **par) -> (p_in, p_out, p_ctrl)`` — what the valve really sees
   given the measured pressures (sensor / ambient offsets);
2. ``delta_p(dp, x, **par) -> dp`` — the equivalent membrane pressure
   difference Δp (eq. 13); an effect with ``uses_flow = True`` receives the flow
   as ``x.mdot`` and the model solves the implicit equation for ṁ;
3. ``flow(m, x, **par) -> m`` — the flow *magnitude* (hi → lo port); ``x.g`` is
   the valve conductance 1/R (eq. 19) and ``x.d`` = p_hi² − p_lo²;
4. the sign of the flow is applied last (eq. 25).

Within a stage effects run in increasing ``order``.  ``x`` is an
:class:`Inputs` namespace: ``p_in, p_out, p_ctrl, p_hi, p_lo, d, forward,
time, sweep, params`` (the :class:`~pneunet.physics.valve_params.ValveParams`).

A user effect is a few lines::

    from pneunet.physics.valve_effects import Effect, Param, register_effect

    @register_effect
    class Drift(Effect):
        '''Flow-sensor gain drifting linearly with time: ṁ_meas = ṁ (1 + c t/3600 s).'''
        id = "drift"
        needs = ("time",)
        params = {"c": Param("1/h", -0.5, 0.5, 0.0, "relative gain change per hour")}
        order = 90
        def flow(self, m, x, c):
            return m * (1 + c * x.time / 3600.0)
"""
from __future__ import annotations

import inspect
from dataclasses import dataclass
from types import SimpleNamespace

from ...common.errors import ParameterError


@dataclass(frozen=True)
class Param:
    """One bounded effect parameter.

    ``null`` is the value at which the effect does nothing; ``init`` (default:
    ``null``) is where a fit starts.
    """

    unit: str
    lo: float
    hi: float
    null: float
    doc: str = ""
    init: float | None = None

    @property
    def start(self) -> float:
        return self.null if self.init is None else self.init


class Inputs(SimpleNamespace):
    """The quantities an effect hook may read (see module docstring)."""


class Effect:
    """Base class of valve-model effects.  Subclass, set the class attributes,
    implement one or more hooks, and decorate with :func:`register_effect`.

    Class attributes
    ----------------
    id : str
        Unique id (lower case, ``-`` allowed).  In a ``.model`` card its
        parameters are named ``<id with - as _>_<param>``.
    params : dict[str, Param]
        The effect's parameters.
    needs : tuple[str, ...]
        Extra inputs the effect needs besides pressures: ``"time"``, ``"sweep"``.
    order : int
        Position within its hook stage (lower first).
    uses_flow : bool
        True if ``delta_p`` depends on the flow (``x.mdot``); the model then
        solves ṁ = f(Δp(ṁ)) by safeguarded Newton iteration.
    signature : str
        Residual signature of the missing effect (what the residuals of the
        plain model look like), in plain language.
    tell_apart : str
        Which measurement separates this effect from look-alikes.
    """

    id: str = ""
    params: dict[str, Param] = {}
    needs: tuple[str, ...] = ()
    order: int = 50
    uses_flow: bool = False
    signature: str = ""
    tell_apart: str = ""

    def __init__(self, **values):
        unknown = set(values) - set(self.params)
        if unknown:
            raise ParameterError(
                f"effect {self.id!r} has no parameter(s) {', '.join(sorted(unknown))}",
                hint="parameters: " + ", ".join(self.params))
        self.values = {k: float(values.get(k, p.null)) for k, p in self.params.items()}
        for k, v in self.values.items():
            p = self.params[k]
            if not (p.lo <= v <= p.hi):
                raise ParameterError(f"{self.id}.{k} = {v:g} {p.unit} outside [{p.lo:g}, {p.hi:g}]",
                                     where=f"effect {self.id}")

    # -- hooks (defaults do nothing) -------------------------------------------------
    def pressures(self, x, **par):
        return x.p_in, x.p_out, x.p_ctrl

    def delta_p(self, dp, x, **par):
        return dp

    def flow(self, m, x, **par):
        return m

    # -- helpers ------------------------------------------------------------------------
    @classmethod
    def card_prefix(cls) -> str:
        return cls.id.replace("-", "_") + "_"

    @classmethod
    def hooks(cls) -> set[str]:
        """Names of the hooks this effect overrides."""
        return {h for h in ("pressures", "delta_p", "flow")
                if getattr(cls, h) is not getattr(Effect, h)}

    def with_values(self, **values) -> "Effect":
        merged = dict(self.values)
        merged.update(values)
        return type(self)(**merged)

    def is_null(self) -> bool:
        return all(v == self.params[k].null for k, v in self.values.items())

    @classmethod
    def describe(cls) -> str:
        """First paragraph of the docstring (physics and equation)."""
        doc = inspect.getdoc(cls) or ""
        return doc.split("\n\n")[0].replace("\n", " ")

    def __repr__(self) -> str:
        vals = ", ".join(f"{k}={v:.4g}" for k, v in self.values.items())
        return f"{type(self).__name__}({vals})"

    def __eq__(self, other):
        return type(self) is type(other) and self.values == other.values

    def __hash__(self):
        return hash((type(self), tuple(sorted(self.values.items()))))


_REGISTRY: dict[str, type[Effect]] = {}


def register_effect(cls: type[Effect] | None = None, *, replace: bool = False):
    """Class decorator: make an :class:`Effect` subclass known by its ``id``.

    Re-registering an id raises :class:`ParameterError` unless ``replace=True``.
    """

    def deco(c):
        if not (isinstance(c, type) and issubclass(c, Effect)):
            raise ParameterError("register_effect expects an Effect subclass")
        if not c.id or c.id != c.id.lower() or " " in c.id or "_" in c.id:
            raise ParameterError(f"bad effect id {c.id!r}",
                                 hint="use lower case letters, digits and '-'")
        for name, p in c.params.items():
            if "_" in name or not isinstance(p, Param):
                raise ParameterError(f"effect {c.id}: parameter {name!r} must be a Param "
                                     "without '_' in its name")
            if not p.lo <= p.null <= p.hi or not p.lo <= p.start <= p.hi:
                raise ParameterError(f"effect {c.id}: null/init of {name} outside its bounds")
        if not c.hooks():
            raise ParameterError(f"effect {c.id} overrides no hook (pressures, delta_p, flow)")
        if c.id in _REGISTRY and _REGISTRY[c.id] is not c and not replace:
            raise ParameterError(f"effect id {c.id!r} already registered",
                                 hint="pass replace=True to override it")
        _REGISTRY[c.id] = c
        return c

    return deco(cls) if cls is not None else deco


def unregister_effect(effect_id: str) -> None:
    _REGISTRY.pop(effect_id, None)


def get_effect(effect_id: str) -> type[Effect]:
    """The registered effect class with this id (clear error otherwise)."""
    _load_library()
    try:
        return _REGISTRY[effect_id]
    except KeyError:
        raise ParameterError(f"unknown effect {effect_id!r}",
                             hint="known effects: " + ", ".join(available_effects())) from None


def available_effects() -> list[str]:
    """Ids of all registered effects (library first, in definition order)."""
    _load_library()
    return list(_REGISTRY)


def as_effect(spec) -> Effect:
    """An Effect instance from an instance, a class, or an id (null values)."""
    if isinstance(spec, Effect):
        return spec
    if isinstance(spec, type) and issubclass(spec, Effect):
        return spec()
    if isinstance(spec, str):
        return get_effect(spec)()
    raise ParameterError(f"not an effect: {spec!r}")


_LIBRARY = ("choked", "leak", "laminar", "internal_drop", "hysteresis", "pressure_offset")


def _load_library():
    import importlib

    for name in _LIBRARY:
        importlib.import_module(f"pneunet.physics.valve_effects.{name}")
