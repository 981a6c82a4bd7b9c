"""Time functions for sources: constant, step, pulse, piecewise-linear, sine, any function,
and samples with slopes (cubic Hermite between them).

Each waveform gives ``value(t)`` (vectorised) in the unit of the source it drives
(kPa for pressure sources, mg/s for flow sources), its ``breakpoints`` (times at
which the value or its slope jumps; the transient solver stops there), and
``netlist()``, the text that writes it back in a netlist.
SPICE users will recognise PULSE(V1 V2 TD TR TF PW PER), PWL(t1 v1 t2 v2 …) and
SIN(VO VA FREQ TD THETA PHASE).
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..common.errors import ParameterError


class Waveform(ABC):
    """Base class: subclasses implement ``value`` and ``netlist`` (and, where the
    waveform has corners, ``breakpoints`` and ``jumps``)."""

    @abstractmethod
    def value(self, t):
        """Value at time(s) ``t`` (s), in the unit of the driven source."""

    def breakpoints(self, t_start: float, t_stop: float) -> np.ndarray:
        """Times in (t_start, t_stop) where the waveform or its slope jumps."""
        return np.empty(0)

    def jumps(self, t_start: float, t_stop: float) -> np.ndarray:
        """The subset of breakpoints where the value itself is discontinuous."""
        return np.empty(0)

    def corner_count(self, t_start: float, t_stop: float) -> float:
        """How many breakpoints (at most) lie in (t_start, t_stop), counted without
        making them: a periodic waveform's count is checked before it is allocated."""
        return len(self.breakpoints(t_start, t_stop))

    @abstractmethod
    def netlist(self) -> str:
        """The netlist text that writes this waveform back."""


def _fmt(x: float) -> str:
    return f"{x:.10g}"


@dataclass(frozen=True)
class Constant(Waveform):
    level: float

    def value(self, t):
        return np.full(np.shape(t), float(self.level)) if np.ndim(t) else float(self.level)

    def netlist(self) -> str:
        return _fmt(self.level)


@dataclass(frozen=True)
class Step(Waveform):
    """``initial`` until ``at``, then a linear ramp of duration ``rise`` to ``final``."""

    initial: float
    final: float
    at: float = 0.0
    rise: float = 0.0

    def __post_init__(self):
        if self.rise < 0:
            raise ParameterError(f"STEP rise time must be >= 0 s, got {self.rise}")

    def value(self, t):
        t = np.asarray(t, dtype=float)
        if self.rise > 0:
            frac = np.clip((t - self.at) / self.rise, 0.0, 1.0)
        else:
            frac = (t >= self.at).astype(float)
        out = self.initial + (self.final - self.initial) * frac
        return out if out.ndim else float(out)

    def breakpoints(self, t_start, t_stop):
        pts = np.array([self.at, self.at + self.rise]) if self.rise > 0 else np.array([self.at])
        return _inside(pts, t_start, t_stop)

    def jumps(self, t_start, t_stop):
        return np.empty(0) if self.rise > 0 else _inside(np.array([self.at]), t_start, t_stop)

    def netlist(self) -> str:
        return f"STEP({_fmt(self.initial)} {_fmt(self.final)} {_fmt(self.at)} {_fmt(self.rise)})"


_TINY_S = 1e-300  # turns ramps of zero length into steps without dividing by zero


