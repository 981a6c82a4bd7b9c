"""A rigid volume with a gas energy balance and finite wall heat transfer.

The form of Simscape Gas' constant-volume chamber and Modelica's fluid volumes: ideal
gas of heat-capacity ratio γ in a rigid volume V whose walls stay at the circuit's
temperature T_w, heat flowing to the gas as Q = hA·(T_w − T) with the wall conductance

    hA = m_ref·c_v/τ · (m/m_ref)^s,      m_ref = p_ref·V·M/(R·T_w)

τ is the gas' thermal time constant at the reference state (s; τ → 0 isothermal, τ → ∞
adiabatic).  ``scaling`` s = 0 (default) is the constant conductance of Simscape Gas'
chamber and Modelica's volumes; s = 1 a conductance proportional to the gas mass
(the same τ at every pressure).  The volume is filled and
emptied through its one port; the gas entering carries the enthalpy of the circuit
(T_w: flow through restrictions is isenthalpic), the gas leaving the volume's own:

    mass     q = d/dt (p·V / (R·T))                                  [mg/s into the volume]
    energy   V·ṗ/(γ − 1) = c_p·T_up·q + m·c_v·(T_w − T)/τ,   T_up = T_w if q ≥ 0 else T

This one-port form is exact when the volume has one line (an actuator at the end of its
tube).  A vessel filled through one line while it empties through another (a tank
between a valve and a vent) needs the enthalpy of each line on its own: use
``thermal_chamber`` with one ``thermal_inlet`` per line (below).

The gas temperature is a second unknown, carried at the element's second node (port
``heat``) as the pressure-like θ = p_ref·T/T_w (kPa; p_ref = p0, or ambient), so it
starts at θ = p_ref (T = T_w) and the assembler treats it like any storage node.
Eliminating the mass derivative, the flow at the gas node depends on ṗ alone:

    s = C·ṗ − H,   H = C·(p/θ)^s·(p_ref − θ)/τ,   q = s/γ (s ≥ 0)   or   q = s·T_w/(γ·T) (s < 0)

with C = M·V/(R·T_w) (mg/kPa) and m/m_ref = p/θ; the ``heat`` node's residual is the mass balance
q − C·(p_ref/θ)·(ṗ − p·θ̇/θ) = 0 (mg/s).  Signal ``T_<name>`` is the gas temperature, K.
"""
from __future__ import annotations

import numpy as np

from .base import FEW_INSTANCES, ElementFamily, Param, register


def _gas_terms(u, w, ud, wd, c, pr, tau, sc, ratio, partials):
    """Wall heat H and mass storage M of the gas (u = p, w = θ, rates ud, wd; C, p_ref,
    τ, s; ``ratio`` = (u/w)^s), and with ``partials`` H by (u, w) and M by (u, w, u̇,
    ẇ): on arrays or on Python floats with the same operations, so the same bits."""
    heat = c * ratio * (pr - w) / tau
    cp = c * pr
    w2 = w * w
    mass = cp * (ud / w - u * wd / w2)
    if not partials:
        return heat, mass, None, None
    d_heat = (sc * heat / u, -c * ratio / tau - sc * heat / w)
    d_mass = (-cp * wd / w2, cp * (-ud / w2 + 2 * u * wd / (w2 * w)), cp / w, -cp * u / w2)
    return heat, mass, d_heat, d_mass


