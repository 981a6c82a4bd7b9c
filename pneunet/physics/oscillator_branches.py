"""Stationary branches of the oscillator's valve + R_out subsystem (paper Fig. 11, eqs. 27–29).

Subsystem I (valve fed by p_H, output through R_out into node c, control port at p_c)
admits stationary pairs (p_c, ṁ) solving eq. 28::

    F(p_c, ṁ) = ṁ − G(Δp) · √(p_H² − p_out²) = 0,   p_out = √(ṁ² R_out² + p_c²)   (27)
    Δp = a_in p_H + a_out p_out − p_c

with G the valve conductance of eq. 19.  The curve is traced by pseudo-arclength
continuation from the closure point (ṁ = 0, Δp = p_close); the closed branch ṁ = 0
continues from there to p_H.  Turning points (dp_c/ds = 0, i.e. ∂F/∂ṁ = 0) are refined
by Newton on {F = 0, ∂F/∂ṁ = 0}.  Subsystem II (the vented volume, eq. 29) gives
ṗ_c ∝ ṁ − √(p_c² − p_L²)/R_vent, whose sign colours the (p_c, ṁ) plane.

Branch pieces with ∂F/∂ṁ > 0 attract the fast dynamics (a small dead volume at the
valve output relaxes onto them); the middle piece between two turning points repels.
An equilibrium (branch ∩ vent curve) is stable when it lies on an attracting piece and
d(ṁ − ṁ_vent)/dp_c < 0 there.  Without a stable equilibrium and with two turning
points the circuit oscillates between the turning points: p_c,min is the lower and
p_c,max the upper one (in the limit of vanishing dead volume).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import elements
from ..common.errors import PneunetError
from .laws import Scalar, valve_conductance
from ..common.reprs import Summarized
from .valve_params import ValveParams


@dataclass(frozen=True)
class OscillatorSpec:
    """What the branch analysis needs: supply, vent level, valve, R_out, R_vent (and V)."""

    pH: float = 496.0
    pL: float = 96.0
    Rout: float = 1.132
    Rvent: float = 3.0
    valve: ValveParams | str = "axi"
    V: float = 200.0

    @property
    def params(self) -> ValveParams:
        from .valve_params import resolve_valve_model

        return resolve_valve_model(self.valve)


@dataclass(frozen=True)
class Point:
    p_c: float
    mdot: float

    def as_dict(self):
        return {"p_c": self.p_c, "mdot": self.mdot}


@dataclass(frozen=True)
class Equilibrium:
    p_c: float
    mdot: float
    stable: bool

    def as_dict(self):
        return {"p_c": self.p_c, "mdot": self.mdot, "stable": self.stable}


@dataclass(frozen=True, repr=False)
class Branches(Summarized):
    """Result of :func:`stationary_branches`.

    ``p_c``, ``mdot``: the open curve in continuation order (from the closure point);
    ``attracting``: per point, ∂F/∂ṁ > 0; ``closed_from``: p_c from which ṁ = 0 is a
    solution; ``turning_points`` sorted by p_c; ``equilibria``; ``regime``
    ('oscillation' or 'equilibrium'); ``p_c_min``/``p_c_max`` the predicted cycle.
    """

    spec: OscillatorSpec
    p_c: np.ndarray
    mdot: np.ndarray
    attracting: np.ndarray
    closed_from: float
    turning_points: tuple
    equilibria: tuple
    regime: str
    p_c_min: float
    p_c_max: float
    steps: int = 0
    extras: dict = field(default_factory=dict)

    def _summary(self):
        s = self.spec
        rows = [("turning points", ", ".join(f"p_c {tp.p_c:.4g} kPa"
                                             for tp in self.turning_points) or "none"),
                ("equilibria", ", ".join(f"{e.p_c:.4g} kPa "
                                         f"({'stable' if e.stable else 'unstable'})"
                                         for e in self.equilibria) or "none"),
                ("predicted cycle", f"p_c {self.p_c_min:.4g}–{self.p_c_max:.4g} kPa"
                 if self.regime == "oscillation" else "none")]
        return (f"R_out={s.Rout:g}, R_vent={s.Rvent:g}: {self.regime}", rows,
                ".p_c, .mdot (the curve), .as_dict(), plot_branches(b)")

    def as_dict(self) -> dict:
        s = self.spec
        return {"pH": s.pH, "pL": s.pL, "Rout": s.Rout, "Rvent": s.Rvent,
                "valve": s.valve if isinstance(s.valve, str) else s.params.as_dict(),
                "closed_from": self.closed_from,
                "turning_points": [p.as_dict() for p in self.turning_points],
                "equilibria": [e.as_dict() for e in self.equilibria],
                "regime": self.regime, "p_c_min": self.p_c_min, "p_c_max": self.p_c_max,
                "steps": self.steps, "points": len(self.p_c)}

    def vent_flow(self, p_c):
        """ṁ leaving the volume through R_vent at p_c (mg/s)."""
        return vent_flow(p_c, self.spec.pL, self.spec.Rvent)


def vent_flow(p_c, pL, Rvent):
    p_c = np.asarray(p_c, dtype=float)
    return np.sign(p_c - pL) * np.sqrt(np.abs(p_c ** 2 - pL ** 2)) / Rvent


class _Curve:
    """F(p_c, ṁ) of eq. 28 and its partials, in scaled variables x = (p_c, ṁ)/scale."""

    def __init__(self, spec: OscillatorSpec, band: float):
        self.s = spec
        self.v = spec.params
        self.band = band

    def F(self, pc, m):
        """F (mg/s) at p_c (kPa), ṁ (mg/s): Python floats (laws.Scalar, the curve is
        traced point by point)."""
        s, v = self.s, self.v
        pc, m = float(pc), float(m)
        pout = math.sqrt(m * m * s.Rout ** 2 + pc * pc)
        dp = v.ain * s.pH + v.aout * pout - pc
        g, _ = valve_conductance(dp, v.Rf, v.pclose, v.ptrans, v.e, derivative=False, xp=Scalar)
        d = s.pH ** 2 - pout ** 2
        root = math.copysign(math.sqrt(abs(d)), d) if self.band == 0 \
            else d / (d * d + self.band ** 2) ** 0.25
        return m - g * root

    def grad(self, pc, m):
        """(∂F/∂p_c, ∂F/∂ṁ) by central differences (the law is smooth on the open curve)."""
        hp = 1e-6 * max(abs(pc), 1.0)
        hm = 1e-6 * max(abs(m), 1.0)
        fp = (self.F(pc + hp, m) - self.F(pc - hp, m)) / (2 * hp)
        fm = (self.F(pc, m + hm) - self.F(pc, m - hm)) / (2 * hm)
        return np.array([fp, fm])


def closure_pressure(spec: OscillatorSpec) -> float:
    """p_c at which the valve closes with no flow: a_in p_H + a_out p_c − p_c = p_close."""
    v = spec.params
    if v.aout >= 1:
        raise PneunetError("a_out ≥ 1: the valve never closes by its own output pressure")
    return (v.ain * spec.pH - v.pclose) / (1.0 - v.aout)


def stationary_branches(spec: OscillatorSpec | None = None, *, band: float = 0.0, ds: float = 5.0,
                        max_steps: int = 5000, p_c_low: float | None = None, **kw) -> Branches:
    """Trace the stationary curve of eq. 28 by pseudo-arclength continuation.

    ``spec`` (or keyword arguments of :class:`OscillatorSpec`) gives the circuit;
    ``band`` the zero-flow regularisation ε (kPa², 0 = exact law as in the paper);
    ``ds`` the arclength step in scaled units (kPa and mg/s);
    the curve is followed down to ``p_c_low`` (default p_L).
    """
    spec = spec or OscillatorSpec(**kw)
    curve = _Curve(spec, band)
    pc_star = closure_pressure(spec)
    if not spec.pL < pc_star < spec.pH:
        raise PneunetError(f"closure pressure {pc_star:.4g} kPa lies outside (p_L, p_H): "
                           "no open branch to trace")
    low = spec.pL if p_c_low is None else p_c_low
    scale = np.array([1.0, 1.0])
    # start a little inside the open region: ṁ from a 1-D solve at p_c slightly below p_c*
    x = np.array([pc_star, 0.0])
    tangent = np.array([-1.0, 0.0])
    pts = [x.copy()]
    steps = 0
    h = ds
    while steps < max_steps:
        steps += 1
        pred = x + h * tangent
        y, ok = _correct(curve, pred, tangent, scale)
        if not ok or np.linalg.norm(y - x) > 3 * h:
            h *= 0.5
            if h < 1e-6:
                break
            continue
        g = curve.grad(*y)
        new_t = np.array([-g[1], g[0]])
        new_t /= np.linalg.norm(new_t)
        if new_t @ tangent < 0:
            new_t = -new_t
        x, tangent = y, new_t
        pts.append(x.copy())
        h = min(ds, h * 1.5)
        if x[0] <= low or x[0] >= spec.pH or x[1] < 0:
            break
    pts = np.array(pts)
    grads = np.array([curve.grad(*p) for p in pts])
    attracting = grads[:, 1] > 0
    turning = _turning_points(curve, pts)
    equilibria = _equilibria(curve, spec, pts, attracting)
    stable = [e for e in equilibria if e.stable]
    if not stable and len(turning) >= 2:
        regime = "oscillation"
        p_min, p_max = turning[0].p_c, turning[-1].p_c
    else:
        regime = "equilibrium" if stable else "undetermined"
        p_min = p_max = stable[0].p_c if stable else float("nan")
    return Branches(spec, pts[:, 0], pts[:, 1], attracting, pc_star, tuple(turning),
                    tuple(equilibria), regime, float(p_min), float(p_max), steps)


def _correct(curve, pred, tangent, scale, tol=1e-10, iters=30):
    """Newton on {F = 0, tangent·(x − pred) = 0}."""
    y = pred.copy()
    for _ in range(iters):
        f = curve.F(*y)
        g = curve.grad(*y)
        J = np.array([g, tangent])
        r = np.array([f, tangent @ (y - pred)])
        try:
            dy = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            return y, False
        y = y + dy
        if y[1] < -1e-9:
            y[1] = 0.0
        if np.linalg.norm(dy) < tol * max(1.0, np.linalg.norm(y)):
            return y, abs(curve.F(*y)) < 1e-6
    return y, False


def _turning_points(curve, pts):
    """Turning points in p_c: sign changes of dp_c/ds, refined by Newton on {F, F_ṁ}."""
    dpc = np.diff(pts[:, 0])
    out = []
    for i in range(1, len(dpc)):
        if dpc[i - 1] * dpc[i] < 0:
            y = pts[i].copy()
            for _ in range(50):
                f = curve.F(*y)
                fm = curve.grad(*y)[1]
                h = 1e-4 * np.maximum(np.abs(y), 1.0)
                J = np.empty((2, 2))
                for k in range(2):
                    e = np.zeros(2)
                    e[k] = h[k]
                    J[0, k] = (curve.F(*(y + e)) - curve.F(*(y - e))) / (2 * h[k])
                    J[1, k] = (curve.grad(*(y + e))[1] - curve.grad(*(y - e))[1]) / (2 * h[k])
                try:
                    dy = np.linalg.solve(J, -np.array([f, fm]))
                except np.linalg.LinAlgError:
                    break
                if np.linalg.norm(dy) > 20:  # refinement wandered off: keep the bracket
                    y = pts[i].copy()
                    break
                y = y + dy
                if np.linalg.norm(dy) < 1e-9:
                    break
            out.append(Point(float(y[0]), float(y[1])))
    return sorted(out, key=lambda p: p.p_c)


def _equilibria(curve, spec, pts, attracting):
    """Intersections of the curve (and the closed branch) with the vent curve."""
    h = pts[:, 1] - vent_flow(pts[:, 0], spec.pL, spec.Rvent)
    out = []
    for i in range(len(h) - 1):
        if h[i] == 0 or h[i] * h[i + 1] < 0:
            w = h[i] / (h[i] - h[i + 1]) if h[i] != h[i + 1] else 0.0
            pc = pts[i, 0] + w * (pts[i + 1, 0] - pts[i, 0])
            m = pts[i, 1] + w * (pts[i + 1, 1] - pts[i, 1])
            pc, m = _refine_equilibrium(curve, spec, pc, m)
            # at the equilibrium itself: attracting piece (F_ṁ > 0) and
            # d(ṁ − ṁ_vent)/dp_c < 0 along the branch (dṁ/dp_c = −F_p/F_ṁ)
            fp, fm = curve.grad(pc, m)
            hv = 1e-6 * pc
            dvent = (vent_flow(pc + hv, spec.pL, spec.Rvent)
                     - vent_flow(pc - hv, spec.pL, spec.Rvent)) / (2 * hv)
            stable = bool(fm > 0 and -fp / fm - dvent < 0)
            out.append(Equilibrium(float(pc), float(m), stable))
    return out


def _refine_equilibrium(curve, spec, pc, m):
    """Newton on {F(p_c, ṁ) = 0, ṁ = ṁ_vent(p_c)}; keeps the interpolated guess on failure."""
    y = np.array([pc, m], dtype=float)
    for _ in range(30):
        g = curve.grad(*y)
        hv = 1e-6 * y[0]
        dv = (vent_flow(y[0] + hv, spec.pL, spec.Rvent) - vent_flow(y[0] - hv, spec.pL, spec.Rvent)) / (2 * hv)
        r = np.array([curve.F(*y), y[1] - vent_flow(y[0], spec.pL, spec.Rvent)])
        try:
            dy = np.linalg.solve(np.array([g, [-dv, 1.0]]), -r)
        except np.linalg.LinAlgError:
            return pc, m
        y = y + dy
        if np.linalg.norm(dy) < 1e-10 * np.linalg.norm(y):
            break
    if abs(y[0] - pc) > 5 or not np.all(np.isfinite(y)):
        return pc, m
    return y[0], y[1]


def predicted_regime(**kw) -> str:
    """'oscillation' or 'equilibrium' for an oscillator from its branches."""
    return stationary_branches(OscillatorSpec(**kw)).regime


#: element kinds that are the oscillator's volume (port 0 at the control node)
VOLUME_KINDS = ("volume", "actuator", "thermal_volume", "thermal_chamber")


def spec_from_circuit(circuit, node: str | None = None) -> OscillatorSpec:
    """Recognise the oscillator in a circuit: a valve fed by a pressure source whose
    output reaches its own control node through a resistor (or directly), the control
    node vented through a resistor to a pressure source or the ambient.  A volume with
    an energy balance counts as the volume, the line node of a link into it
    (``thermal_inlet``: ``ElementFamily.link_ports``) as its node."""
    els = circuit.elements
    chamber_of = {}
    for e in els.values():
        link = elements.family(e.kind).link_ports
        if link:
            chamber_of[e.nodes[link[0]]] = e.nodes[link[1]]

    def at(r):  # a resistor's nodes, a link into a chamber read as the chamber
        return {chamber_of.get(n, n) for n in r.nodes}

    pinned = {}
    for e in els.values():
        if e.kind == "pressure_source":
            pinned[e.nodes[0]] = float(e.params["value"].value(0.0))
    for ref in ("0", "gnd", "atm"):
        pinned.setdefault(ref, circuit.options.ambient)
    for v in els.values():
        if v.kind != "valve":
            continue
        inlet, outlet, ctrl = v.nodes
        if node is not None and ctrl != node or inlet not in pinned:
            continue
        rout = 0.0
        if outlet != ctrl:
            links = [r for r in els.values() if r.kind == "resistor" and at(r) == {outlet, ctrl}]
            if not links:
                continue
            rout = float(links[0].params["R"])
        vents = [r for r in els.values() if r.kind == "resistor" and ctrl in at(r)
                 and (at(r) - {ctrl}) & set(pinned) and at(r) != {outlet, ctrl}]
        if not vents:
            continue
        low = (at(vents[0]) - {ctrl}).pop()
        vols = [x for x in els.values() if x.kind in VOLUME_KINDS and x.nodes[0] == ctrl]
        V = float(vols[0].params["V"]) if vols else float("nan")
        return OscillatorSpec(pH=pinned[inlet], pL=pinned[low], Rout=rout,
                              Rvent=float(vents[0].params["R"]), valve=v.params["model"], V=V)
    raise PneunetError("no oscillator found: need a valve fed by a pressure source whose output "
                       "reaches its control node through a resistor, and a vent resistor from "
                       "that node to a pressure source")


def plot_branches(branches: Branches, path=None, ax=None, trajectory=None, title=None):
    """Fig. 11 style plot: the stationary curve (solid attracting, dashed repelling), the
    closed branch, ṗ_c sign regions (green > 0, red < 0), turning points, equilibria and
    the predicted cycle.  ``trajectory`` = (p_c, ṁ) arrays of a simulation to overlay."""
    from ..common.plotting import legend_outside, pyplot, save

    plt = pyplot()
    s = branches.spec
    own = ax is None
    if own:
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
    else:
        fig = ax.figure
    m_top = max(float(np.max(branches.mdot)) * 1.15, 50.0)
    pcs = np.linspace(s.pL, s.pH, 300)
    ms = np.linspace(0, m_top, 200)
    P, Mg = np.meshgrid(pcs, ms)
    sign = np.sign(Mg - vent_flow(P, s.pL, s.Rvent))
    ax.contourf(P, Mg, sign, levels=[-2, 0, 2], colors=["#f4b6b6", "#b9e4b9"], alpha=0.8)
    ax.plot(pcs, vent_flow(pcs, s.pL, s.Rvent), color="0.4", lw=0.8, ls=":",
            label="vent flow (ṗ_c = 0)")
    pc, m, att = branches.p_c, branches.mdot, branches.attracting
    # draw attracting and repelling pieces
    start = 0
    first = {True: True, False: True}
    for i in range(1, len(pc) + 1):
        if i == len(pc) or att[i] != att[start]:
            seg = slice(start, min(i + 1, len(pc)))
            a = bool(att[start])
            ax.plot(pc[seg], m[seg], color="k", lw=2 if a else 1.2, ls="-" if a else "--",
                    label=("stationary branch" if a else "repelling branch") if first[a] else None)
            first[a] = False
            start = i
    ax.plot([branches.closed_from, s.pH], [0, 0], color="k", lw=2)
    for tp in branches.turning_points:
        ax.plot(tp.p_c, tp.mdot, "o", color="tab:blue", ms=7, zorder=5)
        ax.annotate(f"{tp.p_c:.1f} kPa", (tp.p_c, tp.mdot), textcoords="offset points",
                    xytext=(6, 6), fontsize=8, color="tab:blue")
    for eq in branches.equilibria:
        ax.plot(eq.p_c, eq.mdot, "s" if eq.stable else "x", color="tab:orange", ms=8, zorder=6,
                label="stable equilibrium" if eq.stable else "unstable equilibrium")
    if branches.regime == "oscillation":
        lo, hi = branches.turning_points[0], branches.turning_points[-1]
        top = _branch_value(branches, hi.p_c, lo.p_c, upper=True)
        ax.annotate("", xy=(lo.p_c, top), xytext=(lo.p_c, lo.mdot),
                    arrowprops=dict(arrowstyle="->", color="tab:red", lw=1.5))
        ax.annotate("", xy=(hi.p_c, 0), xytext=(hi.p_c, hi.mdot),
                    arrowprops=dict(arrowstyle="->", color="tab:red", lw=1.5))
    if trajectory is not None:
        ax.plot(trajectory[0], trajectory[1], color="tab:purple", lw=0.8, alpha=0.8,
                label="simulated trajectory")
    ax.set_xlim(s.pL, s.pH)
    ax.set_ylim(-0.02 * m_top, m_top)
    ax.set_xlabel("p_c (kPa abs)")
    ax.set_ylabel("ṁ (mg/s)")
    ax.set_title(title or f"R_out = {s.Rout:g}, R_vent = {s.Rvent:g} kPa·s/mg: {branches.regime}")
    handles, labels = ax.get_legend_handles_labels()
    uniq = dict(zip(labels, handles))
    legend_outside(ax, uniq.values(), uniq.keys(), fontsize=7)
    if own and path is not None:
        return save(fig, path)
    return fig


def _branch_value(branches, lo_pc, at_pc, upper=True):
    """ṁ of the upper attracting piece at p_c = at_pc (for the jump arrow)."""
    pc, m, att = branches.p_c, branches.mdot, branches.attracting
    cand = [m[i] for i in range(len(pc) - 1) if att[i] and (pc[i] - at_pc) * (pc[i + 1] - at_pc) <= 0]
    return max(cand) if cand else float(np.max(m))
