"""Piping footprint of a soft robot (paper Fig. 1B): tubing cross-section and fill times.

A robot of N actuators (each a volume, mL) sits at the end of tubes of length L (mm) from
its pressure source; actuator k sits ``positions[k]`` mm further along the robot (default:
all at its base), so its lines are L + positions[k] long.  Shared lines (the supply, the
address lines and, from the inverters at the nearest actuator on, their complements) run
along the robot with a tap at each actuator.  Three designs are compared, every valve the same membrane valve
(normally open: a control pressure at the supply closes it, ambient opens it):

``individual``
    one power line per actuator; its valve at the source, driven directly;
``supply+control``
    one supply line to the robot, a valve at each actuator, one thin control line per
    valve from the source;
``demux``
    one supply (data) line, ⌈log₂ N⌉ thin address lines, and at the robot a binary
    demultiplexer as in ``netlists/demux3.pn``: per address bit a local inverter (valve
    from the supply, pull-down 20 kPa·s/mg, 2 mL), per actuator a chain of ⌈log₂ N⌉ valves
    (0.5 mL between them) that passes only when the address is the actuator's number.

Footprint: the sum of π/4·D² over the lines that leave the source, by outer diameter (what the tubing occupies)
and by bore (mm²).  Fill time: from the command at the source (t = 0) to the actuator's
pressure reaching ``level`` of the supply's gauge pressure, simulated with every line a
``tube`` element (laminar/Blasius, its own volume), from the idle state: supply line at
the supply pressure, control lines at the level that holds the valves closed, actuators at
ambient.  "alone": each actuator commanded by itself; "all": every actuator commanded at once
(``demux``: one at a time, so the sum of the single fill times).  Nothing is scaled: the
designs differ only in their tubes and where the valves sit.

:func:`control_line_delays` shows what one control line does by itself: it delays and
smooths the valve's control pressure, and the valve opens only once that pressure has
fallen below a_in·p_in + a_out·p_out − p_close (eq. 25).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..common.errors import ParameterError
from ..common.reprs import Summarized, number

if TYPE_CHECKING:
    from ..engine.circuit import Circuit

DESIGNS = ("individual", "supply+control", "demux")
INVERTER_PULL_DOWN = 20.0   # kPa·s/mg, as in netlists/demux3.pn
INVERTER_VOLUME = 2.0       # mL
CHAIN_VOLUME = 0.5          # mL between two valves of a demultiplexer cell


@dataclass(frozen=True)
class Tubing:
    """A tube size: bore (inner) and outer diameter, mm."""

    bore: float
    outer: float

    def __post_init__(self):
        if not 0 < self.bore < self.outer:
            raise ParameterError(f"tubing {self.bore:g}/{self.outer:g} mm: the bore must be "
                                 "> 0 and smaller than the outer diameter")

    def area(self, which: str) -> float:
        """Cross-section π/4·D² (mm²) of the ``bore`` or the ``outer`` diameter."""
        return math.pi / 4 * getattr(self, which) ** 2


@dataclass(frozen=True)
class PipingSpec:
    """The robot and its tubes.  The defaults are the paper's Fig. 1B arm as we read it:
    four actuators; power and supply lines 2.5 mm bore (the paper's hose, sec. 4.2) in
    4 mm tubing, control lines 1.2 mm bore in 3 mm tubing (outer diameters assumed: the
    paper gives none); 1 m of line, 50 mL actuators, the paper's 496/96 kPa."""

    actuators: int = 4
    length: float = 1000.0                          # mm, source to robot, every line
    positions: tuple = ()                           # mm along the robot (() : all at 0)
    volume: float = 50.0                            # mL per actuator
    power: Tubing = Tubing(2.5, 4.0)                # individual lines
    control: Tubing = Tubing(1.2, 3.0)              # control and address lines
    supply: Tubing | None = None                    # shared line (default: ``power``)
    valve: str = "axi"
    p_supply: float = 496.0                         # kPa abs
    ambient: float = 96.0                           # kPa abs
    level: float = 0.9                              # "filled": this fraction of the gauge
    t_stop: float = 10.0                            # s, longest simulated fill

    def __post_init__(self):
        checks = [("actuators", self.actuators >= 1 and self.actuators == int(self.actuators),
                   "a whole number >= 1"), ("length", self.length > 0, "> 0 mm"),
                  ("volume", self.volume > 0, "> 0 mL"),
                  ("p_supply", self.p_supply > self.ambient, "above ambient"),
                  ("level", 0 < self.level < 1, "in (0, 1)"), ("t_stop", self.t_stop > 0, "> 0 s")]
        for name, ok, rule in checks:
            if not ok:
                raise ParameterError(f"piping: {name}={getattr(self, name)!r} must be {rule}")
        if self.supply is None:
            object.__setattr__(self, "supply", self.power)
        positions = tuple(float(x) for x in self.positions)
        if positions and (len(positions) != self.actuators or min(positions) < 0):
            raise ParameterError(f"piping: positions={self.positions!r} must give one distance "
                                 f">= 0 mm per actuator ({self.actuators})")
        object.__setattr__(self, "positions", positions)

    def distance(self, k: int) -> float:
        """Tube length (mm) from the source to actuator ``k``."""
        return self.length + (self.positions[k] if self.positions else 0.0)

    @property
    def bits(self) -> int:
        """Address lines of the demultiplexer, ⌈log₂ N⌉ (at least 1)."""
        return max(1, math.ceil(math.log2(self.actuators)))

    @property
    def filled(self) -> float:
        """The pressure (kPa abs) an actuator must reach to count as filled."""
        return self.ambient + self.level * (self.p_supply - self.ambient)


def lines(spec: PipingSpec, design: str) -> list[tuple[str, int, Tubing]]:
    """The lines from the source to the robot: (role, count, tubing)."""
    n = spec.actuators
    return {"individual": [("power", n, spec.power)],
            "supply+control": [("supply", 1, spec.supply), ("control", n, spec.control)],
            "demux": [("supply", 1, spec.supply), ("address", spec.bits, spec.control)],
            }[_design(design)]


def cross_section(spec: PipingSpec, design: str, which: str = "outer") -> float:
    """Total tubing cross-section (mm²) of a design, by ``outer`` diameter or ``bore``."""
    return sum(count * tube.area(which) for _, count, tube in lines(spec, design))


def _design(name: str) -> str:
    if name not in DESIGNS:
        raise ParameterError(f"unknown piping design {name!r}", hint="one of " + ", ".join(DESIGNS))
    return name


# -- circuits ------------------------------------------------------------------------------
def _idle(circuit, prefix: str, end: str, pressure: float, initial: dict) -> None:
    """Record ``pressure`` as the idle state of a line: its end node and every internal
    node of the tube named ``prefix``."""
    initial[end] = pressure
    initial.update({node: pressure for node in circuit.nodes if node.startswith(prefix + ".")})


def _trunk(c, name: str, start: str, start_at: float, stops, bore: float, idle: float,
           initial: dict) -> dict:
    """A shared line from node ``start`` (``start_at`` mm from the source) with a tap at
    each distance in ``stops`` (mm): tubes ``{name}{j}`` between taps ``{name}_{j}``, idle
    at ``idle`` kPa.  Returns {distance: tap node}."""
    taps, node, at = {start_at: start}, start, start_at
    for j, distance in enumerate(sorted(set(stops) - {start_at})):
        tap = f"{name}_{j}"
        c.tube(f"{name}{j}", node, tap, length=distance - at, diameter=bore)
        _idle(c, f"{name}{j}", tap, idle, initial)
        taps[distance], node, at = tap, tap, distance
    return taps


def build(spec: PipingSpec, design: str, commanded) -> Circuit:
    """The circuit of a design with the actuators in ``commanded`` switched on at t = 0
    (nodes ``act0`` … ``act{N-1}``); ``demux`` takes one actuator."""
    from ..engine.circuit import Circuit
    from ..physics.waveforms import Step

    design, lo, hi = _design(design), spec.ambient, spec.p_supply
    commanded = set(commanded)
    c = Circuit(f"piping {design}, N={spec.actuators}", ambient=lo)
    c.pressure_source("PS", "source", hi)
    initial: dict[str, float] = {}
    if design == "individual":
        for k in range(spec.actuators):
            c.pressure_source(f"PC{k}", f"c{k}", Step(hi, lo) if k in commanded else hi)
            c.valve(f"X{k}", "source", f"v{k}", f"c{k}", model=spec.valve)
            c.tube(f"T{k}", f"v{k}", f"act{k}", length=spec.distance(k),
                   diameter=spec.power.bore)
            c.volume(f"A{k}", f"act{k}", V=spec.volume)
        return c
    distances = [spec.distance(k) for k in range(spec.actuators)]
    supply = _trunk(c, "TS", "source", 0.0, distances, spec.supply.bore, hi, initial)
    if design == "supply+control":
        for k in range(spec.actuators):
            c.pressure_source(f"PC{k}", f"c{k}", Step(hi, lo) if k in commanded else hi)
            c.tube(f"TC{k}", f"c{k}", f"ctl{k}", length=distances[k],
                   diameter=spec.control.bore)
            _idle(c, f"TC{k}", f"ctl{k}", hi, initial)
            c.valve(f"X{k}", supply[distances[k]], f"act{k}", f"ctl{k}", model=spec.valve)
            c.volume(f"A{k}", f"act{k}", V=spec.volume)
    else:
        if len(commanded) != 1:
            raise ParameterError("a demultiplexer fills one actuator at a time")
        _demux(c, spec, commanded.pop(), supply, initial)
    for node, pressure in initial.items():
        c.set_initial(node, pressure)
    return c


def _demux(c, spec: PipingSpec, target: int, supply: dict, initial: dict) -> None:
    """Address lines, inverters and valve chains of the ``demux`` design; the address
    switches at t = 0 from the complement of ``target`` (every line changes) to ``target``.
    Line a0_i is low when bit i is 0, its inverted copy a1_i (from an inverter at the
    nearest actuator) low when bit i is 1.  ``supply``: the supply line's taps."""
    from ..physics.waveforms import Step

    lo, hi, bits = spec.ambient, spec.p_supply, spec.bits
    before = (2 ** bits - 1) ^ target
    distances = [spec.distance(k) for k in range(spec.actuators)]
    near = min(distances)

    def bit(x, i):
        return (x >> i) & 1
    lines = {}
    for i in range(bits):
        was, now = (hi, lo) if bit(before, i) else (lo, hi)
        c.pressure_source(f"PA{i}", f"s{i}", Step(was, now))
        a0 = _trunk(c, f"TA{i}", f"s{i}", 0.0, distances, spec.control.bore, was, initial)
        inverted = lo if was == hi else hi
        a1 = _trunk(c, f"TB{i}", f"a1_{i}", near, distances, spec.control.bore, inverted,
                    initial)
        c.valve(f"XI{i}", supply[near], f"a1_{i}", a0[near], model=spec.valve)
        c.resistor(f"RI{i}", f"a1_{i}", "atm", R=INVERTER_PULL_DOWN)
        c.volume(f"VI{i}", f"a1_{i}", V=INVERTER_VOLUME)
        initial[f"a1_{i}"] = inverted
        lines[0, i], lines[1, i] = a0, a1
    for k in range(spec.actuators):
        node, passing = supply[distances[k]], True
        for i in range(bits):
            after = f"act{k}" if i == bits - 1 else f"n{k}_{i}"
            c.valve(f"X{k}_{i}", node, after, lines[bit(k, i), i][distances[k]],
                    model=spec.valve)
            if i < bits - 1:
                c.volume(f"VN{k}_{i}", after, V=CHAIN_VOLUME)
            passing = passing and bit(k, i) == bit(before, i)
            initial[after] = hi if passing else lo   # the addressed cell is already full
            node = after
        c.volume(f"A{k}", f"act{k}", V=spec.volume)


# -- fill times ----------------------------------------------------------------------------
def crossing(t, p, level: float, falling: bool = False) -> float:
    """First time (s) ``p`` reaches ``level`` (rising, or falling), linear between samples;
    NaN if it never does."""
    i = np.flatnonzero(p <= level if falling else p >= level)
    if not i.size:
        return np.nan
    if i[0] == 0:
        return float(t[0])
    j = slice(i[0] - 1, i[0] + 1)
    return float(np.interp(level, p[j][::-1], t[j][::-1]) if falling else
                 np.interp(level, p[j], t[j]))


def _run(spec: PipingSpec, design: str, commanded, record: int):
    """Fill times of ``commanded`` and the trace (t s, p kPa) of actuator ``record``."""
    sol = build(spec, design, commanded).tran(spec.t_stop, t_step=1e-3)
    times = np.array([crossing(sol.t, sol.pressure(f"act{k}"), spec.filled) for k in commanded])
    return times, (sol.t, sol.pressure(f"act{record}"))


@dataclass(repr=False)
class DesignResult(Summarized):
    """One design: its lines, cross-sections (mm²), fill times (s) and a fill trace."""

    design: str
    lines: list
    outer_mm2: float
    bore_mm2: float
    alone_s: np.ndarray          # per actuator, commanded alone
    all_s: float                 # every actuator filled (demux: one after the other)
    trace: tuple = field(default=(), compare=False)   # (t, p) of actuator 0 filled alone

    def _summary(self):
        return self.design, [("outer", number(self.outer_mm2, "mm²")),
                             ("alone", number(float(np.nanmax(self.alone_s)), "s")),
                             ("all", number(self.all_s, "s"))], ".alone_s, .all_s, .trace"


def evaluate(spec: PipingSpec, design: str) -> DesignResult:
    """Cross-sections and simulated fill times of one design (see module doc)."""
    n = spec.actuators
    alike = design != "demux" and len(set(spec.positions)) <= 1  # one run stands for all
    runs = [_run(spec, design, [k], k) for k in range(1 if alike else n)]
    alone = np.array([r[0][0] for r in runs] * (n if alike else 1))
    trace = runs[0][1]
    if design == "demux":
        total = float(alone.sum())
    else:
        total = float(np.max(_run(spec, design, range(n), 0)[0])) if n > 1 else float(alone[0])
    return DesignResult(design, [(r, k, asdict(t)) for r, k, t in lines(spec, design)],
                        cross_section(spec, design, "outer"), cross_section(spec, design, "bore"),
                        alone, total, trace)


@dataclass(repr=False)
class PipingStudy(Summarized):
    """The designs compared: ``table`` (pandas), ``results`` by design, ``as_dict()``."""

    spec: PipingSpec
    results: dict

    def _summary(self):
        rows = [(d, f"{number(r.outer_mm2, 'mm²')}, fills in "
                    f"{number(float(np.nanmax(r.alone_s)), 's')}") for d, r in self.results.items()]
        return f"N={self.spec.actuators}", rows, ".table, .as_dict(), plot_piping(study)"

    @property
    def table(self):
        """One row per design: lines, cross-sections and saving against ``individual``
        (%), fill times (s) of the fastest and the slowest actuator alone, and of all."""
        import pandas as pd

        base = {w: cross_section(self.spec, "individual", w) for w in ("outer", "bore")}
        return pd.DataFrame([{
            "design": d, "lines": sum(k for _, k, _ in r.lines),
            "outer_mm2": r.outer_mm2, "saving_outer_pct": 100 * (1 - r.outer_mm2 / base["outer"]),
            "bore_mm2": r.bore_mm2, "saving_bore_pct": 100 * (1 - r.bore_mm2 / base["bore"]),
            "fill_alone_min_s": float(np.nanmin(r.alone_s)),
            "fill_alone_max_s": float(np.nanmax(r.alone_s)), "fill_all_s": r.all_s,
        } for d, r in self.results.items()]).set_index("design")

    def as_dict(self) -> dict:
        """Plain data for JSON: the spec, the table and each actuator's fill time."""
        spec = asdict(self.spec)
        return {"spec": spec, "table": self.table.reset_index().to_dict(orient="records"),
                "fill_alone_s": {d: r.alone_s.tolist() for d, r in self.results.items()}}


def piping_study(spec: PipingSpec | None = None, designs=DESIGNS) -> PipingStudy:
    """Evaluate ``designs`` for ``spec`` (default: :class:`PipingSpec`, Fig. 1B)."""
    spec = spec or PipingSpec()
    designs = [_design(d) for d in designs]
    if "demux" in designs and spec.actuators < 2:
        raise ParameterError("a demultiplexer needs at least 2 actuators")
    return PipingStudy(spec, {d: evaluate(spec, d) for d in designs})


def with_sizes(spec: PipingSpec, **sizes) -> PipingSpec:
    """``spec`` with tube sizes given as 'bore/outer' mm strings, e.g. power='2.5/4'."""
    return replace(spec, **{k: _tubing(k, v) if isinstance(v, str) else v
                            for k, v in sizes.items()})


def _tubing(name: str, text: str) -> Tubing:
    try:
        bore, outer = (float(x) for x in text.split("/"))
        return Tubing(bore, outer)
    except ValueError:
        raise ParameterError(f"{name}={text!r} is not BORE/OUTER in mm",
                             hint="e.g. 2.5/4") from None
    except ParameterError as err:
        raise ParameterError(f"{name}: {err.message}") from None


def plot_piping(study: PipingStudy, path=None):
    """Cross-sections (left), fill times (middle) and actuator 0's pressure when filled
    alone (right), one colour per design."""
    from ..common.plotting import legend_outside, pyplot, save

    plt = pyplot()
    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(13, 3.8))
    table, x = study.table, np.arange(len(study.results))
    names = list(study.results)
    ax0.bar(x - 0.2, table["outer_mm2"], 0.4, label="outer diameter", color="0.45")
    ax0.bar(x + 0.2, table["bore_mm2"], 0.4, label="bore", color="0.75")
    for xi, name, pct in zip(x, names, table["saving_outer_pct"]):
        if name == "individual":
            continue
        ax0.annotate(f"{-pct:+.0f} %", (xi - 0.2, 0), xytext=(0, 3), textcoords="offset points",
                     ha="center", fontsize="small", color="white")
    ax0.set(ylabel="tubing cross-section (mm²)", title=f"N = {study.spec.actuators} actuators")
    ax0.legend(frameon=False, fontsize="small")
    ax1.bar(x - 0.2, table["fill_alone_max_s"], 0.4, label="one actuator (slowest)")
    ax1.errorbar(x - 0.2, table["fill_alone_max_s"],
                 yerr=[table["fill_alone_max_s"] - table["fill_alone_min_s"], 0 * x],
                 fmt="none", ecolor="k", capsize=3, label="… to the fastest")
    ax1.bar(x + 0.2, table["fill_all_s"], 0.4, label="all (demux: in turn)")
    ax1.set(ylabel=f"fill time to {100 * study.spec.level:.0f} % (s)")
    ax1.legend(frameon=False, fontsize="small")
    for ax in (ax0, ax1):
        ax.set_xticks(x, names, fontsize="small")
    for name, r in study.results.items():
        ax2.plot(r.trace[0], r.trace[1], label=name)
    ax2.axhline(study.spec.filled, color="0.6", lw=0.8, ls=":")
    t_max = 1.5 * max(float(r.alone_s[0]) for r in study.results.values())
    ax2.set(xlim=(0, t_max if np.isfinite(t_max) else None), xlabel="time after command (s)",
            ylabel="actuator 0 pressure (kPa)")
    legend_outside(ax2, fontsize="small")
    fig.tight_layout()
    return save(fig, path) if path else fig


