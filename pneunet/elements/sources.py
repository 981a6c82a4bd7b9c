"""Sources: pressure sources (pin a node's absolute pressure) and mass-flow sources."""
from __future__ import annotations

import numpy as np

from . import register
from .base import ElementFamily, Param


def _waveform_times(family, method, t_start, t_stop):
    times = [getattr(s.params["value"], method)(t_start, t_stop) for s in family.specs]
    return np.unique(np.concatenate(times)) if times else np.empty(0)


@register
class PressureSource(ElementFamily):
    """Imposes an absolute pressure (kPa), constant or a waveform, at its node."""

    kind = "pressure_source"
    aliases = ("psource", "P")
    description = "pressure source: pins the absolute pressure of a node"
    ports = ("node",)
    pinned_ports = (0,)
    params = {"value": Param("pressure", "absolute pressure or waveform, kPa", low=0.0,
                             low_inclusive=False, kind="waveform")}

    def pinned_pressure(self, t):
        return np.array([[s.params["value"].value(t)] for s in self.specs], dtype=float)

    def jumps(self, t_start, t_stop):
        return _waveform_times(self, "jumps", t_start, t_stop)

    def breakpoints(self, t_start, t_stop):
        return _waveform_times(self, "breakpoints", t_start, t_stop)


@register
class FlowSource(ElementFamily):
    """Drives a mass flow (mg/s, constant or a waveform) from node ``a`` to node ``b``."""

    kind = "flow_source"
    aliases = ("fsource", "F")
    description = "mass-flow source from node a to node b"
    ports = ("a", "b")
    params = {"value": Param("flow", "mass flow a→b or waveform, mg/s", kind="waveform")}

    def _flow(self, t):
        return np.array([s.params["value"].value(t) for s in self.specs], dtype=float)

    def outflows(self, t, p, pdot):
        q = self._flow(t)
        return np.stack([q, -q], axis=1), np.zeros((self.n, 2, 2)), None

    def jumps(self, t_start, t_stop):
        return _waveform_times(self, "jumps", t_start, t_stop)

    def breakpoints(self, t_start, t_stop):
        return _waveform_times(self, "breakpoints", t_start, t_stop)

    def signals(self, t, p):
        flows = np.array([[s.params["value"].value(ti) for s in self.specs] for ti in t])
        return {"mdot": ("mg/s", flows.reshape(len(t), self.n))}
