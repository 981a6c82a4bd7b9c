"""Design helpers: fill and empty times, normal-flow conversions, the paper's valve comparison.

Filling a volume (capacitance C = M V/(R T), isothermal) from a supply p_s through a
quadrature resistance R (eq. 4): C ṗ = √(p_s² − p²)/R, so

    t_fill = C·R·[asin(p₁/p_s) − asin(p₀/p_s)]

Emptying it to p_L: C ṗ = −√(p² − p_L²)/R, so

    t_empty = C·R·[acosh(p₀/p_L) − acosh(p₁/p_L)]

The paper's check (MODEL.md): a fully open axi valve (R_f 0.566) filling a 173 mm × Ø20 mm
McKibben from 96 kPa to 200 kPa gauge with 500 kPa gauge supply takes < 131 ms.
"""
from __future__ import annotations

import math

import numpy as np

from ..common.errors import ParameterError
from ..physics.gas import AIR, ROOM_TEMPERATURE_K


def capacitance(volume_ml: float, temperature_k: float = ROOM_TEMPERATURE_K, gas=AIR,
                n: float = 1.0) -> float:
    """C = M V/(n R T) in mg/kPa (n = 1 isothermal, 1.4 adiabatic at the start pressure)."""
    return gas.capacitance(volume_ml, temperature_k) / n


def cylinder_volume(length_mm: float, diameter_mm: float) -> float:
    """Volume of a cylinder in mL (a McKibben actuator at rest)."""
    return math.pi / 4 * diameter_mm ** 2 * length_mm * 1e-3


def fill_time(volume_ml: float, R: float, p_supply: float, p_from: float, p_to: float, *,
              temperature_k: float = ROOM_TEMPERATURE_K, gas=AIR) -> float:
    """Analytic time (s) to fill from ``p_from`` to ``p_to`` (kPa abs) through R (kPa·s/mg)."""
    if not p_from < p_to < p_supply:
        raise ParameterError(f"filling needs p_from < p_to < p_supply, got {p_from}, {p_to}, "
                             f"{p_supply} kPa")
    C = capacitance(volume_ml, temperature_k, gas)
    return C * R * (math.asin(p_to / p_supply) - math.asin(p_from / p_supply))


def empty_time(volume_ml: float, R: float, p_low: float, p_from: float, p_to: float, *,
               temperature_k: float = ROOM_TEMPERATURE_K, gas=AIR) -> float:
    """Analytic time (s) to empty from ``p_from`` down to ``p_to`` (> p_low) through R."""
    if not p_low < p_to < p_from:
        raise ParameterError(f"emptying needs p_low < p_to < p_from, got {p_low}, {p_to}, "
                             f"{p_from} kPa")
    C = capacitance(volume_ml, temperature_k, gas)
    return C * R * (math.acosh(p_from / p_low) - math.acosh(p_to / p_low))


def simulated_fill_time(volume_ml: float, R: float | None, p_supply: float, p_from: float,
                        p_to: float, *, valve=None, ambient: float = 96.0, t_max: float = 60.0,
                        **options) -> float:
    """Fill time from a transient: supply → resistor R (or a valve with its control port
    at ambient, fully open) → volume starting at ``p_from``; time to reach ``p_to``."""
    from ..engine import measure
    from ..engine.circuit import Circuit

    c = Circuit("fill", ambient=ambient, **options)
    c.pressure_source("PS", "supply", p_supply)
    if valve is not None:
        c.valve("X1", "supply", "v", "atm", model=valve)
    else:
        c.resistor("R1", "supply", "v", R=R)
    c.volume("V1", "v", V=volume_ml, p0=p_from)
    guess = fill_time(volume_ml, R if R else 1.0, p_supply, p_from, p_to)
    t_stop = min(t_max, max(5 * guess, 0.05))
    while True:
        sol = c.tran(t_stop)
        p = sol.pressure("v")
        if p[-1] >= p_to or t_stop >= t_max:
            return measure.when(sol.t, p, p_to, "rise")
        t_stop = min(t_max, 4 * t_stop)


def simulated_empty_time(volume_ml: float, R: float, p_low: float, p_from: float, p_to: float, *,
                         ambient: float = 96.0, **options) -> float:
    """Empty time from a transient: volume at ``p_from`` → R → ``p_low``."""
    from ..engine import measure
    from ..engine.circuit import Circuit

    c = Circuit("empty", ambient=ambient, **options)
    c.pressure_source("PL", "low", p_low)
    c.resistor("R1", "v", "low", R=R)
    c.volume("V1", "v", V=volume_ml, p0=p_from)
    t_stop = 3 * empty_time(volume_ml, R, p_low, p_from, p_to)
    sol = c.tran(t_stop)
    return measure.when(sol.t, sol.pressure("v"), p_to, "fall")


