"""McKibben actuator (issue 12): a braided muscle whose gas volume changes as it contracts
under its mechanical load.

Geometry and the ideal model of Chou & Hannaford (1996, "Measurement and modeling of
McKibben pneumatic artificial muscles", IEEE Trans. Robot. Autom. 12(1):90–102): a thread
of length b wound n times around the bladder; at length L the braid angle θ has
cos θ = L/b and the diameter is D = b·sin θ/(n·π).  From the relaxed length L0, diameter
D0 and braid angle θ0: b = L0/cos θ0, n = b·sin θ0/(π·D0).  With x = L0 − L the
contraction (mm) and p_g = p − ambient:

    V(x) = L·(b² − L²)/(4π·n²)                         [mm³ = 1e-3 mL]
    F(p, x) = −p_g·dV/dL = p_g·(3L² − b²)/(4π·n²)      [kPa·mm² = 1e-3 N]

F pulls the ends together; it vanishes at L = b/√3 (θ = 54.7°): the largest contraction.
End effects (``k_end`` = k > 1) after Tondu & Lopez (2000, "Modeling and control of
McKibben artificial muscle robot actuators", IEEE Control Syst. Mag. 20(2):15–38, eq. 3):
F = π·r0²·p_g·[a·(1 − k·ε)² − c], a = 3/tan²θ0, c = 1/sin²θ0, ε = x/L0, which is F above
at the effective length L0 − k·x; the volume stays V(x).

The load pulls the muscle longer: weight m·g (g = 9.81 m/s²), ``preload``, ``spring``·x;
``damping`` resists the motion.  Two stiff end stops (:data:`STOP_STIFFNESS`, smooth over
:data:`STOP_WIDTH`) keep x within [0, x_max]: at x ≈ 0 the muscle hangs at its stretch
limit (a load it cannot lift), x_max = (L0 − b/√3)/k.  Net force towards contraction:

    G(p, x) = F(p, x) − m·g − preload − spring·x + stops(x)      [N]

The gas at port ``a`` stores m = ρ(p)·V(x), so it takes q = ρ1·(V·ṗ + p·dV/dx·ẋ) (mg/s,
ρ1 = M/(R·T)).  ``mckibben`` expands into one part by its load: ``mckibben_static``
(no mass, no damping: G = 0 is algebraic at the internal node ``NAME.x``, and ẋ =
−(∂G/∂p)/(∂G/∂x)·ṗ), ``mckibben_damped`` (damping·ẋ = G) or ``mckibben_inertial``
(m·v̇ = G − damping·v, ẋ = v, velocity at ``NAME.v``).  Internal nodes carry
ambient + x (mm) and ambient + v/:data:`VELOCITY_SCALE` (v in mm/s): pressure-like
positive unknowns, left out of the solution's pressures (``state_ports``).
Signals: ``contraction_<name>`` (mm), ``force_<name>`` (N, F), ``volume_<name>`` (mL).
"""
from __future__ import annotations

import warnings

import numpy as np

from ...common.solver_messages import SolverWarning
from ...common.errors import ParameterError
from .base import ElementFamily, ElementSpec, Param, register

GRAVITY = 9.81             # m/s²
MAGIC_ANGLE_DEG = np.degrees(np.arccos(1.0 / np.sqrt(3.0)))  # 54.7°: no force at all
STOP_STIFFNESS = 1000.0    # N/mm, end stops at no and full contraction (damped: see parts)
STOP_WIDTH = 0.03          # mm over which a stop engages (softplus)
VELOCITY_SCALE = 100.0     # mm/s per kPa of the velocity node


def _expit(x):
    """The logistic function 1/(1 + e^−x): scipy's ``expit``, imported on first use (a
    run without a muscle need not import scipy.special: ~30 ms)."""
    from scipy.special import expit

    return expit(x)


class LoadWarning(SolverWarning):
    """A muscle that never lifted its load in a run (a ``warning:`` line like the
    integrator's; ``-q`` silences it)."""


