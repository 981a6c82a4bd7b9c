"""The circuits of the paper (section 6), ready to simulate or to modify.

All pressures absolute, kPa; resistances kPa·s/mg; volumes mL.
"""
from __future__ import annotations

from ..engine.circuit import Circuit
from ..physics.valve_params import PAPER_VALVES, ValveParams
from ..physics.waveforms import Pulse

#: resistance of the Clippard 1 mm electronic valve (Table 2), kPa·s/mg
CLIPPARD_RESISTANCE = 7.752

#: an electronic on/off valve as a membrane-valve model: open (R = R_f) while its
#: control pressure is below 150 kPa, closed above 160 kPa, independent of the
#: pressures at its ports (a_in = a_out = 0)
CLIPPARD_LIKE = ValveParams(Rf=CLIPPARD_RESISTANCE, pclose=-160.0, ptrans=-150.0, e=2.0,
                            ain=0.0, aout=0.0)


def oscillator(R_out: float | None = None, *, R_vent: float = 3.0, V: float = 200.0,
               p_high: float = 496.0, p_low: float = 96.0, valve="axi", n: float = 1.0,
               V_out: float = 0.0, R_tube: float = 0.0, **options) -> Circuit:
    """Single-valve relaxation oscillator (Fig. 11A): supply → valve → R_out → tank.

    The tank (volume ``V``, polytropic exponent ``n``) feeds the valve's control
    port and vents to ``p_low`` through ``R_vent``.  ``R_out`` defaults to 2·R_f
    (limit cycle); 0 ties the valve output to the tank (stable equilibrium).
    Circuit-level effects: ``V_out`` tubing dead volume at the valve output (mL),
    ``R_tube`` a tube between the sensed node ``tank`` and the volume.
    Nodes: supply, out, tank, low.  Options (``ambient`` defaults to ``p_low``)
    go to :class:`~pneunet.SimulationOptions`.
    """
    params = PAPER_VALVES[valve] if isinstance(valve, str) else valve
    R_out = 2 * params.Rf if R_out is None else R_out
    options.setdefault("ambient", p_low)
    c = Circuit(f"oscillator R_out={R_out:g}", **options)
    c.pressure_source("PH", "supply", p_high)
    c.pressure_source("PL", "low", p_low)
    if R_out > 0:
        c.valve("X1", "supply", "out", "tank", model=params)
        c.resistor("Rout", "out", "tank", R=R_out)
        if V_out > 0:
            c.volume("Vout", "out", V=V_out, p0=p_low)
    else:
        c.valve("X1", "supply", "tank", "tank", model=params)
    volume_node = "tank"
    if R_tube > 0:
        volume_node = "tank_volume"
        c.resistor("Rtube", "tank", volume_node, R=R_tube)
    c.volume("V1", volume_node, V=V, n=n, p0=p_low)
    c.resistor("Rvent", "tank", "low", R=R_vent)
    return c


def flow_amplifier(valve="mirror", *, p_high: float = 289.0, p_low: float = 120.0,
                   half_period: float = 5.0, ctrl_open: float = 96.0, ctrl_closed: float = 289.0,
                   actuator_length: float = 100.0, actuator_diameter: float = 20.0,
                   **options) -> Circuit:
    """Flow amplification (Fig. 10): a McKibben actuator filled by an in-valve from
    ``p_high`` and emptied by an out-valve to ``p_low``.

    The control pressures alternate every ``half_period``: first the in-valve opens
    (its control at ``ctrl_open``) while the out-valve is held closed (control at
    ``ctrl_closed``), then the reverse.  With the axi valve at these pressures the
    control would have to fall below 82 kPa abs to open, so the default is the
    mirror valve.  Nodes: supply, low, act, c_in, c_out.
    """
    params = PAPER_VALVES[valve] if isinstance(valve, str) else valve
    options.setdefault("ambient", 96.0)
    c = Circuit("flow amplifier", **options)
    c.pressure_source("PH", "supply", p_high)
    c.pressure_source("PL", "low", p_low)
    edge = 0.01  # s, control-line switching ramp
    period = 2 * half_period
    c.pressure_source("CIN", "c_in", Pulse(ctrl_closed, ctrl_open, 0.0, edge, edge,
                                           half_period - edge, period))
    c.pressure_source("COUT", "c_out", Pulse(ctrl_closed, ctrl_open, half_period, edge, edge,
                                             half_period - edge, period))
    c.valve("Xin", "supply", "act", "c_in", model=params)
    c.valve("Xout", "act", "low", "c_out", model=params)
    c.actuator("A1", "act", length=actuator_length, diameter=actuator_diameter, p0=p_low)
    return c


def fill_circuit(*, resistance: float = 0.566, valve=None, p_supply: float = 596.0,
                 p_start: float = 96.0, length: float = 173.0, diameter: float = 20.0,
                 **options) -> Circuit:
    """A McKibben actuator (cylinder ``length`` × ``diameter``, mm) filled from
    ``p_supply`` through a resistor, or through a fully open valve (control at
    ambient) when ``valve`` is given.  Nodes: supply, act (and ctrl)."""
    options.setdefault("ambient", p_start)
    c = Circuit("fill time", **options)
    c.pressure_source("PS", "supply", p_supply)
    if valve is None:
        c.resistor("R1", "supply", "act", R=resistance)
    else:
        c.valve("X1", "supply", "act", "atm", model=valve)
    c.actuator("A1", "act", length=length, diameter=diameter, p0=p_start)
    return c
