"""Sources: pressure sources (pin a node's absolute pressure) and mass-flow sources."""
from __future__ import annotations

import numpy as np

from ..waveforms import Constant, Pulse, PulseTable, Sampled
from .base import ElementFamily, Param, register


def _waveform_corners(family, t_start, t_stop):
    """Each instance's waveform corners and jumps (its ``value``), s."""
    return [(w.breakpoints(t_start, t_stop), w.jumps(t_start, t_stop))
            for w in (s.params["value"] for s in family.specs)]


#: PULSE sources of a bank up to which one time is evaluated on Python floats (~1 µs a
#: pulse against ~6 µs for numpy's call over all of them; 3,000 pulses on floats cost
#: 8.1 → 12.8 s of a 3,000-cell transient)
FLOAT_PULSES = 8


class _WaveformBank:
    """Values of many waveforms at one time: PULSE and constants vectorised.

    PULSE uses the same :class:`~pneunet.physics.waveforms.PulseTable` as
    :meth:`pneunet.physics.waveforms.Pulse.value`, so results are identical; sampled
    waveforms of one table are evaluated together; others one by one.
    """

    def __init__(self, waveforms):
        self.n = len(waveforms)
        kinds = np.array([0 if type(w) is Constant else 1 if type(w) is Pulse else
                          3 if type(w) is Sampled else 2 for w in waveforms])
        self._const = np.flatnonzero(kinds == 0)
        self._level = np.array([float(waveforms[i].level) for i in self._const])
        self._pulse = np.flatnonzero(kinds == 1)
        cols = ("low", "high", "delay", "rise", "width", "fall", "period")
        p = {k: np.array([getattr(waveforms[i], k) for i in self._pulse], dtype=float)
             for k in cols}
        self._low, self._swing = p["low"], p["high"] - p["low"]
        self._table = PulseTable(*(p[k] for k in cols[2:]))
        self._other = [(i, waveforms[i]) for i in np.flatnonzero(kinds == 2)]
        tables = {}  # id(table) → (table, [instance], [column])
        for i in np.flatnonzero(kinds == 3):
            entry = tables.setdefault(id(waveforms[i].table), (waveforms[i].table, [], []))
            entry[1].append(i)
            entry[2].append(waveforms[i].column)
        self._sampled = [(table, np.array(at), np.array(cols)) for table, at, cols in
                         tables.values()]
        self.constant = not (self._pulse.size or self._other or self._sampled)
        # constants and a few PULSEs: one time on floats (value_at); the pulses' places
        # hold 0.0 in the list of levels
        self._small = not (self._other or self._sampled) and self._pulse.size <= FLOAT_PULSES
        levels = np.zeros(self.n)
        levels[self._const] = self._level
        self._levels = levels.tolist()
        self._swings = list(zip(self._pulse.tolist(), self._low.tolist(), self._swing.tolist()))

    def value_at(self, t: float) -> np.ndarray:
        """Values (n,) at one time t (s): for a small bank of constants and PULSEs on
        Python floats, the same operations as :meth:`value` (the same bits) without its
        ~8 numpy calls — IDA asks at every new time."""
        if not self._small:
            return self.value(t)
        out = self._levels.copy()
        for (i, low, swing), fraction in zip(self._swings, self._table.fraction_at(t)):
            out[i] = low + swing * fraction
        return np.array(out)

    def value(self, t):
        """Values (..., n) at time t (s): a float, or an array of times."""
        t = np.asarray(t, dtype=float)
        out = np.empty(t.shape + (self.n,))
        out[..., self._const] = self._level
        if self._pulse.size:
            fraction = (self._table.fraction_at(float(t)) if not t.ndim and
                        self._pulse.size <= FLOAT_PULSES else self._table.fraction(t[..., None]))
            out[..., self._pulse] = self._low + self._swing * fraction
        for table, at, cols in self._sampled:
            times = np.broadcast_to(t[..., None], t.shape + cols.shape)
            out[..., at] = table.at(times.ravel(), np.broadcast_to(cols, times.shape).ravel()
                                    ).reshape(times.shape)
        for i, wave in self._other:
            out[..., i] = wave.value(t)
        return out

    def value_each(self, t):
        """Value of waveform i at its own time t[i] (s), shape (n,)."""
        t = np.asarray(t, dtype=float)
        out = np.empty(self.n)
        out[self._const] = self._level
        if self._pulse.size:
            out[self._pulse] = self._low + self._swing * self._table.fraction(t[self._pulse])
        for table, at, cols in self._sampled:
            out[at] = table.at(t[at], cols)
        for i, wave in self._other:
            out[i] = wave.value(t[i])
        return out


@register
class PressureSource(ElementFamily):
    """Imposes an absolute pressure (kPa), constant or a waveform, at its node."""

    kind = "pressure_source"
    aliases = ("psource", "P")
    description = "pressure source: pins the absolute pressure of a node"
    fluids = ("gas", "liquid")
    ports = ("node",)
    pinned_ports = (0,)
    params = {"value": Param("pressure", "absolute pressure or waveform, kPa", low=0.0,
                             low_inclusive=False, kind="waveform", typical=(20.0, 5000.0),
                             plausible=(1.0, 1e5))}

    def __init__(self, specs, context):
        super().__init__(specs, context)
        self._waveforms = _WaveformBank([s.params["value"] for s in specs])
        self._last_t, self._last_value = None, None

    def pinned_pressure(self, t):
        if not isinstance(t, float) and np.ndim(t):  # (np.ndim of a float builds an array)
            return self._waveforms.value(t)[..., None]
        # IDA evaluates several times at one t: the bank once per t (constants once)
        if t != self._last_t and (self._last_value is None or not self._waveforms.constant):
            self._last_t, self._last_value = t, self._waveforms.value_at(float(t))[:, None]
        return self._last_value

    def pinned_pressure_each(self, t):
        """Pressure (n, 1) of instance i at its own time t[i] (s) (multirate cells)."""
        return self._waveforms.value_each(t)[:, None]

    def flows(self, t, p, pdot):
        return np.zeros(p.shape)

    def instance_corners(self, t_start, t_stop):
        return _waveform_corners(self, t_start, t_stop)


@register
class FlowSource(ElementFamily):
    """Drives a mass flow (mg/s, constant or a waveform) from node ``a`` to node ``b``."""

    kind = "flow_source"
    aliases = ("fsource", "F")
    description = "mass-flow source from node a to node b"
    fluids = ("gas", "liquid")
    ports = ("a", "b")
    params = {"value": Param("flow", "mass flow a→b or waveform, mg/s", kind="waveform")}

    def _flow(self, t):
        return np.array([s.params["value"].value(t) for s in self.specs], dtype=float)

    def outflows(self, t, p, pdot):
        q = self._flow(t)
        return np.stack([q, -q], axis=1), np.zeros((self.n, 2, 2)), None

    def instance_corners(self, t_start, t_stop):
        return _waveform_corners(self, t_start, t_stop)

    def signals(self, t, p):
        flows = np.array([[s.params["value"].value(ti) for s in self.specs] for ti in t])
        return {"mdot": ("mg/s", flows.reshape(len(t), self.n))}