def geometry(params: dict) -> tuple[float, float]:
    """Thread length b (mm) and turns n of a muscle from its parameters (see module)."""
    if np.isnan(params["theta0"]):
        return params["b"], params["n"]
    theta = np.radians(params["theta0"])
    b = params["L0"] / np.cos(theta)
    return b, b * np.sin(theta) / (np.pi * params["D0"])


def _check(spec: ElementSpec) -> None:
    """One of (D0, theta0) or (b, n), a braid that can contract, a muscle that is not
    slack: else ParameterError."""
    p = spec.params
    given = {k for k in ("D0", "theta0", "b", "n") if not np.isnan(p[k])}
    by_angle, by_thread = given == {"D0", "theta0"}, given == {"b", "n"}
    if not (by_angle or by_thread):
        raise ParameterError("a mckibben needs its braid as D0 and theta0, or as b and n",
                             where=spec.where,
                             hint="e.g. L0=530mm D0=12mm theta0=25deg, or L0=530mm b=585mm n=6.6")
    if by_angle and not 0.0 < p["theta0"] < MAGIC_ANGLE_DEG:
        raise ParameterError(
            f"theta0={p['theta0']:g}° is no braid angle that contracts: at "
            f"{MAGIC_ANGLE_DEG:.1f}° and above the pressure gives no contraction force",
            where=spec.where, hint="relaxed braid angles are 15–35°; theta0 must lie in "
                                   f"(0, {MAGIC_ANGLE_DEG:.1f})°")
    if by_thread and not p["b"] * np.cos(np.radians(MAGIC_ANGLE_DEG)) < p["L0"] < p["b"]:
        raise ParameterError(
            f"thread length b={p['b']:g} mm cannot be wound on L0={p['L0']:g} mm: cos θ0 = "
            f"L0/b = {p['L0'] / p['b']:.3g} must lie in (1/√3, 1)", where=spec.where,
            hint="b > L0 (the thread is longer than the muscle) and b < √3·L0 (θ0 < 54.7°)")
    if _part_kind(p) == "mckibben_static" and p["spring"] == 0 and p["preload"] == 0:
        raise ParameterError("a mckibben with no mass, damping, spring or preload is slack: "
                             "at ambient pressure any length balances, so none is defined",
                             where=spec.where, hint="hang a mass (mass=200g), or give a "
                                                    "spring, a preload or damping")


_PARAMS = {
    "L0": Param("length", "relaxed length, mm", low=0.0, low_inclusive=False,
                typical=(20.0, 3000.0)),
    "D0": Param("length", "relaxed diameter, mm (with theta0)", low=0.0,
                low_inclusive=False, default=np.nan, typical=(2.0, 100.0)),
    "theta0": Param("angle", "relaxed braid angle to the axis, degrees, in (0, 54.7)",
                    low=0.0, high=90.0, low_inclusive=False, default=np.nan,
                    typical=(10.0, 50.0), plausible=(5.0, 54.7)),
    "b": Param("length", "thread length, mm (with n; instead of D0 and theta0)", low=0.0,
               low_inclusive=False, default=np.nan, typical=(20.0, 5000.0)),
    "n": Param("dimensionless", "turns of a thread around the muscle (with b)", low=0.0,
               low_inclusive=False, default=np.nan),
    "k_end": Param("dimensionless", "Tondu–Lopez end-effect factor k (1: ideal "
                   "Chou–Hannaford; above 1 a shorter stroke)", low=1.0, high=3.0,
                   default=1.0),
    "mass": Param("mass", "mass hanging on the muscle, kg (gravity extends it)", low=0.0,
                  default=0.0, typical=(1e-3, 50.0), plausible=(1e-6, 1e4)),
    "spring": Param("stiffness", "spring resisting contraction, N/m", low=0.0, default=0.0,
                    typical=(1.0, 1e6)),
    "damping": Param("damping", "viscous damping of the motion, N·s/m", low=0.0, default=0.0),
    "preload": Param("force", "constant force extending the muscle, N", default=0.0),
}