class PulseTable:
    """The timing of one or many PULSEs (floats or arrays, s), prepared once.

    :meth:`fraction` evaluates all of them at a time, or at an array of times,
    elementwise: rising for ``rise``, high for ``width``, falling for ``fall``,
    repeated every ``period`` (0: once); a ramp of zero length is a step.
    """

    def __init__(self, delay, rise, width, fall, period):
        rise, width, fall, period = (np.asarray(x, dtype=float)
                                     for x in (rise, width, fall, period))
        self._delay = np.asarray(delay, dtype=float)
        self._periodic = period > 0
        self._period = np.where(self._periodic, period, 1.0)
        self._step_up = np.where(rise > 0, 0.0, _TINY_S)
        self._rise = rise + self._step_up
        self._end = rise + width + fall
        self._fall = np.where(fall > 0, fall, _TINY_S)
        self._steps = bool(np.any(rise == 0) or np.any(fall == 0))  # ramps divided by _TINY_S
        self._rows = list(zip(*(x.reshape(-1).tolist() for x in np.broadcast_arrays(
            self._delay, self._periodic, self._period, self._step_up, self._rise, self._end,
            self._fall))))

    def fraction_at(self, t: float) -> list[float]:
        """:meth:`fraction` of each pulse at one finite time ``t`` (s), on Python floats: the
        same operations, so the same bits, without numpy's cost per call (~1 µs a pulse,
        not ~6 µs for all: IDA asks at every new time)."""
        out = []
        for delay, periodic, period, step_up, rise, end, fall in self._rows:
            tau = t - delay
            if periodic and tau >= 0:
                tau = math.fmod(tau, period)
            out.append(max(min((tau + step_up) / rise, (end - tau) / fall, 1.0), 0.0))
        return out

    def fraction(self, t):
        """Fraction 0…1 of each pulse's swing at time ``t`` (s)."""
        tau = t - self._delay  # time since the start of the current cycle
        tau = np.where(self._periodic & (tau >= 0), np.fmod(tau, self._period), tau)
        if not self._steps:
            return self._clip(tau)
        with np.errstate(over="ignore"):
            return self._clip(tau)

    def _clip(self, tau):
        up = (tau + self._step_up) / self._rise
        down = (self._end - tau) / self._fall
        return np.maximum(np.minimum(np.minimum(up, down), 1.0), 0.0)


@dataclass(frozen=True)
class Pulse(Waveform):
    """SPICE PULSE: ``low`` → ``high`` after ``delay``, ramps ``rise``/``fall``,
    held ``width``, repeated every ``period`` (0: once)."""

    low: float
    high: float
    delay: float = 0.0
    rise: float = 0.0
    fall: float = 0.0
    width: float = np.inf
    period: float = 0.0

    def __post_init__(self):
        for key in ("delay", "rise", "fall", "width", "period"):
            if getattr(self, key) < 0:
                raise ParameterError(f"PULSE {key} must be >= 0 s, got {getattr(self, key)}")
        if self.period and self.period < self.rise + self.width + self.fall:
            raise ParameterError(
                f"PULSE period {self.period} s is shorter than rise + width + fall "
                f"({self.rise + self.width + self.fall} s)")

    @cached_property
    def _table(self) -> PulseTable:
        return PulseTable(self.delay, self.rise, self.width, self.fall, self.period)

    def value(self, t):
        frac = self._table.fraction(np.asarray(t, dtype=float))
        out = self.low + (self.high - self.low) * frac
        return out if out.ndim else float(out)

    def _corners(self, t_start, t_stop):
        """Corner times of the periods that reach into [t_start, t_stop] (s): from the
        period before t_start's, not from 0 (a wall-clock time of 1.7e9 s is 1.7e8
        periods of 10 s)."""
        offsets = np.array([0.0, self.rise, self.rise + self.width,
                            self.rise + self.width + self.fall])
        offsets = offsets[np.isfinite(offsets)]
        if self.period > 0:
            first = max(math.floor((t_start - self.delay) / self.period) - 1, 0)
            n = int(np.ceil(max(t_stop - self.delay, 0.0) / self.period)) + 1
            starts = self.delay + self.period * np.arange(first, max(n, first))
        else:
            starts = np.array([self.delay])
        return starts[:, None] + offsets[None, :]

    def breakpoints(self, t_start, t_stop):
        return _inside(np.unique(self._corners(t_start, t_stop).ravel()), t_start, t_stop)

    def corner_count(self, t_start, t_stop):
        if not self.period > 0:
            return 4.0
        return 4.0 * (np.ceil(max(t_stop - max(self.delay, t_start), 0.0) / self.period) + 2)

    def jumps(self, t_start, t_stop):
        corners = self._corners(t_start, t_stop)
        keep = []
        if self.rise == 0:
            keep.append(corners[:, 0])
        if self.fall == 0 and corners.shape[1] > 2:
            keep.append(corners[:, 2])
        if not keep:
            return np.empty(0)
        return _inside(np.unique(np.concatenate(keep)), t_start, t_stop)

    def netlist(self) -> str:
        vals = [self.low, self.high, self.delay, self.rise, self.fall, self.width, self.period]
        if not np.isfinite(self.width):
            vals = vals[:5]
        return "PULSE(" + " ".join(_fmt(v) for v in vals) + ")"