@register
class ThermalVolume(ElementFamily):
    """Rigid volume with gas energy balance (ports: gas node, internal temperature node)."""

    kind = "thermal_volume"
    aliases = ("VT",)
    description = "rigid gas volume with energy balance and wall heat transfer (time constant)"
    ports = ("node", "heat")
    storage_ports = (0, 1)
    params = {
        "V": Param("volume", "volume, mL", low=0.0, low_inclusive=False),
        "tau": Param("time", "thermal time constant of the gas, s (0+ isothermal, large "
                     "adiabatic)", low=0.0, low_inclusive=False),
        "gamma": Param("dimensionless", "heat-capacity ratio c_p/c_v (default: the gas's, "
                       "1.4 for air)", low=1.0, high=1.67, default=np.nan, low_inclusive=False),
        "scaling": Param("dimensionless", "exponent s of the gas mass in the wall "
                         "conductance: 0 constant hA (Simscape, Modelica), 1 constant τ",
                         low=0.0, high=1.0, default=0.0),
        "p0": Param("pressure", "initial absolute pressure, kPa (default: ambient)", low=0.0,
                    low_inclusive=False, default=np.nan, typical=(20.0, 5000.0)),
    }

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts = context.options
        self._c = context.gas.capacitance(self.column("V"), opts.temperature)
        self._tau = self.column("tau")
        self._gamma = np.where(np.isnan(self.column("gamma")), context.gas.gamma,
                               self.column("gamma"))
        self._scaling = self.column("scaling")
        p0 = self.column("p0")
        self._p_ref = np.where(np.isnan(p0), opts.ambient, p0)
        self._t_wall = opts.temperature
        # few instances of constant hA or constant τ ((u/w)^s exact): on Python floats
        self.on_floats = self.n <= FEW_INSTANCES and bool(np.all(np.isin(self._scaling, (0, 1))))
        # per instance (C, p_ref, τ, s, γ) as Python floats
        self._constants = list(zip(*(x.tolist() for x in (
            self._c, self._p_ref, self._tau, self._scaling, self._gamma))))

    def _storage(self, p, pdot, partials=False):
        """Wall heat H and mass storage M = d/dt(p·V·M/(R·T)) (mg/s, see above) of the
        gas (u = p, w = θ), and with ``partials`` their derivatives: H by (u, w), M by
        (u, w, u̇, ẇ)."""
        u, w = p[..., 0], p[..., 1]
        return _gas_terms(u, w, pdot[..., 0], pdot[..., 1], self._c, self._p_ref, self._tau,
                          self._scaling, (u / w) ** self._scaling, partials)

    def _float_terms(self, p, pdot, rows, partials):
        """Per instance ((C, p_ref, γ), w, u̇, its :func:`_gas_terms`) on Python floats."""
        for (iu, iw), (c, pr, tau, sc, g) in zip(rows, self._constants):
            u, w = p[iu], p[iw]
            terms = _gas_terms(u, w, pdot[iu], pdot[iw], c, pr, tau, sc,
                               1.0 if sc == 0.0 else u / w, partials)
            yield (c, pr, g), w, pdot[iu], terms

    def _inflow(self, p, pdot, heat):
        """s = C·ṗ − H, T_w/T_up and the mass inflow q = (T_w/T_up)·s/γ (mg/s)."""
        s = self._c * pdot[..., 0] - heat
        k = np.where(s >= 0, 1.0, self._p_ref / p[..., 1])  # T_w / T_up
        return s, k, k * s / self._gamma

    def flows(self, t, p, pdot):
        heat, mass, _, _ = self._storage(p, pdot)
        q = self._inflow(p, pdot, heat)[2]
        return np.stack([q, q - mass], axis=-1)

    def outflows(self, t, p, pdot):
        heat, mass, (dh_du, dh_dw), (dm_du, dm_dw, dm_dud, dm_dwd) = \
            self._storage(p, pdot, partials=True)
        s, k, q = self._inflow(p, pdot, heat)
        g, w = self._gamma, p[..., 1]
        # q = k·s/γ; k depends on w only where s < 0
        dk_dw = np.where(s >= 0, 0.0, -self._p_ref / (w * w))
        dq_du = -k * dh_du / g
        dq_dw = (-k * dh_dw + dk_dw * s) / g
        dq_dud = k * self._c / g
        n = self.n
        dq_dp = np.zeros((n, 2, 2))
        dq_dpdot = np.zeros((n, 2, 2))
        dq_dp[:, 0, 0], dq_dp[:, 0, 1] = dq_du, dq_dw
        dq_dp[:, 1, 0], dq_dp[:, 1, 1] = dq_du - dm_du, dq_dw - dm_dw
        dq_dpdot[:, 0, 0] = dq_dud
        dq_dpdot[:, 1, 0], dq_dpdot[:, 1, 1] = dq_dud - dm_dud, -dm_dwd
        return np.stack([q, q - mass], axis=-1), dq_dp, dq_dpdot

    def float_outflows(self, t, p, pdot, rows, partials):
        """:meth:`outflows` on Python floats, the same operations."""
        q_all, dq_dp, dq_dpdot = [], [] if partials else None, [] if partials else None
        for (c, pr, g), w, ud, (heat, mass, d_heat, d_mass) in self._float_terms(
                p, pdot, rows, partials):
            s = c * ud - heat
            k = 1.0 if s >= 0 else pr / w
            q = k * s / g
            q_all += (q, q - mass)
            if not partials:
                continue
            dk_dw = 0.0 if s >= 0 else -pr / (w * w)
            dq_du = -k * d_heat[0] / g
            dq_dw = (-k * d_heat[1] + dk_dw * s) / g
            dq_dud = k * c / g
            dq_dp += (dq_du, dq_dw, dq_du - d_mass[0], dq_dw - d_mass[1])
            dq_dpdot += (dq_dud, 0.0, dq_dud - d_mass[2], -d_mass[3])
        return q_all, dq_dp, dq_dpdot

    def initial_pressure(self):
        # both unknowns start at p_ref: the gas node at p0, θ at p_ref (T = T_w)
        return self.column("p0")

    def signals(self, t, p):
        return {"T": ("K", self._t_wall * p[..., 1] / self._p_ref)}