def to_normal_l_min(mdot_mg_s, gas=AIR):
    """Mass flow (mg/s) → normal litres per minute (0 °C, 101.325 kPa)."""
    return gas.normal_l_min(np.asarray(mdot_mg_s, dtype=float))


def from_normal_l_min(flow_nl_min, gas=AIR):
    """Normal litres per minute → mass flow (mg/s)."""
    return gas.mg_s(np.asarray(flow_nl_min, dtype=float))


#: Table 2 of the paper: valve comparison (resistance kPa·s/mg, size cm³, mass g)
VALVE_COMPARISON = (
    {"valve": "axi-symmetric membrane valve (this work)", "key": "axi", "resistance": 0.566,
     "size_cm3": 11.5, "mass_g": 17, "actuation": "fluid"},
    {"valve": "mirror-symmetric membrane valve (this work)", "key": "mirror", "resistance": 0.400,
     "size_cm3": 5.3, "mass_g": 11, "actuation": "fluid"},
    {"valve": "Festo VPPM", "key": "festo_vppm", "resistance": 0.042, "size_cm3": 300.4,
     "mass_g": 400, "actuation": "electronic"},
    {"valve": "Festo VEAB", "key": "festo_veab", "resistance": 1.164, "size_cm3": 92.6,
     "mass_g": 70, "actuation": "electronic"},
    {"valve": "Clippard 1 mm", "key": "clippard", "resistance": 7.752, "size_cm3": 3.5,
     "mass_g": 6, "actuation": "electronic"},
    {"valve": "microfluidic (off-chip)", "key": "microfluidic", "resistance": 33.059,
     "size_cm3": 3.3, "mass_g": 3, "actuation": "fluid"},
)


def valve_comparison(p_in: float = 596.0, p_out: float = 296.0, fill=None):
    """Table 2 as a DataFrame with derived columns at a working point: the flow through
    the fully open valve from ``p_in`` to ``p_out`` (mg/s and NL/min), flow per cm³ and
    per gram, and the analytic fill time of the paper's McKibben (``fill`` =
    (V mL, p_supply, p_from, p_to); default 54.4 mL, 596 kPa, 96 → 296 kPa)."""
    import pandas as pd

    df = pd.DataFrame(VALVE_COMPARISON)
    mdot = math.sqrt(p_in ** 2 - p_out ** 2) / df["resistance"]
    df["flow_mg_s"] = mdot
    df["flow_NL_min"] = to_normal_l_min(mdot)
    df["flow_per_cm3"] = mdot / df["size_cm3"]
    df["flow_per_g"] = mdot / df["mass_g"]
    V, ps, p0, p1 = fill or (cylinder_volume(173, 20), 596.0, 96.0, 296.0)
    df["fill_time_ms"] = [1e3 * fill_time(V, r, ps, p0, p1) for r in df["resistance"]]
    return df


def plot_fill(volume_ml, R, p_supply, p_from, p_to, path=None, valve=None, ambient=96.0):
    """Analytic and simulated filling curves p(t)."""
    from ..engine.circuit import Circuit
    from ..common.plotting import legend_outside, pyplot, save

    plt = pyplot()
    t_an = fill_time(volume_ml, R, p_supply, p_from, p_to)
    C = capacitance(volume_ml)
    t = np.linspace(0, 2 * t_an, 200)
    a0 = math.asin(p_from / p_supply)
    p_an = p_supply * np.sin(np.minimum(a0 + t / (C * R), math.pi / 2))
    fig, ax = plt.subplots(figsize=(6, 3.8))
    ax.plot(t * 1e3, p_an, "k-", lw=2, label=f"analytic, R = {R:g}: {t_an * 1e3:.1f} ms")
    for label, kw in (("simulated resistor", {"R": R}),
                      ("simulated valve (control at ambient)", {"valve": valve}) if valve else (None, None)):
        if label is None:
            continue
        c = Circuit("fill", ambient=ambient)
        c.pressure_source("PS", "supply", p_supply)
        if kw.get("valve") is not None:
            c.valve("X1", "supply", "v", "atm", model=kw["valve"])
        else:
            c.resistor("R1", "supply", "v", R=kw["R"])
        c.volume("V1", "v", V=volume_ml, p0=p_from)
        sol = c.tran(2 * t_an if "R" in kw else 4 * t_an)
        ts = simulated_fill_time(volume_ml, kw.get("R"), p_supply, p_from, p_to,
                                 valve=kw.get("valve"), ambient=ambient)
        ax.plot(sol.t * 1e3, sol.pressure("v"), "--", label=f"{label}: {ts * 1e3:.1f} ms")
    ax.axhline(p_to, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("pressure (kPa abs)")
    legend_outside(ax, fontsize=8)
    ax.set_title(f"filling {volume_ml:.1f} mL from {p_from:g} to {p_to:g} kPa, supply {p_supply:g} kPa",
                 fontsize=9)
    return save(fig, path) if path is not None else fig
