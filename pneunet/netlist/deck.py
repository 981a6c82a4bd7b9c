"""What a parsed netlist describes: the circuit plus analyses, measurements, saves, steps."""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

from ..common.errors import SourceSpan
from ..common.reprs import Summarized


@dataclass
class Tran:
    """``.tran [tstep] tstop [tstart]``: transient analysis to ``t_stop`` seconds."""

    t_stop: float
    t_step: float | None = None
    t_start: float = 0.0
    span: SourceSpan | None = None
    kind: str = "tran"


@dataclass
class Op:
    """``.op``: operating point (stationary pressures and flows)."""

    span: SourceSpan | None = None
    kind: str = "op"


@dataclass
class DC:
    """``.dc SOURCE start stop step`` (or ``list v1 v2 ...``): operating points of a swept source."""

    source: str
    values: list
    span: SourceSpan | None = None
    kind: str = "dc"


@dataclass
class Step:
    """``.step param NAME ...``: values of a parameter; several ``.step`` lines nest."""

    param: str
    values: list
    span: SourceSpan | None = None


@dataclass
class Signal:
    """A signal reference ``p(node)`` / ``mdot(element)``; ``key`` names it in a Solution."""

    quantity: str  # 'p', 'mdot', 'dp', 'opening', ...
    target: str

    @property
    def key(self) -> str:
        return f"{self.quantity}_{self.target}"

    def __str__(self) -> str:
        return f"{self.quantity}({self.target})"


@dataclass
class Measure:
    """One ``.meas`` statement, values already in internal units.

    ``kind`` is one of find, min, max, avg, pp, rms, integ, when, find_when,
    trig_targ, period, freq, risetime, falltime, param.
    """

    name: str
    kind: str
    analysis: str = "tran"
    signal: Signal | None = None
    args: dict = field(default_factory=dict)
    span: SourceSpan | None = None
    text: str = ""


@dataclass
class Instance:
    """A subcircuit instance (``X1 supply in out INV Rp=20``) as elaborated: its full name
    (``Xcell[3]``; inside another instance ``X1.X2``), its subcircuit, the flattened
    circuit's node on each port, its declared parameters' values (defaults and the
    instance's own) and the names of the elements it made; ``depth`` 0 at the top level."""

    name: str
    subckt: str
    ports: dict
    params: dict
    depth: int = 0
    elements: tuple = ()
    span: SourceSpan | None = None


@dataclass(repr=False)
class Deck(Summarized):
    """A netlist after elaboration.

    ``circuit`` is the (flattened) :class:`~pneunet.engine.circuit.Circuit`; ``analyses``
    the analyses in file order; ``measures`` the ``.meas`` statements; ``saves``
    the signals to write (empty: all); ``steps`` the ``.step`` sweeps (nested,
    first outermost); ``instances`` the subcircuit instances (:class:`Instance`).  :meth:`variant` rebuilds the deck with parameter values
    overridden (what ``.step`` does).
    """

    circuit: Any
    title: str = ""
    file: str = "<netlist>"
    analyses: list = field(default_factory=list)
    measures: list = field(default_factory=list)
    saves: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    params: dict = field(default_factory=dict)
    overrides: dict = field(default_factory=dict)
    source: Any = None  # the parsed statements, to rebuild variants
    instances: list = field(default_factory=list)
    elaborator: Any = None  # elaborate(source, overrides) -> Deck, which made this one

    def _summary(self):
        rows = [("elements", str(len(self.circuit.elements))),
                ("analyses", ", ".join(f".{a.kind}" for a in self.analyses) or "none"),
                ("measures", str(len(self.measures)))]
        if self.steps:
            rows.append(("step points", str(len(self.step_points()))))
        return repr(self.file), rows, ".circuit, .analyses, .measures, .variant(point)"

    def validate(self) -> None:
        """``circuit.validate()``; an error about the whole circuit ("no node has a defined
        pressure") is placed in the netlist's file."""
        from ..common.errors import PneunetError

        try:
            self.circuit.validate()
        except PneunetError as err:
            if err.where is not None or err.span is not None:
                raise
            raise type(err)(err.message, where=self.file, hint=err.hint) from None

    def draw(self, path=None, *, results=None, expand: bool = False):
        """The circuit's schematic (:func:`pneunet.interfaces.schematic.draw`): each subcircuit
        instance a box, or its elements with ``expand=True``."""
        from ..common.views import view

        return view("schematic")(self.circuit, path, results=results,
                                 instances=None if expand else self.instances)

    def _repr_svg_(self) -> str:
        """Jupyter shows a deck as its schematic."""
        return self.draw().svg

    def step_points(self) -> list[dict]:
        """All combinations of the ``.step`` values ([{}] without ``.step``)."""
        if not self.steps:
            return [{}]
        names = [s.param for s in self.steps]
        return [dict(zip(names, combo)) for combo in itertools.product(*(s.values for s in self.steps))]

    def variant(self, overrides: dict) -> "Deck":
        """The deck rebuilt with ``.param`` values replaced by ``overrides``."""
        return self.elaborator(self.source, overrides)

    def to_netlist(self) -> str:
        """Netlist text for this deck (flattened circuit, analyses, measurements)."""
        from .printer import print_deck

        return print_deck(self)