class _Muscle(ElementFamily):
    checks_run = True
    """The physics shared by the parts (see module docstring); ports a, x[, v]."""

    params = _PARAMS
    description = "McKibben muscle part (made by mckibben)"
    flow_ports = (0,)
    state_ports = (1, 2)

    @classmethod
    def check_spec(cls, spec):
        _check(spec)
        wanted = _part_kind(spec.params)
        if cls.kind != wanted:
            raise ParameterError(f"{cls.kind} does not fit this load (it is a {wanted})",
                                 where=spec.where, hint="write mckibben: it picks its part")

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts = context.options
        b, n = np.array([geometry(s.params) for s in specs]).T
        self._b2, self._c = b * b, 1e-3 / (4.0 * np.pi * n * n)  # c: mL/mm³ = N/(kPa·mm²)
        self._l0, self._k = self.column("L0"), self.column("k_end")
        self._x_max = (self._l0 - b / np.sqrt(3.0)) / self._k
        self._load = GRAVITY * self.column("mass") + self.column("preload")  # N
        self._spring = 1e-3 * self.column("spring")                          # N/mm
        self._damp = 1e-3 * self.column("damping")                           # N·s/mm
        self._mass = 1e-3 * self.column("mass")                             # N·s²/mm
        self._amb = opts.ambient
        self._rho1 = context.gas.capacitance(1.0, opts.temperature)  # mg/(kPa·mL)

    # -- laws of one state (x mm, p kPa), arrays of any shape ending in n -------------
    def held(self, x):
        """x held smoothly within [0, x_max] (softplus over STOP_WIDTH; beyond the stops
        the laws stay at their ends) and its first two derivatives."""
        w = STOP_WIDTH
        above, s_above = w * np.logaddexp(0.0, x / w), _expit(x / w)        # ≈ max(x, 0)
        u = (self._x_max - above) / w
        s_below = _expit(u)
        held = self._x_max - w * np.logaddexp(0.0, u)                       # ≈ min(·, x_max)
        slope = s_below * s_above
        bend = (s_below * s_above * (1 - s_above)
                - s_above ** 2 * s_below * (1 - s_below)) / w
        return held, slope, bend

    def volume(self, x):
        """V (mL), dV/dx (mL/mm) and d²V/dx² at contraction x (mm)."""
        held, slope, bend = self.held(x)
        length = self._l0 - held
        v_h = self._c * (3.0 * length ** 2 - self._b2)
        return (self._c * length * (self._b2 - length ** 2), v_h * slope,
                -6.0 * self._c * length * slope ** 2 + v_h * bend)

    def _per_kpa(self, x):
        """F/p_g (N/kPa; Tondu–Lopez at k_end, Chou–Hannaford at 1) and its first two
        derivatives by x."""
        held, slope, bend = self.held(x)
        eff = self._l0 - self._k * held
        f, f_h, f_hh = (self._c * (3.0 * eff ** 2 - self._b2), -6.0 * self._c * self._k * eff,
                        6.0 * self._c * self._k ** 2)
        return f, f_h * slope, f_hh * slope ** 2 + f_h * bend

    def tension(self, p, x):
        """F (N), ∂F/∂p and ∂F/∂x."""
        f, f_x, _ = self._per_kpa(x)
        return (p - self._amb) * f, f, (p - self._amb) * f_x

    def stops(self, x):
        """Force of the end stops (N, towards contraction), its first and second
        derivatives by x, their engagement e ∈ [0, 1] and de/dx."""
        w = STOP_WIDTH
        low, high = -x / w, (x - self._x_max) / w
        s_low, s_high = _expit(low), _expit(high)
        slope_low, slope_high = s_low * (1 - s_low) / w, s_high * (1 - s_high) / w
        force = STOP_STIFFNESS * w * (np.logaddexp(0.0, low) - np.logaddexp(0.0, high))
        return (force, -STOP_STIFFNESS * (s_low + s_high),
                STOP_STIFFNESS * (slope_low - slope_high), s_low + s_high,
                slope_high - slope_low)

    def net_force(self, p, x):
        """G (N), ∂G/∂p, ∂G/∂x, ∂²G/∂x² and ∂²G/∂p∂x (see module)."""
        stops, d_stops, dd_stops, _, _ = self.stops(x)
        f, f_x, f_xx = self._per_kpa(x)
        gauge = p - self._amb
        return (gauge * f - self._load - self._spring * x + stops, f,
                gauge * f_x - self._spring + d_stops, gauge * f_xx + dd_stops, f_x)

    def _contraction(self, z):
        return z - self._amb

    # -- engine interface -----------------------------------------------------------------
    def flows(self, t, p, pdot):
        return self._terms(p, pdot, partials=False)[0]

    def outflows(self, t, p, pdot):
        return self._terms(p, pdot, partials=True)

    def _gas(self, p, x, pdot, xdot, partials):
        """Gas stored through port a with ẋ given: q = ρ1·(V·ṗ + p·V'·ẋ) and its partials
        by p, x, ṗ, ẋ."""
        v, v_x, v_xx = self.volume(x)
        r = self._rho1
        q = r * (v * pdot + p * v_x * xdot)
        if not partials:
            return q, None
        return q, (r * v_x * xdot, r * (v_x * pdot + p * v_xx * xdot), r * v, r * p * v_x)

    def signals(self, t, p):
        x = self._contraction(p[..., 1])
        force = self.tension(p[..., 0], x)[0]
        if np.ndim(t) and np.size(t) > 1:
            self._warn_unlifted(p[..., 0])
        return {"contraction": ("mm", x), "force": ("N", force),
                "volume": ("mL", self.volume(x)[0])}

    def _warn_unlifted(self, p):
        """A run in which the highest pressure cannot pull the load off the stop."""
        top = p.max(axis=0)
        most = self.tension(top, 0.0)[0]
        for k in np.flatnonzero(self._load > most):
            warnings.warn(LoadWarning(
                f"{self.specs[k].where}: the muscle cannot lift its load of "
                f"{self._load[k]:.3g} N: at the run's highest pressure {top[k]:.4g} kPa it "
                f"pulls {max(most[k], 0.0):.3g} N at its relaxed length, so it stays at its "
                "stretch limit (contraction ≈ 0)"), stacklevel=2)


