"""Elastic volumes: gas in a volume that grows with its pressure, V(p), isothermal.

The mass stored is m = ρ(p)·V(p) with ρ = p·M/(R·T), so the capacitance is

    C(p) = dm/dp = (M/(R·T)) · (V(p) + p·V'(p))            [mg/kPa]

(ρ·dV/dp plus V·dρ/dp).  In a liquid circuit (density ρ, bulk modulus K; see
:mod:`pneunet.physics.liquids`) the wall compliance adds to the liquid's: C = ρ·(V/K + dV/dp).  ``accumulator``: V = V0 + k·(p − pref), valid while V > 0.
``pv_volume`` (aliases ``pv_actuator``, ``free_actuator``: the data-driven actuator, a pouch
or bellows, FONSim's FreeActuator): V(p) from a table of (p, V) points (a measured curve;
V must not decrease), interpolated by a monotone cubic (scipy's PchipInterpolator, C¹) and
continued linearly with its end slopes outside the table.  A table whose pressures are not
monotone but whose volumes increase (a balloon that snaps through) is p(V) instead, with the
volume as the state: the part ``pv_volume_state`` (:mod:`pneunet.physics.elements.pv_state`).
Signal ``volume_<name>`` is the volume, mL.
"""
from __future__ import annotations

from abc import abstractmethod

import numpy as np

from ...common.errors import ParameterError
from .base import ElementSpec, Param, register
from .cubic_tables import CubicTables
from .volumes import StorageNode

_P0 = Param("pressure", "initial absolute pressure, kPa (default: ambient)", low=0.0,
            low_inclusive=False, default=np.nan, typical=(20.0, 5000.0))


class _ElasticVolume(StorageNode):
    """A volume V(p) at one node; subclasses give :meth:`volume` with two derivatives."""

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._rho_per_p = context.gas.capacitance(1.0, context.options.temperature)  # mg/(kPa·mL)
        self._liquid = context.options.liquid

    @abstractmethod
    def volume(self, p):
        """V (mL), dV/dp (mL/kPa) and d²V/dp² of each instance at pressures p (..., n)."""

    def capacitance(self, p):
        v, dv, d2v = self.volume(p)
        if self._liquid is not None:  # C = ρ·(V/K + dV/dp)
            rho, k = self._liquid.density, self._liquid.bulk_modulus
            return rho * (v / k + dv), rho * (dv / k + d2v)
        return self._rho_per_p * (v + p * dv), self._rho_per_p * (2.0 * dv + p * d2v)

    def signals(self, t, p):
        return {"volume": ("mL", self.volume(p[..., 0])[0])}


@register
class Accumulator(_ElasticVolume):
    """Linear elastic volume V = V0 + k·(p − pref)."""

    kind = "accumulator"
    description = "elastic volume V = V0 + k·(p − pref) (isothermal gas)"
    params = {
        "V0": Param("volume", "volume at pref, mL", low=0.0, low_inclusive=False),
        "k": Param("compliance", "compliance dV/dp, mL/kPa", low=0.0),
        "pref": Param("pressure", "absolute pressure where V = V0, kPa (default: ambient)",
                      low=0.0, low_inclusive=False, default=np.nan),
        "p0": _P0,
    }

    def __init__(self, specs, context):
        super().__init__(specs, context)
        pref = self.column("pref")
        self._pref = np.where(np.isnan(pref), context.options.ambient, pref)
        self._v0, self._k = self.column("V0"), self.column("k")
        p0 = self.column("p0")
        start = np.where(np.isnan(p0), context.options.ambient, p0)
        for spec, p, v in zip(specs, start, self.volume(start)[0]):
            if v <= 0:
                raise ParameterError(f"the volume V0 + k·(p − pref) is {v:g} mL at the initial "
                                     f"pressure {p:g} kPa", where=spec.where,
                                     hint="it must be > 0: raise V0, or lower k or pref")

    def volume(self, p):
        return self._v0 + self._k * (p - self._pref), self._k + 0.0 * p, 0.0 * p


@register
class PressureVolumeCurve(_ElasticVolume):
    """Elastic volume whose V(p) is a table of measured points (monotone cubic)."""

    kind = "pv_volume"
    aliases = ("pv_actuator", "free_actuator")
    description = ("pressure–volume actuator (pouch, bellows): elastic volume from a table "
                   "of measured points (CSV p_kPa,V_mL; PCHIP)")
    table_slots = ("pressure", "volume")
    params = {
        "table": Param("volume", "(p kPa, V mL) points, or a CSV file with columns "
                       "<p>_<unit>,<V>_<unit>", kind="table"),
        "p0": _P0,
        "V0": Param("volume", "initial volume, mL, of a table whose pressure is not monotone "
                    "(default: the smallest volume at p0)", low=0.0, low_inclusive=False,
                    default=np.nan),
    }

    @classmethod
    def check_spec(cls, spec):
        p, v = (np.asarray(x, dtype=float) for x in spec.params["table"])
        problem = ("needs at least two points" if p.ndim != 1 or p.shape != v.shape or p.size < 2
                   else "holds a value that is not finite" if not np.all(np.isfinite([p, v]))
                   else f"volumes must be > 0: V = {v[0]:g} mL at {p[0]:g} kPa" if v[0] <= 0
                   else None)
        if problem is None and not np.all(np.diff(p) > 0):  # p(V): volumes must increase
            problem = _first_fault(p, np.diff(v) <= 0, "pressures or volumes must increase", v)
        elif problem is None:
            problem = _first_fault(p, np.diff(v) < 0, "volumes must not decrease", v)
        if problem:
            raise ParameterError(f"the pressure–volume table {problem}", where=spec.where,
                                 hint="a table of (p kPa, V mL) points, p increasing; or V "
                                      "increasing, p free (a balloon's curve)")
        if not np.isnan(spec.params["V0"]) and np.all(np.diff(p) > 0):
            raise ParameterError("V0 chooses the branch of a table whose pressure is not "
                                 "monotone; this table's is", where=spec.where,
                                 hint="give the initial pressure p0 instead")
        spec.params["table"] = (p, v)

    @classmethod
    def expand(cls, spec):
        """Itself for a monotone V(p); the volume-state part ``pv_volume_state`` (internal
        node ``NAME.V``) when the pressures are not monotone."""
        if np.all(np.diff(spec.params["table"][0]) > 0):
            return [spec]
        return [ElementSpec("pv_volume_state", spec.name, (spec.nodes[0], f"{spec.name}.V"),
                            dict(spec.params), spec.span)]

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._curves = CubicTables([spec.params["table"] for spec in specs])

    def volume(self, p):
        return self._curves(p)


def _first_fault(p, bad, rule, v=None):
    """``rule`` and the first pair of points that breaks it (kPa, mL), or None."""
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    show = (lambda k: f"{v[k]:g} mL at {p[k]:g} kPa") if v is not None else \
        (lambda k: f"{p[k]:g} kPa")
    return f"{rule} from point to point: point {i + 2} ({show(i + 1)}) after {show(i)}"
