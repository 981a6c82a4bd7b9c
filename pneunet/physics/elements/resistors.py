"""Quadrature resistors (eq. 4): by resistance, or by pipe geometry (eq. 6)."""
from __future__ import annotations

import numpy as np

from ..gas import GAS_CONSTANT
from ..laws import Scalar, quadrature_flow
from .base import ElementFamily, FEW_INSTANCES, Param, register


def pipe_resistance(length_mm, diameter_mm, friction, temperature_k, molar_mass_g_mol):
    """Weymouth resistance R = 8·√(f·L·R·T/(π²·D⁵·M)) (eq. 6), in kPa·s/mg.

    ``friction`` is the Fanning friction factor f (Darcy λ = 4f).
    """
    length, diameter = length_mm * 1e-3, diameter_mm * 1e-3
    r_si = 8.0 * np.sqrt(friction * length * GAS_CONSTANT * temperature_k
                         / (np.pi ** 2 * diameter ** 5 * molar_mass_g_mol * 1e-3))
    return r_si * 1e-9  # Pa·s/kg -> kPa·s/mg


_OUT_IN = np.array([1.0, -1.0])  # a flow a→b leaves node a and enters node b


class _QuadratureFamily(ElementFamily):
    """Shared flow law of resistors; subclasses set ``self._r`` (kPa·s/mg) per instance."""

    ports = ("a", "b")

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self.on_floats = self.n <= FEW_INSTANCES
        self._own_rows = np.arange(2 * self.n).reshape(self.n, 2).tolist()  # p (n, 2) raveled

    def float_outflows(self, t, p, pdot, rows, partials):
        """Each instance's law on Python floats (laws.Scalar), in one loop (few of them)."""
        band = self.context.options.flow_band
        q, dq = [], [] if partials else None
        for (a, b), r in zip(rows, self._r_floats):
            m, d_a, d_b = quadrature_flow(p[a], p[b], r, band, partials, xp=Scalar)
            q += (m, -m)
            if partials:
                dq += (d_a, d_b, -d_a, -d_b)
        return q, dq, None

    def outflows(self, t, p, pdot):
        if self.n <= FEW_INSTANCES:
            q, dq, _ = self.float_outflows(t, p.ravel().tolist(), None, self._own_rows, True)
            return np.array(q).reshape(self.n, 2), np.array(dq).reshape(self.n, 2, 2), None
        mdot, d_a, d_b = quadrature_flow(p[:, 0], p[:, 1], self._r, self.context.options.flow_band)
        grad = np.empty((self.n, 1, 2))
        grad[:, 0, 0], grad[:, 0, 1] = d_a, d_b
        return mdot[:, None] * _OUT_IN, _OUT_IN[:, None] * grad, None

    def flows(self, t, p, pdot):
        if self.n <= FEW_INSTANCES and p.ndim == 2:
            q, _, _ = self.float_outflows(t, p.ravel().tolist(), None, self._own_rows, False)
            return np.array(q).reshape(self.n, 2)
        mdot, _, _ = quadrature_flow(p[..., 0], p[..., 1], self._r,
                                     self.context.options.flow_band, partials=False)
        return mdot[..., None] * _OUT_IN

    def signals(self, t, p):
        return {"mdot": ("mg/s", self.flows(t, p, None)[..., 0])}


@register
class Resistor(_QuadratureFamily):
    """Quadrature resistor: ṁ = √(p_a² − p_b²)/R, both directions."""

    kind = "resistor"
    aliases = ("R",)
    description = "quadrature resistor ṁ = √(p_a² − p_b²)/R"
    params = {"R": Param("resistance", "resistance, kPa·s/mg", low=0.0, low_inclusive=False)}

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._r = self.column("R")
        self._r_floats = self._r.tolist()


def check_line(spec) -> None:
    """A line shorter than its bore is outside every line law (fully developed flow): a
    ParameterError; such a restriction is an orifice or a resistor."""
    from ...common.errors import ParameterError

    length, diameter = spec.params["length"], spec.params["diameter"]
    if length < diameter:
        raise ParameterError(
            f"length {length:.4g} mm is shorter than the bore {diameter:.4g} mm: a line law "
            "does not hold for it", where=spec.where,
            hint="check the units (a bare number is in mm, M and m are milli, a metre is "
                 "1m or 1meter); a restriction that short is a resistor R or an orifice")


@register
class Pipe(_QuadratureFamily):
    """Tube of length L and inner diameter D with Fanning friction factor f (eq. 6)."""

    kind = "pipe"
    description = "tube resistor from length, inner diameter and friction factor (eq. 6)"
    params = {
        "length": Param("length", "tube length, mm", low=0.0, low_inclusive=False,
                        typical=(10.0, 1e5), plausible=(1.0, 1e6)),
        "diameter": Param("length", "inner diameter, mm", low=0.0, low_inclusive=False,
                          typical=(0.1, 50.0), plausible=(0.01, 500.0)),
        "f": Param("dimensionless", "Fanning friction factor (Darcy λ = 4f)", low=0.0,
                   high=1.0, low_inclusive=False, default=0.008),
    }
    check_spec = classmethod(lambda cls, spec: check_line(spec))

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts = context.options
        self._r = pipe_resistance(self.column("length"), self.column("diameter"),
                                  self.column("f"), opts.temperature, context.gas.molar_mass_g_mol)
        self._r_floats = self._r.tolist()
