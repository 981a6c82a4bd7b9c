"""Flow laws of liquid circuits (``.options fluid=water``): an orifice and a laminar tube.

With the liquid's density ρ (mg/mL = kg/m³) and viscosity μ (Pa·s), Δp = p_a − p_b (kPa):

* ``orifice``: ṁ = Cd·A·√(2ρ·Δp), A = π·d²/4 — turbulent, ∝ √Δp (a minor-loss factor K,
  Δp = K·ρv²/2: Cd = 1/√K);
  in mg/s with A in mm² and Δp in kPa: ṁ = Cd·A·√(2000·ρ·Δp);
* ``laminar_tube``: Hagen–Poiseuille ṁ = ρ·π·D⁴·Δp/(128·μ·L) — ∝ Δp (valid while the
  Reynolds number 4ṁ/(π·D·μ) stays below ~2000; signal ``Re_<name>``);
  in mg/s with D, L in mm: ṁ = ρ·π·D⁴·Δp/(128·μ·L).

The orifice's √ is regularised like the gas laws' (:func:`pneunet.physics.laws.signed_root`) with
the band ε = flow_band/(2·ambient) kPa: the gas band mapped through p_a² − p_b² ≈ 2p·Δp.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ...common.errors import ParameterError
from ..laws import signed_root
from .base import ElementFamily, Param, register
from . import run_checks
from .resistors import check_line

_OUT_IN = np.array([1.0, -1.0])  # a flow a→b leaves node a and enters node b
CD_SHARP = 0.61  # discharge coefficient of a sharp-edged orifice


class _LiquidLaw(ElementFamily, ABC):
    """Flow a→b from Δp = p_a − p_b; subclasses give :meth:`law` (ṁ, dṁ/dΔp)."""

    ports = ("a", "b")
    fluids = ("liquid",)

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self.liquid = context.options.liquid
        if self.liquid is None:
            raise ParameterError(f"{self.kind} {self.names[0]} needs a liquid circuit",
                                 hint=".options fluid=water (or Circuit(fluid='water'))")

    @abstractmethod
    def law(self, dp, partials):
        """Mass flow a→b (mg/s) at pressure differences dp = p_a − p_b (kPa), and
        dṁ/d(dp) (mg/(s·kPa)) when ``partials`` (else None)."""

    def outflows(self, t, p, pdot):
        mdot, slope = self.law(p[:, 0] - p[:, 1], partials=True)
        grad = np.stack([slope, -slope], axis=1)[:, None, :]
        return mdot[:, None] * _OUT_IN, _OUT_IN[:, None] * grad, None

    def flows(self, t, p, pdot):
        return self.law(p[..., 0] - p[..., 1], partials=False)[0][..., None] * _OUT_IN

    def signals(self, t, p):
        return {"mdot": ("mg/s", self.flows(t, p, None)[..., 0])}


@register
class Orifice(_LiquidLaw):
    """Sharp-edged orifice of diameter d: ṁ = Cd·A·√(2ρ·Δp)."""

    kind = "orifice"
    description = "liquid orifice ṁ = Cd·A·√(2ρΔp)"
    params = {
        "diameter": Param("length", "orifice diameter, mm", low=0.0, low_inclusive=False,
                          typical=(0.05, 50.0), plausible=(0.005, 500.0)),
        "Cd": Param("dimensionless", "discharge coefficient (0.61 sharp-edged; 1/√K for a "
                    "minor-loss factor K)", low=0.0, high=2.0, low_inclusive=False,
                    default=CD_SHARP),
        "K": Param("dimensionless", "minor-loss factor K, Δp = K·ρv²/2 with v in the bore "
                   "(FONSim's FlowRestrictor): Cd = 1/√K (default: Cd)", low=0.25,
                   high=1e6, default=np.nan),
    }

    @classmethod
    def check_spec(cls, spec):
        if not np.isnan(spec.params["K"]) and spec.params["Cd"] != CD_SHARP:
            raise ParameterError("give the orifice's Cd or its K, not both", where=spec.where,
                                 hint="Cd = 1/√K")

    def __init__(self, specs, context):
        super().__init__(specs, context)
        area = np.pi / 4 * self.column("diameter") ** 2  # mm²
        k_factor = self.column("K")
        cd = np.where(np.isnan(k_factor), self.column("Cd"), 1.0 / np.sqrt(k_factor))
        self._k = cd * area * np.sqrt(2000.0 * self.liquid.density)
        self._band = context.options.flow_band / (2.0 * context.options.ambient)

    def law(self, dp, partials):
        root, slope = signed_root(dp, self._band, derivative=partials)
        return self._k * root, (self._k * slope if partials else None)


@register
class LaminarTube(_LiquidLaw):
    checks_run = True
    """Tube of length L and inner diameter D in laminar flow (Hagen–Poiseuille)."""

    kind = "laminar_tube"
    description = "liquid laminar tube ṁ = ρπD⁴Δp/(128μL)"
    params = {
        "length": Param("length", "tube length, mm", low=0.0, low_inclusive=False,
                        typical=(10.0, 1e5), plausible=(1.0, 1e6)),
        "diameter": Param("length", "inner diameter, mm", low=0.0, low_inclusive=False,
                          typical=(0.1, 50.0), plausible=(0.01, 500.0)),
    }
    check_spec = classmethod(lambda cls, spec: check_line(spec))

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._d = self.column("diameter")
        self._g = (self.liquid.density * np.pi * self._d ** 4
                   / (128.0 * self.liquid.viscosity * self.column("length")))

    def law(self, dp, partials):
        return self._g * dp, (self._g + 0.0 * dp if partials else None)

    def signals(self, t, p):
        out = super().signals(t, p)
        # Re = ρ·v·D/μ = 4ṁ/(π·D·μ): ṁ mg/s → kg/s, D mm → m
        out["Re"] = ("1", 4e-3 * np.abs(out["mdot"][1]) / (np.pi * self._d * self.liquid.viscosity))
        if np.size(t) > 1:
            run_checks.laminar_reynolds(self.specs, t, out["Re"][1])
        return out
