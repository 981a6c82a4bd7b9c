"""The paper's circuits as Python builders (picklable, so sweeps can ship them to workers).

``oscillator(params)`` builds Fig. 11A / 12A: supply p_H → valve → R_out → tank (V) whose
pressure p_c drives the valve's control port; the tank vents to p_L through R_vent.
"""
from __future__ import annotations

from ..engine.circuit import Circuit

#: the paper's oscillator (section 6.2); R_out = 2 R_f of the axi valve
OSCILLATOR_DEFAULTS = {"pH": 496.0, "pL": 96.0, "Rout": 1.132, "Rvent": 3.0, "V": 200.0,
                       "n": 1.0, "valve": "axi", "ambient": 96.0, "dead_volume": 0.0,
                       "V_out": 0.0, "R_tube": 0.0}


def oscillator(params: dict | None = None, **options) -> Circuit:
    """The oscillator of Fig. 11A with parameters overriding :data:`OSCILLATOR_DEFAULTS`.

    A dict-driven front end of :func:`pneunet.design.paper_circuits.oscillator` (module-level
    and picklable, for sweeps).  Nodes: ``supply``, ``out``, ``tank``, ``low``.
    """
    from .paper_circuits import oscillator as build

    p = dict(OSCILLATOR_DEFAULTS)
    plain = {k: v for k, v in (params or {}).items() if "." not in k}  # dotted: element params
    unknown = sorted(set(plain) - set(OSCILLATOR_DEFAULTS))
    if unknown:
        import difflib

        from ..common.errors import ParameterError

        close = difflib.get_close_matches(unknown[0], OSCILLATOR_DEFAULTS, n=1)
        raise ParameterError(f"the oscillator has no parameter {unknown[0]!r}",
                             hint=f"did you mean {close[0]!r}?" if close else
                             "parameters: " + ", ".join(OSCILLATOR_DEFAULTS))
    p.update(plain)
    opts = {"ambient": p["ambient"]}
    if p["dead_volume"]:
        opts["dead_volume"] = p["dead_volume"]
    opts.update(options)
    return build(p["Rout"], R_vent=p["Rvent"], V=p["V"], p_high=p["pH"], p_low=p["pL"],
                 valve=p["valve"], n=p["n"], V_out=p["V_out"], R_tube=p["R_tube"], **opts)


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
