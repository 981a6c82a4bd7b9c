"""A circuit (+ effects) simulated at the recorded times, and synthetic recordings.

:class:`TraceModel` builds the circuit for a parameter point, adds circuit effects,
simulates with the fit's solver settings and samples the signals at given times.
:class:`TraceResidual` is the picklable residual (scaled, jump samples left out) that
a process pool evaluates in parallel.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import PneunetError

#: simulator settings of the fit's simulations: the Jacobian is taken by forward
#: differences with a step of :data:`DIFF_STEP` in ln value, so the simulator's own
#: error (rtol 1e-6: < 0.005 kPa on sampled tank pressures of the oscillator) must be
#: far below the response to a 0.5 % change (~0.5 kPa)
FIT_OPTIONS = {"rtol": 1e-6, "atol": 1e-6}
DIFF_STEP = 5e-3


class TraceModel:
    """Simulate ``build(point)`` (+ effects) and sample its signals at given times."""

    def __init__(self, build: Callable, fixed: dict | None = None, effects=(), start: str = "ic",
                 options: dict | None = None):
        self.build, self.fixed, self.effects, self.start = build, dict(fixed or {}), tuple(effects), start
        self.options = dict(options or {})
        self.calls = 0

    def circuit(self, values: dict):
        from ..analysis.sweep import apply_overrides

        point = dict(self.fixed)
        point.update({k: v for k, v in values.items() if not self._effect_param(k)})
        c = self.build(point)
        apply_overrides(c, point)
        for eff in self.effects:
            eff.apply(c, {k: values.get(k, eff.params[k][0]) for k in eff.params})
        if self.options:
            c.options = c.options.replace(**self.options)
        return c

    def _effect_param(self, name):
        return any(name in e.params for e in self.effects)

    def simulate(self, values: dict, t_end: float, t_step: float | None = None):
        self.calls += 1
        return self.circuit(values).tran(t_end, t_step=t_step, start=self.start)

    def sample(self, values: dict, times, signals):
        """({signal: samples at ``times``}, solution); output on the sample spacing."""
        dt = float(np.median(np.diff(times))) if len(times) > 1 else None
        sol = self.simulate(values, float(times[-1]), dt)
        return {s: sample_at(sol.t, sol[s], times) for s in signals}, sol


def sample_at(t, y, times):
    """``y(t)`` interpolated at ``times``; the two states a branch jump stores at one
    time are nudged apart so the abscissae increase."""
    t = np.array(t, dtype=float)
    dup = np.nonzero(np.diff(t) <= 0)[0]
    if dup.size:
        t[dup + 1] = t[dup] + 1e-12 * np.maximum(1.0, np.abs(t[dup]))
        t = np.maximum.accumulate(t)
    return np.interp(times, t, y)


class TraceResidual:
    """Scaled residual (simulated − recorded) on the compared samples, for ln-parameters
    ``x``; a failed simulation gives a large constant residual.  Picklable."""

    def __init__(self, model: TraceModel, names, times, signals, measured: dict, keep: dict,
                 scales: dict):
        self.model, self.names, self.times, self.signals = model, list(names), times, signals
        self.measured, self.keep, self.scales = measured, keep, scales
        self.failures = 0

    def size(self) -> int:
        return int(sum(self.keep[s].sum() for s in self.signals))

    def __call__(self, x):
        values = dict(zip(self.names, np.exp(x)))
        try:
            sim, _ = self.model.sample(values, self.times, self.signals)
        except PneunetError:
            self.failures += 1
            return np.full(self.size(), 1e3)
        return np.concatenate([((sim[s] - self.measured[s]) / self.scales[s])[self.keep[s]]
                               for s in self.signals])


def process_pool(workers: int | None):
    """A fork-based process pool of ``workers`` (None: up to 2, the cores shared here),
    or None for one worker."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    n = min(2, os.cpu_count() or 1) if workers is None else int(workers)
    if n < 2 or "fork" not in multiprocessing.get_all_start_methods():
        return None
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("fork"))


def synthetic_trace(build: Callable, params: dict, t_end: float, *, dt: float = 0.05,
                    signals=("p_tank", "p_out"), noise: float = 0.5, seed: int = 0,
                    options: dict | None = None):
    """A recording simulated by pneunet with known ``params`` plus white noise (kPa /
    mg/s), in the DATA-FORMAT layout (rtol 1e-7 unless ``options``)."""
    import pandas as pd

    from ..analysis.sweep import apply_overrides

    c = build(params)
    apply_overrides(c, params)
    c.options = c.options.replace(**({"rtol": 1e-7, "atol": 1e-6} if options is None else options))
    times = np.arange(0.0, t_end + 1e-9, dt)
    sol = c.tran(float(times[-1]), t_step=dt)
    rng = np.random.default_rng(seed)
    data = {"time_s": times}
    for s in signals:
        unit = "kPa" if s.startswith("p_") else "mg_s"
        data[f"{s}_{unit}"] = sample_at(sol.t, sol[s], times) + noise * rng.standard_normal(len(times))
    return pd.DataFrame(data)