@register
class ThermalChamber(ThermalVolume):
    """Rigid volume with gas energy balance, fed through ``thermal_inlet`` elements only.

    Its gas node carries the chamber's energy balance and its ``heat`` node the mass
    balance; each line reaches the chamber through a ``thermal_inlet`` that brings its
    mass flow q_k and enthalpy c_p·T_up,k·q_k (T_up,k = T_w entering, T leaving):

        gas node    C·ṗ/γ − H/γ − Σ_k (T_up,k/T_w)·q_k = 0        (energy / (c_p·T_w), mg/s)
        heat node   Σ_k q_k − C·(p_ref/θ)·(ṗ − p·θ̇/θ) = 0           (mass, mg/s)

    with C, H, θ and p_ref as for ``thermal_volume``.  This is the volume of Simscape
    Gas and Modelica with any number of ports."""

    kind = "thermal_chamber"
    aliases = ()
    description = ("rigid gas volume with energy balance and wall heat transfer, fed "
                   "through thermal_inlet elements (one per line)")

    def flows(self, t, p, pdot):
        heat, mass, _, _ = self._storage(p, pdot)
        energy = (self._c * pdot[..., 0] - heat) / self._gamma
        return np.stack([energy, -mass], axis=-1)

    def outflows(self, t, p, pdot):
        heat, mass, (dh_du, dh_dw), (dm_du, dm_dw, dm_dud, dm_dwd) = \
            self._storage(p, pdot, partials=True)
        g = self._gamma
        energy = (self._c * pdot[..., 0] - heat) / g
        n = self.n
        dq_dp = np.zeros((n, 2, 2))
        dq_dpdot = np.zeros((n, 2, 2))
        dq_dp[:, 0, 0], dq_dp[:, 0, 1] = -dh_du / g, -dh_dw / g
        dq_dp[:, 1, 0], dq_dp[:, 1, 1] = -dm_du, -dm_dw
        dq_dpdot[:, 0, 0] = self._c / g
        dq_dpdot[:, 1, 0], dq_dpdot[:, 1, 1] = -dm_dud, -dm_dwd
        return np.stack([energy, -mass], axis=-1), dq_dp, dq_dpdot

    def float_outflows(self, t, p, pdot, rows, partials):
        """:meth:`outflows` on Python floats, the same operations."""
        q_all, dq_dp, dq_dpdot = [], [] if partials else None, [] if partials else None
        for (c, _, g), _, ud, (heat, mass, d_heat, d_mass) in self._float_terms(
                p, pdot, rows, partials):
            q_all += ((c * ud - heat) / g, -mass)
            if partials:
                dq_dp += (-d_heat[0] / g, -d_heat[1] / g, -d_mass[0], -d_mass[1])
                dq_dpdot += (c / g, 0.0, -d_mass[2], -d_mass[3])
        return q_all, dq_dp, dq_dpdot


