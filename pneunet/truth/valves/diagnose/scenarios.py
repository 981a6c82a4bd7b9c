"""Bench scenarios with known truth: each library effect, pairs, and effects the
library does not know (used by the tests, the docs and the benchmark).

All data come from :func:`pneunet.truth.valves.identify.simulate_bench` (issue 4's virtual
bench with its default noise, setpoint errors and outlet regulator) run on the
paper's axi valve extended by the scenario's effects.
"""
from __future__ import annotations

import numpy as np

from ....physics.valve_effects import ValveModel, get_effect
from ....physics.valve_params import PAPER_VALVES


def alternating_protocol(step=25.0, p_in=(121.0, 596.0)):
    """The paper's protocol (4410 points at step 25) with every other p_ctrl
    sweep run upwards (``sweep`` +1), so that both sweep directions are present
    at the same size and order as the paper's experiment."""
    from ..identify import paper_protocol

    proto = paper_protocol(step=step, p_in=p_in)
    key = proto["p_in_cmd_kPa"].astype(str) + "/" + proto["p_out_cmd_kPa"].astype(str)
    sweep_no = (key != key.shift()).cumsum() - 1
    parts = []
    for k, part in proto.groupby(sweep_no, sort=True):
        part = part.copy()
        if k % 2 == 1:
            part[["p_ctrl_cmd_kPa"]] = part[["p_ctrl_cmd_kPa"]].to_numpy()[::-1]
            part["sweep"] = 1
        parts.append(part)
    import pandas as pd

    out = pd.concat(parts, ignore_index=True)
    out["time_s"] = proto["time_s"].to_numpy()
    return out


def reduced_protocol():
    """A 50 kPa-step version of :func:`alternating_protocol` (≈ 600 points) for
    tests of logic rather than of realistic size."""
    return alternating_protocol(step=50.0, p_in=(121.0, 571.0))


#: library effects at realistic, clearly visible strengths (id -> values)
LIBRARY_SCENARIOS = {
    "choked": {"b": 0.25},
    "leak": {"G": 0.01},
    "laminar": {"K": 10.0},
    "internal-drop": {"lam": 0.5},
    "hysteresis": {"h": 10.0},
    "pressure-offset": {"p0": 30.0},
}


class _Unlisted:
    """A truth model = valve (+ optional transforms) that is not a library effect."""

    def __init__(self, name, fn, expect):
        self.name, self.fn, self.expect = name, fn, expect

    def __call__(self, frame):
        return self.fn(frame)


def _axi(frame, **kw):
    P = PAPER_VALVES["axi"]
    return ValveModel(P)(frame)


def _drift(frame):
    # flow-sensor gain drifting by +8 % over the experiment (~6 h)
    t = frame["time_s"].to_numpy(float)
    return _axi(frame) * (1.0 + 0.08 * t / t.max())


def _control_area(frame):
    # control area grows with p_ctrl (membrane bulging into the control chamber)
    from ....physics.laws import valve_flow

    P = PAPER_VALVES["axi"]
    pc = frame["p_ctrl_kPa"].to_numpy(float)
    pc_eff = pc * (1.0 + 2.5e-4 * (pc - 96.0))
    return valve_flow(frame["p_in_kPa"].to_numpy(float), frame["p_out_kPa"].to_numpy(float),
                      pc_eff, **P.as_dict())


def _sensor_nonlinearity(frame):
    # S-shaped linearisation error of the flow sensor, ±1.2 % of 1000 mg/s full scale
    m = _axi(frame)
    return m + 12.0 * np.sin(2 * np.pi * m / 1000.0)


#: effects not in the library: name -> truth, and the features that must lead ``where``
UNLISTED_SCENARIOS = {
    "drift": _Unlisted("drift", _drift, ("time", "p_in")),
    "control-area": _Unlisted("control-area", _control_area, ("p_ctrl", "dp")),
    "sensor-nonlinearity": _Unlisted("sensor-nonlinearity", _sensor_nonlinearity,
                                     ("mdot",)),
}


def truth_model(effects=()):
    """The paper's axi valve with library effects ``{id: values}`` or ``[(id, values)]``."""
    items = effects.items() if isinstance(effects, dict) else effects
    return ValveModel(PAPER_VALVES["axi"], [get_effect(i)(**v) for i, v in items])


def bench(truth, *, reduced=False, seed=0, **bench_options):
    """Bench data for ``truth`` (a ValveModel or callable) on the alternating protocol."""
    from ..identify import simulate_bench

    proto = reduced_protocol() if reduced else alternating_protocol()
    return simulate_bench(truth, protocol=proto, seed=seed, **bench_options)


def achievable_floor(truth, data) -> float:
    """RMSE of the *true* model on the measured pressures: the noise floor the bench
    was given (flow noise plus pressure noise propagated through the law)."""
    pred = np.asarray(truth(data[["time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "sweep"]]))
    return float(np.sqrt(np.mean((pred - data["mdot_mg_s"].to_numpy(float)) ** 2)))


def scenario_truth(name):
    """Truth for a scenario name: 'clean', a library id, 'a+b', or an unlisted name."""
    if name in UNLISTED_SCENARIOS:
        return UNLISTED_SCENARIOS[name]
    if name == "clean":
        return truth_model()
    return truth_model([(n, LIBRARY_SCENARIOS[n]) for n in name.split("+")])


def run_scenario(name, *, seed=0, reduced=False, **diagnose_options):
    """Bench data for scenario ``name``, diagnosed; returns (diagnosis, floor, data)."""
    from . import diagnose

    truth = scenario_truth(name)
    data = bench(truth, reduced=reduced, seed=seed)
    diagnose_options.setdefault("progress", False)
    return diagnose(data, **diagnose_options), achievable_floor(truth, data), data
