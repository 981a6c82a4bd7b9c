"""Virtual test bench: the paper's measurement protocol run on any flow model.

The paper (sec. 4.3) commands p_in from 121 to 596 kPa in 25 kPa steps, for each
p_out from 96 kPa to p_in − 25 kPa, and for each of these lowers p_ctrl from 596
to 96 kPa in 25 kPa steps: 4410 held points, each averaged over 2 s.  The bench
reproduces that protocol and the imperfections of the real setup:

* **setpoint error** — the regulators hold the true pressures a few kPa off the
  command (paper: within 5 kPa for input and control);
* **sensor noise** on the three pressures and on the flow reading (absolute and
  relative part), and a constant **flow-sensor bias**;
* the **outlet regulator** cannot vent the valve's flow fast enough at high flow, so
  the real p_out rises above its command (paper: up to 220 kPa).  It is modelled as
  a quadrature resistance ``r_vent`` to the vent pressure: the outlet pressure is
  ``max(command, sqrt(p_vent² + (r_vent·ṁ)²))``, and because ṁ depends on p_out
  the bench solves this fixed point (bisection, vectorised).

``flow`` is a :class:`~pneunet.physics.valve_params.ValveParams` or any callable
``flow(frame) -> ndarray`` receiving the true pressures in the canonical columns
(``p_in_kPa``, ``p_out_kPa``, ``p_ctrl_kPa``) plus ``time_s`` and ``sweep``, so
models with hysteresis (sweep direction) or drift (time) plug in unchanged.
Deterministic for a given ``seed``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from ....common.errors import ParameterError
from ....physics.valve_params import ValveParams

CANONICAL = ("time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s")
PAPER_AMBIENT_KPA = 96.0


def paper_protocol(*, p_in=(121.0, 596.0), p_out_min=96.0, p_ctrl=(596.0, 96.0), step=25.0,
                   sweeps="down", settle_s=3.0, hold_s=2.0) -> pd.DataFrame:
    """Commanded points of the paper's protocol in experiment order.

    ``p_in``: (first, last) commanded input pressure; ``p_out`` runs from ``p_out_min``
    to p_in − step; ``p_ctrl`` from its first to its last value for ``sweeps="down"``
    (the paper), then back up again for ``"downup"`` (hysteresis studies).  Returns
    columns ``p_in_cmd_kPa, p_out_cmd_kPa, p_ctrl_cmd_kPa, sweep, time_s``; time stamps
    are the middle of each hold period.  The default gives the paper's 4410 points.
    """
    if sweeps not in ("down", "downup"):
        raise ParameterError(f"sweeps must be 'down' or 'downup', got {sweeps!r}")
    n_in = int(round((p_in[1] - p_in[0]) / step)) + 1
    n_ctrl = int(round(abs(p_ctrl[0] - p_ctrl[1]) / step)) + 1
    ctrl_down = np.linspace(p_ctrl[0], p_ctrl[1], n_ctrl)
    rows = []
    for pin in p_in[0] + step * np.arange(n_in):
        n_out = int(round((pin - step - p_out_min) / step)) + 1
        for pout in p_out_min + step * np.arange(max(n_out, 0)):
            sequence = [(c, -1) for c in ctrl_down]
            if sweeps == "downup":
                sequence += [(c, +1) for c in ctrl_down[::-1][1:]]
            rows.extend((pin, pout, c, s) for c, s in sequence)
    frame = pd.DataFrame(rows, columns=["p_in_cmd_kPa", "p_out_cmd_kPa", "p_ctrl_cmd_kPa",
                                        "sweep"])
    frame["sweep"] = frame["sweep"].astype(int)
    period = settle_s + hold_s
    frame.insert(0, "time_s", period * np.arange(len(frame)) + settle_s + 0.5 * hold_s)
    return frame


@dataclass(frozen=True)
class OutletRegulator:
    """An outlet pressure regulator that vents through a quadrature resistance.

    With the defaults (r_vent 0.36 kPa·s/mg to 96 kPa) the paper's axi valve at
    p_in 396 kPa cannot get p_out below about 227 kPa when fully open, and the
    largest rise above the command is about 230 kPa — the paper's Fig. 7 gap and
    its "up to 220 kPa".
    """

    r_vent: float = 0.36
    p_vent: float = PAPER_AMBIENT_KPA

    def floor(self, mdot):
        """Lowest outlet pressure the regulator can hold at valve flow ``mdot``."""
        mdot = np.maximum(np.asarray(mdot, dtype=float), 0.0)
        return np.sqrt(self.p_vent ** 2 + (self.r_vent * mdot) ** 2)


def _as_flow_function(flow):
    if isinstance(flow, ValveParams):
        from ....physics.laws import valve_flow

        params = flow.as_dict()

        def function(frame):
            return valve_flow(frame["p_in_kPa"].to_numpy(), frame["p_out_kPa"].to_numpy(),
                              frame["p_ctrl_kPa"].to_numpy(), **params)

        return function
    if callable(flow):
        return flow
    raise ParameterError(f"flow must be a ValveParams or a callable flow(frame), got "
                         f"{type(flow).__name__}")


def _evaluate(function, frame):
    mdot = np.asarray(function(frame), dtype=float).reshape(-1)
    if mdot.shape[0] != len(frame):
        raise ParameterError(f"the flow model returned {mdot.shape[0]} values for "
                             f"{len(frame)} points")
    return mdot


def simulate_bench(flow, *, protocol=None, noise_mdot=0.2, noise_rel=0.01, noise_p=0.5,
                   setpoint_error=1.5, bias=0.0, regulator="paper", seed=0,
                   clip_negative=False, include_truth=True) -> pd.DataFrame:
    """Run a measurement protocol on a valve model and return the recorded data.

    Parameters
    ----------
    flow : ValveParams or callable
        The valve under test (see module docstring).
    protocol : DataFrame, optional
        Commanded points with ``p_in_cmd_kPa, p_out_cmd_kPa, p_ctrl_cmd_kPa``
        (``sweep`` and ``time_s`` optional); default :func:`paper_protocol`.
    noise_mdot, noise_rel : float
        Flow reading noise: standard deviation ``noise_mdot`` mg/s plus
        ``noise_rel`` × the true flow (of the 2 s average).
    noise_p : float
        Pressure sensor noise, standard deviation in kPa.
    setpoint_error : float
        Standard deviation (kPa) of the true pressures around their commands.
    bias : float
        Constant flow-sensor offset (mg/s) added to every flow reading.
    regulator : "paper", OutletRegulator or None
        Outlet regulator model; None holds p_out at its command whatever the flow.
    clip_negative : bool
        Clip flow readings at zero before the bias (a unidirectional sensor).
    include_truth : bool
        Also return the true pressures and flow (``*_true`` columns).

    Returns the canonical columns ``time_s, p_in_kPa, p_out_kPa, p_ctrl_kPa,
    mdot_mg_s, sweep`` plus the commanded pressures (``*_cmd_kPa``).
    """
    function = _as_flow_function(flow)
    commands = paper_protocol() if protocol is None else protocol.copy()
    missing = [c for c in ("p_in_cmd_kPa", "p_out_cmd_kPa", "p_ctrl_cmd_kPa")
               if c not in commands]
    if missing:
        raise ParameterError(f"protocol lacks columns {missing}",
                             hint="build one with pneunet.truth.valves.identify.paper_protocol()")
    n = len(commands)
    if "sweep" not in commands:
        commands["sweep"] = -1
    if "time_s" not in commands:
        commands.insert(0, "time_s", 5.0 * np.arange(n) + 4.0)
    if regulator == "paper":
        regulator = OutletRegulator()
    rng = np.random.default_rng(seed)
    # true pressures: commands plus setpoint errors (the outlet may rise, below)
    p_in = commands["p_in_cmd_kPa"].to_numpy(float) + setpoint_error * rng.standard_normal(n)
    p_out_cmd = commands["p_out_cmd_kPa"].to_numpy(float) + setpoint_error * rng.standard_normal(n)
    p_ctrl = commands["p_ctrl_cmd_kPa"].to_numpy(float) + setpoint_error * rng.standard_normal(n)
    true = pd.DataFrame({"time_s": commands["time_s"].to_numpy(float), "p_in_kPa": p_in,
                         "p_out_kPa": p_out_cmd, "p_ctrl_kPa": p_ctrl,
                         "sweep": commands["sweep"].to_numpy(int)})
    mdot = _evaluate(function, true)
    if regulator is not None:
        p_out = _solve_outlet(function, true, mdot, regulator)
        true["p_out_kPa"] = p_out
        mdot = _evaluate(function, true)
    sensor = rng.standard_normal((4, n))
    reading = mdot + noise_mdot * sensor[3] + noise_rel * np.abs(mdot) * rng.standard_normal(n)
    if clip_negative:
        reading = np.maximum(reading, 0.0)
    out = pd.DataFrame({
        "time_s": true["time_s"],
        "p_in_kPa": true["p_in_kPa"] + noise_p * sensor[0],
        "p_out_kPa": true["p_out_kPa"] + noise_p * sensor[1],
        "p_ctrl_kPa": true["p_ctrl_kPa"] + noise_p * sensor[2],
        "mdot_mg_s": reading + bias,
        "sweep": true["sweep"],
    })
    for c in ("p_in_cmd_kPa", "p_out_cmd_kPa", "p_ctrl_cmd_kPa"):
        out[c] = commands[c].to_numpy(float)
    if include_truth:
        out["p_out_true_kPa"] = true["p_out_kPa"]
        out["mdot_true_mg_s"] = mdot
    out.attrs["bench"] = {
        "noise_mdot": noise_mdot, "noise_rel": noise_rel, "noise_p": noise_p,
        "setpoint_error": setpoint_error, "bias": bias, "seed": seed,
        "regulator": None if regulator is None else asdict(regulator),
        "flow": flow.as_dict() if isinstance(flow, ValveParams) else repr(flow),
    }
    return out


def _solve_outlet(function, true, mdot, regulator, grid=48, iterations=30):
    """Outlet pressure p with p = max(p_cmd, floor(ṁ(p))) for every point.

    h(p) = floor(ṁ(p)) − p is > 0 at the command when the regulator is overloaded
    and < 0 at p = p_in (no flow).  Several roots can exist (the valve opens further
    as p_out rises): a falling control sweep (``sweep`` −1) starts from a closed valve
    and stays on the lowest root, a rising one (+1) on the highest.  A grid scan
    brackets the root, bisection refines it.  The model always sees the full frame
    (history-dependent models need it).
    """
    p_cmd = true["p_out_kPa"].to_numpy(float).copy()
    p_in = true["p_in_kPa"].to_numpy(float)
    need = regulator.floor(mdot) > p_cmd
    if not need.any():
        return p_cmd
    rising = true["sweep"].to_numpy() > 0
    work = true.copy()
    span = np.where(need, np.maximum(p_in - p_cmd, 0.0), 0.0)

    def h_at(p):
        work["p_out_kPa"] = p
        return regulator.floor(_evaluate(function, work)) - p

    fractions = np.linspace(0.0, 1.0, grid + 1)
    positive = np.empty((grid + 1, len(p_cmd)), dtype=bool)
    for k, t in enumerate(fractions):
        positive[k] = h_at(p_cmd + t * span) > 0
    positive[0] = True
    positive[-1] = False
    # lowest root: first grid index with h <= 0; highest: after the last h > 0
    first_neg = np.argmax(~positive, axis=0)
    last_pos = grid - np.argmax(positive[::-1], axis=0)
    upper = np.where(rising, last_pos + 1, first_neg)
    lo = p_cmd + fractions[upper - 1] * span
    hi = p_cmd + fractions[upper] * span
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        up = h_at(np.where(need, mid, p_cmd)) > 0
        lo = np.where(up, mid, lo)
        hi = np.where(up, hi, mid)
    return np.where(need, 0.5 * (lo + hi), p_cmd)