@register
class ThermalInlet(ElementFamily):
    """One line into a ``thermal_chamber`` (ports: line node, chamber gas node, chamber
    heat node).

    A stiff linear link q = (p_line − p_gas)/r (mg/s into the chamber; r small enough
    that the drop is negligible) that delivers the line's mass flow to the chamber's
    mass balance and its enthalpy, T_up/T_w·q with T_up = T_w when entering and the
    gas temperature T = T_w·θ/p_ref when leaving, to its energy balance.  ``p0`` must
    be the chamber's (it fixes θ's reference p_ref)."""

    kind = "thermal_inlet"
    aliases = ()
    description = "one line into a thermal_chamber: mass and enthalpy of the flow"
    ports = ("line", "node", "heat")
    link_ports = (0, 1)
    params = {
        "r": Param("resistance", "link resistance, kPa·s/mg (small)", low=0.0,
                   low_inclusive=False, default=1e-5),
        "p0": Param("pressure", "the chamber's p0, kPa (default: ambient)", low=0.0,
                    low_inclusive=False, default=np.nan, typical=(20.0, 5000.0)),
    }

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._r = self.column("r")
        p0 = self.column("p0")
        self._p_ref = np.where(np.isnan(p0), context.options.ambient, p0)
        self.on_floats = self.n <= FEW_INSTANCES
        self._constants = list(zip(self._r.tolist(), self._p_ref.tolist()))  # (r, p_ref)

    def _terms(self, p):
        q = (p[..., 0] - p[..., 1]) / self._r
        k = np.where(q >= 0, 1.0, p[..., 2] / self._p_ref)  # T_up / T_w
        return q, k

    def flows(self, t, p, pdot):
        q, k = self._terms(p)
        return np.stack([q, -k * q, q], axis=-1)

    def outflows(self, t, p, pdot):
        q, k = self._terms(p)
        g = 1.0 / self._r
        n = self.n
        dq_dp = np.zeros((n, 3, 3))
        dq_dp[:, 0, 0], dq_dp[:, 0, 1] = g, -g
        dq_dp[:, 1, 0], dq_dp[:, 1, 1] = -k * g, k * g
        dq_dp[:, 1, 2] = -np.where(q >= 0, 0.0, q / self._p_ref)
        dq_dp[:, 2, 0], dq_dp[:, 2, 1] = g, -g
        return np.stack([q, -k * q, q], axis=-1), dq_dp, None

    def float_outflows(self, t, p, pdot, rows, partials):
        """:meth:`outflows` on Python floats, the same operations."""
        q_all, dq_dp = [], [] if partials else None
        for (il, ig, ih), (r, pr) in zip(rows, self._constants):
            q = (p[il] - p[ig]) / r
            k = 1.0 if q >= 0 else p[ih] / pr
            q_all += (q, -k * q, q)
            if partials:
                g = 1.0 / r
                dq_dp += (g, -g, 0.0, -k * g, k * g, -(0.0 if q >= 0 else q / pr), g, -g, 0.0)
        return q_all, dq_dp, None
