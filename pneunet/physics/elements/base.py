"""The fixed interface every element family implements, and its parameter specs.

An element *family* (all resistors, all valves, …) is evaluated for all its
instances at once.  The assembler only sees this interface:

* ``ports``: names of the element's nodes, in netlist order;
* ``params``: a :class:`Param` per parameter (slot/unit, valid range, default);
* ``outflows(t, p, pdot)``: mass flow from each port's node *into* the element,
  shape (n, n_ports), with partials ``dq_dp`` and ``dq_dpdot`` (n, n_ports, n_ports);
* ``flows(t, p, pdot)``: the same flows without partials, for the residual and
  for reporting over many time points at once (override it for speed);
* ``flow_ports``: ports through which flow can pass (a valve's control port
  passes none), used by the topology checks;
* ``storage_ports``: ports through which the element stores mass (their nodes
  become differential unknowns);
* ``pinned_ports`` and ``pinned_pressure(t)``: ports whose node pressure the
  element imposes (pressure sources);
* ``state_ports``: ports at internal nodes that carry the element's own state as a
  pressure-like unknown (a muscle's contraction): never floating or dangling, no dead
  volume there, and no pressure of theirs in results;
* ``signals(t, p)``: named per-instance results for the solution (flows…);
* ``fluids``: the fluids its law holds for ('gas', 'liquid'; see ``.options fluid``).

The assembler never asks what type an element is.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...common.errors import ParameterError, SourceSpan

#: up to this many instances a family may evaluate its law instance by instance on
#: Python floats (:class:`pneunet.physics.laws.Scalar`): faster than numpy on tiny arrays
FEW_INSTANCES = 8


@dataclass(frozen=True)
class Param:
    """A parameter: its slot (see :mod:`pneunet.physics.units`), valid range and default."""

    slot: str
    doc: str
    low: float = -np.inf
    high: float = np.inf
    default: Any = None
    low_inclusive: bool = True
    kind: str = "number"  # 'number', 'waveform' or 'object'
    #: (low, high) where real values lie, internal unit: a netlist's bare number outside it
    #: is a located warning (pneunet.netlist.plausible); None: no usual range
    typical: tuple[float, float] | None = None
    #: (low, high) outside which any value, unit or not, is a located warning (default:
    #: ``typical`` widened 100× each way)
    plausible: tuple[float, float] | None = None

    @property
    def required(self) -> bool:
        return self.default is None

    def check(self, value: float, where: str, name: str) -> None:
        if not np.isfinite(value):
            raise ParameterError(f"{name} must be a finite number, got {value}", where=where)
        too_low = value < self.low if self.low_inclusive else value <= self.low
        if too_low or value > self.high:
            from ..units import SLOTS, pretty

            unit = f" {pretty(SLOTS[self.slot])}" if SLOTS[self.slot] else ""
            lo = "[" if self.low_inclusive else "("
            raise ParameterError(
                f"{name}={value:g}{unit} is outside its valid range {lo}{self.low:g}, {self.high:g}]",
                where=where, hint=self.doc)


@dataclass
class ElementSpec:
    """One element as the user described it (converted to internal units)."""

    kind: str
    name: str
    nodes: tuple[str, ...]
    params: dict[str, Any]
    span: SourceSpan | None = None

    @property
    def where(self) -> str:
        return f"{self.span}: element {self.name}" if self.span else f"element {self.name}"


@dataclass
class FamilyContext:
    """What families need from the circuit: options and the gas."""

    options: Any  # SimulationOptions

    @property
    def gas(self):
        return self.options.gas_model


class ElementFamily:
    """Base class of element families (see module docstring)."""

    kind: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    description: ClassVar[str] = ""
    ports: ClassVar[tuple[str, ...]] = ()
    params: ClassVar[dict[str, Param]] = {}
    flow_ports: ClassVar[tuple[int, ...] | None] = None  # ports that pass flow (None: all)
    storage_ports: ClassVar[tuple[int, ...]] = ()
    pinned_ports: ClassVar[tuple[int, ...]] = ()
    state_ports: ClassVar[tuple[int, ...]] = ()  # internal state nodes, not pressures
    #: (a, b): the element is a zero-resistance link, port a's node at port b's pressure
    link_ports: ClassVar[tuple[int, int] | None] = None
    fluids: ClassVar[tuple[str, ...]] = ("gas",)  # 'gas' and/or 'liquid': where its law holds
    #: its signals warn about a whole run (pneunet.physics.elements.run_checks): read at the end of
    #: every transient, whatever is saved
    checks_run: ClassVar[bool] = False

    def __init__(self, specs: list[ElementSpec], context: FamilyContext):
        self.specs = specs
        self.names = [s.name for s in specs]
        self.context = context
        self.n = len(specs)

    @classmethod
    def passing_flow(cls, n_nodes: int) -> list[int]:
        """Indices of the ports that pass flow, for an instance with ``n_nodes`` nodes."""
        return [k for k in (cls.flow_ports if cls.flow_ports is not None else range(n_nodes))
                if k < n_nodes]

    @classmethod
    def check_spec(cls, spec: ElementSpec) -> None:
        """Checks across parameters (single values are checked by :class:`Param`)."""

    @classmethod
    def expand(cls, spec: ElementSpec) -> list[ElementSpec]:
        """The elements the circuit stores for ``spec``: itself, or parts joined at
        internal nodes (a ``tube``'s segments)."""
        return [spec]

    def column(self, name: str) -> np.ndarray:
        """All instances' values of a numeric parameter, as an array."""
        return np.array([s.params[name] for s in self.specs], dtype=float)

    # -- physics ----------------------------------------------------------------
    def outflows(self, t: float, p: np.ndarray, pdot: np.ndarray):
        """Flows (n, n_ports) out of each port's node, ``dq_dp``, ``dq_dpdot`` (or None)."""
        n_ports = len(self.ports)
        zero = np.zeros((self.n, n_ports))
        return zero, np.zeros((self.n, n_ports, n_ports)), None

    #: whether this family has ``float_outflows(t, p, pdot, rows, partials)``:
    #: :meth:`outflows` on Python floats for a small circuit — ``p``, ``pdot`` lists of
    #: pressures and rates, ``rows`` each instance's indices of its ports' values in them;
    #: it returns flat lists ``q`` (n·n_ports), ``dq_dp`` and ``dq_dpdot`` (n·n_ports²,
    #: None without ``partials``; ``dq_dpdot`` None where zero), row-major like the
    #: arrays' ravel and the same bits (:mod:`pneunet.engine.float_plan`).  Families
    #: that have it set this True; the others are never asked for it.
    on_floats: bool = False

    def flows(self, t, p: np.ndarray, pdot: np.ndarray) -> np.ndarray:
        """Flows out of each port's node, shape (..., n, n_ports), no partials.

        ``p`` and ``pdot`` have shape (n, n_ports) with a float ``t``, or
        (n_t, n, n_ports) with ``t`` an array of the n_t times.
        """
        if np.ndim(t) == 0:
            return self.outflows(t, p, pdot)[0]
        return np.stack([self.outflows(ti, pi, di)[0] for ti, pi, di in zip(t, p, pdot)])

    def pinned_pressure(self, t) -> np.ndarray:
        """Pressures (..., n, len(pinned_ports)) imposed at pinned ports, kPa.

        ``t`` is a float, or an array of times (a leading axis in the result).
        """
        return np.empty(np.shape(t) + (self.n, 0))

    def pinned_pressure_each(self, t: np.ndarray) -> np.ndarray:
        """Pressures (n, len(pinned_ports)) with instance i at its own time t[i] (s)."""
        if not self.n:
            return np.empty((0, len(self.pinned_ports)))
        return np.stack([self.pinned_pressure(float(ti))[i] for i, ti in enumerate(t)])

    def instance_corners(self, t_start: float, t_stop: float):
        """Per instance: (times where an input's slope jumps, the subset where its value
        jumps) in (t_start, t_stop), s; None for a family without time-varying inputs."""
        return None

    def jumps(self, t_start: float, t_stop: float) -> np.ndarray:
        """Times where an input of this family jumps (the solver restarts there)."""
        return self._union(t_start, t_stop, 1)

    def breakpoints(self, t_start: float, t_stop: float) -> np.ndarray:
        """Times where an input's slope jumps (the solver steps onto them)."""
        return self._union(t_start, t_stop, 0)

    def _union(self, t_start, t_stop, which):
        corners = self.instance_corners(t_start, t_stop)
        if not corners:
            return np.empty(0)
        return np.unique(np.concatenate([c[which] for c in corners]))

    def initial_pressure(self) -> np.ndarray:
        """Initial pressure (n,) of storage instances, NaN where not set, kPa; or (n, k),
        one per storage port."""
        return np.full(self.n, np.nan)

    def signals(self, t: np.ndarray, p: np.ndarray) -> dict[str, tuple[str, np.ndarray]]:
        """Named results per instance over time: {suffix: (unit, array (n_t, n))}.

        ``p`` has shape (n_t, n, n_ports).  The solution names each signal
        ``<suffix>_<element>``, e.g. ``mdot_Rout``.
        """
        return {}

    def undefined_signals(self, suffix: str) -> frozenset[int]:
        """Instances for which the signal ``suffix`` has no meaning (left out of the
        solution, so that asking for it is an error rather than a column of NaN)."""
        return frozenset()


_REGISTRY: dict[str, type[ElementFamily]] = {}  # kind or alias (lower case) -> family


def register(family: type[ElementFamily]) -> type[ElementFamily]:
    """Make an element family known to circuits and netlists (usable as decorator)."""
    for key in (family.kind, *family.aliases):
        _REGISTRY[key.lower()] = family
    return family