@dataclass(frozen=True)
class PiecewiseLinear(Waveform):
    """SPICE PWL: linear interpolation between (time, value) corners, held at the ends."""

    times: tuple
    values: tuple

    def __post_init__(self):
        t = np.asarray(self.times, dtype=float)
        if len(t) == 0 or len(t) != len(self.values):
            raise ParameterError("PWL needs pairs of time and value")
        if np.any(np.diff(t) < 0):
            raise ParameterError("PWL times must not decrease",
                                 hint="write corners in time order: PWL(0 96 1 200 …)")

    def value(self, t):
        out = np.interp(np.asarray(t, dtype=float), self.times, self.values)
        return out if np.ndim(out) else float(out)

    def breakpoints(self, t_start, t_stop):
        return _inside(np.unique(np.asarray(self.times, dtype=float)), t_start, t_stop)

    def jumps(self, t_start, t_stop):
        t = np.asarray(self.times, dtype=float)
        repeated = t[1:][np.diff(t) == 0]
        return _inside(np.unique(repeated), t_start, t_stop)

    def netlist(self) -> str:
        return "PWL(" + " ".join(f"{_fmt(a)} {_fmt(b)}" for a, b in zip(self.times, self.values)) + ")"


@dataclass(frozen=True)
class Sine(Waveform):
    """SPICE SIN: offset + amplitude·sin(2π f (t−delay) + phase)·exp(−damping (t−delay)),
    offset before ``delay``; ``phase`` in degrees."""

    offset: float
    amplitude: float
    frequency: float
    delay: float = 0.0
    damping: float = 0.0
    phase: float = 0.0

    def __post_init__(self):
        if self.frequency < 0:
            raise ParameterError(f"SIN frequency must be >= 0 Hz, got {self.frequency}")

    def value(self, t):
        tau = np.asarray(t, dtype=float) - self.delay
        wave = self.amplitude * np.sin(2 * np.pi * self.frequency * tau + np.radians(self.phase))
        wave = wave * np.exp(-self.damping * np.maximum(tau, 0.0))
        pre = self.amplitude * np.sin(np.radians(self.phase))
        out = self.offset + np.where(tau >= 0, wave, pre)
        return out if out.ndim else float(out)

    def breakpoints(self, t_start, t_stop):
        return _inside(np.array([self.delay]), t_start, t_stop) if self.delay > 0 else np.empty(0)

    def netlist(self) -> str:
        vals = [self.offset, self.amplitude, self.frequency, self.delay, self.damping, self.phase]
        return "SIN(" + " ".join(_fmt(v) for v in vals) + ")"


class Function(Waveform):
    """Any Python function of time ``f(t)`` (t in s, a float) returning the source's value
    in internal units (kPa absolute, mg/s).  Its corners are unknown to the solver unless
    given: ``breakpoints`` (times where the value or its slope jumps; the solver steps onto
    them) and ``jumps`` (those where the value jumps; the solver restarts there).  Without
    them a fast change between two steps can be stepped over: give the corners, or bound
    the step with the option ``max_step``."""

    def __init__(self, function, breakpoints=(), jumps=()):
        if not callable(function):
            raise ParameterError(f"a function source needs a callable, got {function!r}")
        self.function = function
        self._breakpoints = np.unique(np.asarray([*breakpoints, *jumps], dtype=float))
        self._jumps = np.unique(np.asarray(jumps, dtype=float))

    def __repr__(self):
        return f"Function({getattr(self.function, '__name__', self.function)!r})"

    def _one(self, t):
        try:
            value = self.function(float(t))
        except Exception as err:  # noqa: BLE001 - any error of the user's function
            raise ParameterError(f"function source {self!r} raised {type(err).__name__} at "
                                 f"t={t:g} s: {err}") from err
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"function source {self!r} returned {value!r} at t={t:g} s, "
                                 "not a number") from None
        if not np.isfinite(value):
            raise ParameterError(f"function source {self!r} returned {value} at t={t:g} s")
        return value

    def value(self, t):
        if not np.ndim(t):
            return self._one(t)
        t = np.asarray(t, dtype=float)
        return np.array([self._one(x) for x in t.ravel()]).reshape(t.shape)

    def breakpoints(self, t_start, t_stop):
        return _inside(self._breakpoints, t_start, t_stop)

    def jumps(self, t_start, t_stop):
        return _inside(self._jumps, t_start, t_stop)

    def netlist(self) -> str:
        raise ParameterError(f"function source {self!r} cannot be written as netlist text",
                             hint="sample it into a PWL, or a CSV read by PWL(FILE=...)")


