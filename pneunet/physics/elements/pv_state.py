"""A pressure–volume table whose pressure is not monotone (issue 34): a balloon that snaps
through, with its volume as the state.

The table (p, V points, V increasing) gives p = P(V), a monotone cubic (PCHIP, continued
linearly outside; :mod:`pneunet.physics.elements.cubic_tables`).  The volume is carried at the
internal node ``NAME.V`` as z = ambient + V (mL), a pressure-like unknown.  The mass at the
node is m = ρ(p)·V, so the node takes

    gas:     q = ρ1·(V·ṗ + p·V̇),  ρ1 = M/(R·T)       liquid:  q = ρ·(V/K·ṗ + V̇)

and the state row holds p = P(V) differentiated, with the drift pulled back over τ = 1 µs
(a mode at −1/τ, faster than any the circuit has: the stability report's slowest mode stays
the circuit's own):

    P'(V)·V̇ − ṗ + (P(V) − p)/τ = 0                   [kPa/s]

The two rows' rates form a regular block even where P'(V) = 0 (its determinant is
ρ1·(p + V·P'), > 0 unless the pressure falls faster than p/V), so a balloon fed through a
restriction passes the top of its curve and snaps to its other branch.  Fed by a pressure
source directly, the volume would jump there: keep a restriction in front.
"""
from __future__ import annotations

import numpy as np

from ...common.errors import ParameterError
from .cubic_tables import CubicTables
from .base import ElementFamily, register
from .elastic import PressureVolumeCurve

TAU = 1e-6  # s, the pull-back of p towards P(V)


@register
class PressureVolumeState(ElementFamily):
    """``pv_volume`` with a non-monotone pressure: p = P(V), V the state at ``NAME.V``."""

    kind = "pv_volume_state"
    description = "pressure–volume actuator whose pressure is not monotone (volume as state)"
    ports = ("node", "state")  # "state": not a line in the schematic
    flow_ports = (0,)
    storage_ports = (0, 1)
    state_ports = (1,)
    fluids = ("gas", "liquid")
    params = PressureVolumeCurve.params
    table_slots = PressureVolumeCurve.table_slots

    @classmethod
    def check_spec(cls, spec):  # as pv_volume's (a printed part parses back)
        PressureVolumeCurve.check_spec(spec)

    def __init__(self, specs, context):
        super().__init__(specs, context)
        opts = context.options
        self._amb = opts.ambient
        self._curves = CubicTables([(v, p) for p, v in (s.params["table"] for s in specs)])
        liquid = opts.liquid
        self._rho1 = context.gas.capacitance(1.0, opts.temperature)  # mg/(kPa·mL)
        self._liquid = None if liquid is None else (liquid.density, liquid.bulk_modulus)
        self._v0 = np.array([self._start(s) for s in specs])

    def _start(self, spec) -> float:
        """Initial volume: V0, else the smallest volume where P(V) = p0 (default ambient)."""
        p_table, v_table = spec.params["table"]
        if not np.isnan(spec.params["V0"]):
            return float(spec.params["V0"])
        p0 = spec.params["p0"] if not np.isnan(spec.params["p0"]) else self._amb
        from scipy.interpolate import PchipInterpolator

        roots = PchipInterpolator(v_table, p_table).solve(p0, extrapolate=False)
        if roots.size:
            return float(roots.min())
        slope = PchipInterpolator(v_table, p_table).derivative()(v_table[0])
        below = v_table[0] + (p0 - p_table[0]) / slope if slope > 0 else -1.0
        if p0 < p_table[0] and below > 0:
            return float(below)
        raise ParameterError(f"the table's pressure never reaches p0 = {p0:g} kPa (from "
                             f"{p_table.min():g} to {p_table.max():g} kPa)", where=spec.where,
                             hint="give p0 within the table, or the initial volume V0")

    def initial_pressure(self):
        """(n, 2): the node at P(V0), the state node at ambient + V0."""
        return np.stack([self._curves(self._v0)[0], self._amb + self._v0], axis=1)

    def _rows(self, p, pdot, partials):
        pa, v = p[..., 0], p[..., 1] - self._amb
        pa_dot, v_dot = pdot[..., 0], pdot[..., 1]
        big_p, slope, bend = self._curves(v)
        if self._liquid is None:
            c_p, c_v = self._rho1 * v, self._rho1 * pa       # ∂q/∂ṗ, ∂q/∂V̇
            q = c_p * pa_dot + c_v * v_dot
        else:
            rho, k = self._liquid
            c_p, c_v = rho * v / k, rho + 0.0 * v
            q = c_p * pa_dot + c_v * v_dot
        state = slope * v_dot - pa_dot + (big_p - pa) / TAU
        out = np.stack([q, state], axis=-1)
        if not partials:
            return out, None, None
        d_p = np.zeros(pa.shape + (2, 2))
        d_pdot = np.zeros(pa.shape + (2, 2))
        if self._liquid is None:
            d_p[..., 0, 0], d_p[..., 0, 1] = self._rho1 * v_dot, self._rho1 * pa_dot
        else:
            d_p[..., 0, 1] = rho / k * pa_dot
        d_p[..., 1, 0], d_p[..., 1, 1] = -1.0 / TAU, bend * v_dot + slope / TAU
        d_pdot[..., 0, 0], d_pdot[..., 0, 1] = c_p, c_v
        d_pdot[..., 1, 0], d_pdot[..., 1, 1] = -1.0, slope
        return out, d_p, d_pdot

    def outflows(self, t, p, pdot):
        return self._rows(p, pdot, partials=True)

    def flows(self, t, p, pdot):
        return self._rows(p, pdot, partials=False)[0]

    def signals(self, t, p):
        return {"volume": ("mL", p[..., 1] - self._amb)}
