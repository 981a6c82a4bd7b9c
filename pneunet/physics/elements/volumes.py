"""Volumes that store gas: rigid volumes (isothermal or polytropic) and actuators.

In a liquid circuit (``.options fluid=water``) a rigid volume stores liquid compressed
with bulk modulus K: C = ρ·V/K (mg/kPa), constant.

Mass in a volume V at pressure p, compressed polytropically with exponent n from
a reference state (p_ref, T) where p_ref is its initial pressure:

    m(p) = (M·V / (R·T)) · p_ref · (p/p_ref)^(1/n)
    C(p) = dm/dp = (M·V / (n·R·T)) · (p/p_ref)^(1/n − 1)       [mg/kPa]

n = 1 is isothermal (C = M·V/(R·T), the paper's eq. 29); n = 1.4 adiabatic air.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ...common.errors import ParameterError
from .base import FEW_INSTANCES, ElementFamily, Param, register


class StorageNode(ElementFamily, ABC):
    """Mass stored at one node through a capacitance: outflow C(p)·ṗ (subclasses give
    :meth:`capacitance`) and an initial pressure ``p0``."""

    ports = ("node",)
    storage_ports = (0,)
    fluids = ("gas", "liquid")

    @abstractmethod
    def capacitance(self, p):
        """C(p) in mg/kPa and dC/dp, for pressures p (..., n)."""

    def outflows(self, t, p, pdot):
        c, dc = self.capacitance(p[:, 0])  # c (n,), dc (n,) or 0
        rate = pdot[:, 0]
        return (c * rate)[:, None], (dc * rate).reshape(self.n, 1, 1), c.reshape(self.n, 1, 1)

    def flows(self, t, p, pdot):
        return self.capacitance(p[..., 0])[0][..., None] * pdot

    def initial_pressure(self):
        return self.column("p0")


@register
class Volume(StorageNode):
    """A rigid volume at one node: outflow C(p)·ṗ stores mass."""

    kind = "volume"
    aliases = ("V", "C")
    description = "rigid gas volume (isothermal or polytropic)"
    params = {
        "V": Param("volume", "volume, mL", low=0.0, low_inclusive=False),
        "n": Param("dimensionless", "polytropic exponent (1 isothermal, 1.4 adiabatic air)",
                   low=1.0, high=1.4, default=1.0),
        "p0": Param("pressure", "initial absolute pressure, kPa (default: ambient)", low=0.0,
                    low_inclusive=False, default=np.nan, typical=(20.0, 5000.0)),
    }

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts = context.options
        self._n = self.column("n")
        self._c0 = context.gas.capacitance(self.volume(), opts.temperature) / self._n
        p0 = self.column("p0")
        self._p_ref = np.where(np.isnan(p0), opts.ambient, p0)
        self._isothermal = bool(np.all(self._n == 1.0))
        if opts.liquid is not None:  # C = ρ·V/K, constant (n does not apply)
            self._c0 = opts.liquid.density * self.volume() / opts.liquid.bulk_modulus
            self._isothermal = True
        self._c0_floats = self._c0.tolist()
        self._p_ref_floats, self._n_floats = self._p_ref.tolist(), self._n.tolist()
        self.on_floats = self.n <= FEW_INSTANCES

    def volume(self) -> np.ndarray:
        """Volume of each instance, mL."""
        return self.column("V")

    def capacitance(self, p):
        """C(p) in mg/kPa and dC/dp."""
        if self._isothermal:
            return self._c0, 0.0
        ratio = np.maximum(p / self._p_ref, 1e-6)
        expo = 1.0 / self._n - 1.0
        c = self._c0 * ratio ** expo
        return c, c * expo / (ratio * self._p_ref)

    def _float_capacitance(self, p):
        """:meth:`capacitance` on Python floats: lists of C(p) and dC/dp.  Python's
        power, not numpy's on an array (which uses SIMD code on some processors): equal
        to the vectorised path within a few units in the last place, at a sixth of the
        cost of building arrays for a few volumes."""
        c, dc = [], []
        for pi, c0, p_ref, n in zip(p, self._c0_floats, self._p_ref_floats, self._n_floats):
            ratio = max(pi / p_ref, 1e-6)
            expo = 1.0 / n - 1.0
            ci = c0 * ratio ** expo
            c.append(ci)
            dc.append(ci * expo / (ratio * p_ref))
        return c, dc

    def float_outflows(self, t, p, pdot, rows, partials):
        if self._isothermal:
            c, dc = self._c0_floats, None
        else:
            c, dc = self._float_capacitance([p[i] for i, in rows])
        rates = [pdot[i] for i, in rows]
        q = [ci * rate for ci, rate in zip(c, rates)]
        if not partials:
            return q, None, None
        dq_dp = [0.0] * len(rates) if dc is None else [d * rate for d, rate in zip(dc, rates)]
        return q, dq_dp, list(c)


@register
class Actuator(Volume):
    """McKibben actuator as a gas volume: V given, or a cylinder of length × diameter.

    The volume is fixed for now; a pressure-dependent volume V(p) and a load
    would override :meth:`volume` and :meth:`capacitance`.
    """

    kind = "actuator"
    aliases = ("A",)
    description = "McKibben actuator (fixed volume, or cylinder length × diameter)"
    params = {
        "V": Param("volume", "volume, mL (or give length and diameter)", low=0.0,
                   low_inclusive=False, default=np.nan),
        "length": Param("length", "length of the cylinder, mm", low=0.0, low_inclusive=False,
                        default=np.nan, typical=(5.0, 3000.0)),
        "diameter": Param("length", "diameter of the cylinder, mm", low=0.0,
                          low_inclusive=False, default=np.nan, typical=(1.0, 300.0)),
        "n": Volume.params["n"],
        "p0": Volume.params["p0"],
    }

    @classmethod
    def check_spec(cls, spec):
        p = spec.params
        has_v = not np.isnan(p["V"])
        has_cyl = not (np.isnan(p["length"]) or np.isnan(p["diameter"]))
        if has_v == has_cyl:
            raise ParameterError("an actuator needs either V or both length and diameter",
                                 where=spec.where, hint="e.g. V=54mL, or length=173mm diameter=20mm")

    def volume(self):
        v = self.column("V")
        cyl = np.pi / 4 * self.column("diameter") ** 2 * self.column("length") * 1e-3
        return np.where(np.isnan(v), cyl, v)