def _part_kind(params) -> str:
    if params["mass"] > 0:
        return "mckibben_inertial"
    return "mckibben_damped" if params["damping"] > 0 else "mckibben_static"


@register
class McKibben(ElementFamily):
    """McKibben muscle with its load (see module docstring); one gas port ``a``."""

    kind = "mckibben"
    description = ("McKibben muscle (Chou–Hannaford, optional Tondu–Lopez end effect) "
                   "lifting a mass against a spring and damping")
    ports = ("a",)
    params = _PARAMS

    @classmethod
    def check_spec(cls, spec):
        _check(spec)

    @classmethod
    def expand(cls, spec):
        """One part by its load, its internal nodes ``NAME.x`` (and ``NAME.v``)."""
        kind = _part_kind(spec.params)
        nodes = (spec.nodes[0], f"{spec.name}.x") + \
            ((f"{spec.name}.v",) if kind == "mckibben_inertial" else ())
        return [ElementSpec(kind, spec.name, nodes, dict(spec.params), spec.span)]


@register
class StaticMcKibben(_Muscle):
    """No mass, no damping: the force balance −G(p, x) = 0 at ``NAME.x`` is algebraic."""

    kind = "mckibben_static"
    ports = ("a", "x")
    storage_ports = (0,)
    state_ports = (1,)

    def _terms(self, p, pdot, partials):
        pa, x, pa_dot = p[..., 0], self._contraction(p[..., 1]), pdot[..., 0]
        g, g_p, g_x, g_xx, g_px = self.net_force(pa, x)
        rate = -g_p / g_x                                  # dx/dp on the balance, mm/kPa
        q, dq = self._gas(pa, x, pa_dot, rate * pa_dot, partials)
        out = np.stack([q, -g], axis=-1)  # −G rises with x, as a flow with its pressure
        if not partials:
            return out, None, None
        dq_dp, dq_dx, dq_dpd, dq_dxd = dq
        rate_p = g_p * g_px / g_x ** 2
        rate_x = -(g_px * g_x - g_p * g_xx) / g_x ** 2
        d_p = np.zeros((self.n, 2, 2))
        d_p[:, 0, 0] = dq_dp + dq_dxd * rate_p * pa_dot
        d_p[:, 0, 1] = dq_dx + dq_dxd * rate_x * pa_dot
        d_p[:, 1, 0], d_p[:, 1, 1] = -g_p, -g_x
        d_pdot = np.zeros((self.n, 2, 2))
        d_pdot[:, 0, 0] = dq_dpd + dq_dxd * rate
        return out, d_p, d_pdot