def _hermite_coefficients(times, values, slopes):
    """(y_k, d_k, c2, c3) of the cubics y = y_k + d_k·τ + c2·τ² + c3·τ³ (τ = t − t_k)
    through the values and slopes at consecutive times (rows); a zero-length interval
    (a repeated time) gets finite coefficients that are never evaluated."""
    h = np.diff(times).reshape((-1,) + (1,) * (values.ndim - 1))
    h = np.where(h > 0, h, 1.0)
    dy = (values[1:] - values[:-1]) / h
    return (values[:-1], slopes[:-1], (3 * dy - 2 * slopes[:-1] - slopes[1:]) / h,
            (slopes[:-1] + slopes[1:] - 2 * dy) / (h * h))


def _horner(c, tau):
    """c[..., 0] + c[..., 1]·τ + c[..., 2]·τ² + c[..., 3]·τ³."""
    return c[..., 0] + tau * (c[..., 1] + tau * (c[..., 2] + tau * c[..., 3]))


class SampleTable:
    """c signals known with their slopes at shared, increasing sample times (m,):
    between two samples the cubic Hermite through both values and both slopes (C¹).
    A time may repeat once (a corner): the earlier row ends the interval before it,
    the later one starts the interval after it."""

    def __init__(self, times, values, slopes):
        self.times = np.asarray(times, dtype=float)
        values, slopes = (np.asarray(a, dtype=float).reshape(self.times.size, -1)
                          for a in (values, slopes))
        # (m − 1, c, 4): the cubic's coefficients per interval and signal, one gather a call
        self._packed = np.stack(_hermite_coefficients(self.times, values, slopes), axis=-1)
        self._last = self.times.size - 2

    def _interval(self, t):
        k = np.minimum(np.maximum(np.searchsorted(self.times, t, side="right") - 1, 0),
                       self._last)  # (np.clip costs more than the search)
        return k, t - self.times[k]

    def value(self, t):
        """Values (t.size, c) of every signal at the times ``t`` (s)."""
        return _horner(*self._cubics(t))

    def slope(self, t):
        """Slopes (t.size, c) of every signal at the times ``t`` (s), per s."""
        c, tau = self._cubics(t)
        return c[..., 1] + tau * (2 * c[..., 2] + 3 * tau * c[..., 3])

    def _cubics(self, t):
        k, tau = self._interval(np.asarray(t, dtype=float))
        return self._packed[k], tau[:, None]

    def at(self, t, columns):
        """Value of signal ``columns[i]`` at time ``t[i]`` (s), arrays of one shape."""
        k, tau = self._interval(np.asarray(t, dtype=float))
        return _horner(self._packed[k, columns], tau)


class Sampled(Waveform):
    """Signal ``column`` of a :class:`SampleTable`: a waveform computed elsewhere (the
    hub of a multirate transient), with the ``corners`` (s) where its slope jumps.
    Sources that share a table are evaluated together."""

    def __init__(self, table: SampleTable, column: int, corners=()):
        self.table, self.column = table, int(column)
        self._corners = np.unique(np.asarray(corners, dtype=float))

    def __repr__(self):
        return f"Sampled(column {self.column} of {self.table.times.size} samples)"

    def value(self, t):
        t = np.asarray(t, dtype=float)
        out = self.table.at(t.ravel(), np.full(t.size, self.column)).reshape(t.shape)
        return out if out.ndim else float(out)

    def breakpoints(self, t_start, t_stop):
        return _inside(self._corners, t_start, t_stop)

    def netlist(self) -> str:
        raise ParameterError(f"{self!r} cannot be written as netlist text",
                             hint="sample it into a PWL")


def _inside(points, t_start, t_stop):
    points = np.asarray(points, dtype=float)
    return points[(points > t_start) & (points < t_stop)]


def as_waveform(value) -> Waveform:
    """A number becomes a :class:`Constant`, a function of time a :class:`Function`; a
    waveform is returned as is."""
    if isinstance(value, Waveform):
        return value
    if callable(value):
        return Function(value)
    try:
        return Constant(float(value))
    except (TypeError, ValueError):
        raise ParameterError(f"a source value must be a number or a waveform, got {value!r}") from None
