"""The paper's circuits as Python builders (picklable, so sweeps can ship them to workers).

``oscillator(params)`` builds Fig. 11A / 12A: supply p_H → valve → R_out → tank (V) whose
pressure p_c drives the valve's control port; the tank vents to p_L through R_vent.
"""
from __future__ import annotations

from ..circuit import Circuit

#: the paper's oscillator (section 6.2); R_out = 2 R_f of the axi valve
OSCILLATOR_DEFAULTS = {"pH": 496.0, "pL": 96.0, "Rout": 1.132, "Rvent": 3.0, "V": 200.0,
                       "n": 1.0, "valve": "axi", "ambient": 96.0, "dead_volume": 0.0,
                       "V_out": 0.0, "R_tube": 0.0}


def oscillator(params: dict | None = None, **options) -> Circuit:
    """The oscillator of Fig. 11A with parameters overriding :data:`OSCILLATOR_DEFAULTS`.

    Nodes: ``supply`` (p_H), ``out`` (valve output), ``tank`` (p_c), ``low`` (p_L).
    R_out = 0 ties the valve output to the tank.  Optional circuit-level effects:
    ``n`` polytropic exponent of the tank, ``V_out`` tubing dead volume at the valve
    output (mL), ``R_tube`` a tube between the tank volume and the sensed node ``tank``.
    """
    p = dict(OSCILLATOR_DEFAULTS)
    p.update(params or {})
    opts = {"ambient": p["ambient"]}
    if p["dead_volume"]:
        opts["dead_volume"] = p["dead_volume"]
    opts.update(options)
    c = Circuit("oscillator", **opts)
    c.pressure_source("PH", "supply", p["pH"])
    if p["Rout"] > 0:
        c.valve("X1", "supply", "out", "tank", model=p["valve"])
        c.resistor("Rout", "out", "tank", R=p["Rout"])
        if p["V_out"] > 0:
            c.volume("Vout", "out", V=p["V_out"])
    else:
        c.valve("X1", "supply", "tank", "tank", model=p["valve"])
    vol_node = "tank"
    if p["R_tube"] > 0:
        vol_node = "tank_volume"
        c.resistor("Rtube", "tank", vol_node, R=p["R_tube"])
    c.volume("V1", vol_node, V=p["V"], n=p["n"])
    c.pressure_source("PL", "low", p["pL"])
    c.resistor("Rvent", "tank", "low", R=p["Rvent"])
    return c


def inverter(params: dict | None = None) -> Circuit:
    """Fluid inverter: a valve from the supply to Y, controlled by input A; Y vents to
    ambient through R_load and has a small volume.  A high closes the valve (Y low)."""
    p = {"pH": 496.0, "A": 96.0, "R_load": 3.0, "V_load": 10.0, "ambient": 96.0, "valve": "axi"}
    p.update(params or {})
    c = Circuit("inverter", ambient=p["ambient"])
    c.pressure_source("PH", "supply", p["pH"])
    c.pressure_source("PA", "a", p["A"])
    c.valve("X1", "supply", "y", "a", model=p["valve"])
    c.volume("VY", "y", V=p["V_load"])
    c.resistor("RL", "y", "atm", R=p["R_load"])
    return c


def nor_gate(params: dict | None = None) -> Circuit:
    """Fluid NOR: two valves in series from the supply to Y, controlled by A and B."""
    p = {"pH": 496.0, "A": 96.0, "B": 96.0, "R_load": 3.0, "V_load": 10.0, "ambient": 96.0,
         "valve": "axi"}
    p.update(params or {})
    c = Circuit("nor", ambient=p["ambient"])
    c.pressure_source("PH", "supply", p["pH"])
    c.pressure_source("PA", "a", p["A"])
    c.pressure_source("PB", "b", p["B"])
    c.valve("X1", "supply", "m", "a", model=p["valve"])
    c.volume("VM", "m", V=1.0)
    c.valve("X2", "m", "y", "b", model=p["valve"])
    c.volume("VY", "y", V=p["V_load"])
    c.resistor("RL", "y", "atm", R=p["R_load"])
    return c