@register
class DampedMcKibben(_Muscle):
    """No mass, damping c: c·ẋ = G(p, x) at ``NAME.x``."""

    kind = "mckibben_damped"
    ports = ("a", "x")
    storage_ports = (0, 1)
    state_ports = (1,)

    def _terms(self, p, pdot, partials):
        pa, x = p[..., 0], self._contraction(p[..., 1])
        g, g_p, g_x, _, _ = self.net_force(pa, x)
        q, dq = self._gas(pa, x, pdot[..., 0], pdot[..., 1], partials)
        out = np.stack([q, self._damp * pdot[..., 1] - g], axis=-1)
        if not partials:
            return out, None, None
        d_p = np.zeros((self.n, 2, 2))
        d_p[:, 0, 0], d_p[:, 0, 1] = dq[0], dq[1]
        d_p[:, 1, 0], d_p[:, 1, 1] = -g_p, -g_x
        d_pdot = np.zeros((self.n, 2, 2))
        d_pdot[:, 0, 0], d_pdot[:, 0, 1] = dq[2], dq[3]
        d_pdot[:, 1, 1] = self._damp
        return out, d_p, d_pdot


@register
class InertialMcKibben(_Muscle):
    """Mass m: ẋ = v at ``NAME.x``, m·v̇ = G(p, x) − (c + e·c_stop)·v at ``NAME.v``, the
    stops (engaged by e) critically damped: c_stop = 2·√(STOP_STIFFNESS·m)."""

    kind = "mckibben_inertial"
    ports = ("a", "x", "v")
    storage_ports = (0, 1, 2)

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._stop_damp = 2.0 * np.sqrt(STOP_STIFFNESS * self._mass)  # N·s/mm

    def _terms(self, p, pdot, partials):
        pa, x = p[..., 0], self._contraction(p[..., 1])
        vel = VELOCITY_SCALE * (p[..., 2] - self._amb)              # mm/s
        g, g_p, g_x, _, _ = self.net_force(pa, x)
        _, _, _, engaged, d_engaged = self.stops(x)
        damp = self._damp + engaged * self._stop_damp
        q, dq = self._gas(pa, x, pdot[..., 0], pdot[..., 1], partials)
        accel = VELOCITY_SCALE * pdot[..., 2]                       # mm/s²
        out = np.stack([q, pdot[..., 1] - vel, self._mass * accel + damp * vel - g], axis=-1)
        if not partials:
            return out, None, None
        d_p = np.zeros((self.n, 3, 3))
        d_p[:, 0, 0], d_p[:, 0, 1] = dq[0], dq[1]
        d_p[:, 1, 2] = -VELOCITY_SCALE
        d_p[:, 2, 0] = -g_p
        d_p[:, 2, 1] = d_engaged * self._stop_damp * vel - g_x
        d_p[:, 2, 2] = damp * VELOCITY_SCALE
        d_pdot = np.zeros((self.n, 3, 3))
        d_pdot[:, 0, 0], d_pdot[:, 0, 1] = dq[2], dq[3]
        d_pdot[:, 1, 1] = 1.0
        d_pdot[:, 2, 2] = self._mass * VELOCITY_SCALE
        return out, d_p, d_pdot