# -- one control line ----------------------------------------------------------------------
@dataclass(repr=False)
class ControlLines(Summarized):
    """How a control line delays and smooths the valve's control pressure: ``table`` (one
    row per length: times in s after the command at the source), ``traces`` {length mm:
    (t s, control pressure at the valve kPa, actuator pressure kPa)}."""

    spec: PipingSpec
    table: object
    traces: dict

    def _summary(self):
        rows = [(f"{length:g} mm", number(row.ctrl_50_s, "s") + " to half")
                for length, row in self.table.iterrows()]
        return f"{self.spec.control.bore:g} mm bore", rows, ".table, .traces, plot_control_lines"


def control_line_delays(spec: PipingSpec | None = None, lengths=(500.0, 1000.0, 2000.0, 4000.0)
                        ) -> ControlLines:
    """One actuator of the ``supply+control`` design opened through control lines of each
    length (mm; the supply line as long): the times (s) its control pressure at the valve
    takes to fall 10, 50 and 90 % of the way from the supply to ambient, the time the
    actuator starts to rise (1 kPa) and its fill time."""
    import pandas as pd

    spec = replace(spec or PipingSpec(), actuators=1)
    rows, traces = [], {}
    hi, lo = spec.p_supply, spec.ambient
    for length in lengths:
        one = replace(spec, length=float(length))
        sol = build(one, "supply+control", [0]).tran(spec.t_stop, t_step=1e-4)
        ctl, act = sol.pressure("ctl0"), sol.pressure("act0")
        rows.append({"length_mm": float(length),
                     **{f"ctrl_{k}_s": crossing(sol.t, ctl, hi - k / 100 * (hi - lo), True)
                        for k in (10, 50, 90)},
                     "actuator_moves_s": crossing(sol.t, act, lo + 1.0),
                     "fill_s": crossing(sol.t, act, one.filled)})
        traces[float(length)] = (sol.t, ctl, act)
    return ControlLines(spec, pd.DataFrame(rows).set_index("length_mm"), traces)


def plot_control_lines(result: ControlLines, path=None):
    """Control pressure at the valve (left) and actuator pressure (right) against time
    after the command, one line per control-line length."""
    from ..common.plotting import legend_outside, pyplot, save

    fig, (ax0, ax1) = pyplot().subplots(1, 2, figsize=(11, 3.8))
    t_max = 1.3 * float(np.nanmax(result.table["fill_s"]))
    for length, (t, ctl, act) in result.traces.items():
        line, = ax0.plot(t, ctl, label=f"{length / 1000:g} m")
        ax1.plot(t, act, color=line.get_color(), label=f"{length / 1000:g} m")
    ax0.set(xlim=(0, 0.5 * t_max), xlabel="time after command (s)",
            ylabel="control pressure at the valve (kPa)",
            title=f"control line {result.spec.control.bore:g} mm bore")
    ax1.axhline(result.spec.filled, color="0.6", lw=0.8, ls=":")
    ax1.set(xlim=(0, t_max), xlabel="time after command (s)", ylabel="actuator pressure (kPa)")
    legend_outside(ax1, title="line length", fontsize="small")
    fig.tight_layout()
    return save(fig, path) if path else fig
