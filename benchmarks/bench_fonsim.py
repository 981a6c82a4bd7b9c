"""FONSim against pneunet on the same equations (issue 14).

* fill (N = 1): a 50 mL container filled from atmosphere to 3 bar absolute through an
  orifice (FONSim ``FlowRestrictor``, d = 0.5 mm, K = 0.6; pneunet's quadrature resistor
  with R = 4/(πd²)·√(K·p_atm/ρ_stp), the same law), 2 s;
* chain: N such restrictor–container cells in series fed by that step, 2 s;
* oscillator: the paper's relaxation oscillator (axi valve) with a 1 mL dead volume at
  the valve output, 20 s; in FONSim the membrane valve is a user-written component
  evaluating pneunet's law; the period against pneunet at rtol 1e-9.

* water (issue 34): FONSim's own test of two accumulators draining through a 2 mm × 0.1 m
  tube (Re 6,900 → laminar, ``tube`` with roughness against ``CircularTube``), 1 s;
* balloon (issue 34): FONSim's packaged 60 mm balloon curve (read from the installed
  package; skipped without it) behind the restrictor, 65 kPa gauge with a pulse to 89 kPa:
  the rest volume before and after the snap-through, 8 s.

Both use FONSim's gas (ρ_stp = 1.23 kg/m³ at 1.013 bar): pneunet's temperature is set so
that M/(R·T) = ρ_stp/p_atm, and its flow band is 1e-3 kPa² (FONSim's law has none).
Errors are the largest deviation of any container's pressure from pneunet at
rtol = atol = 1e-10 on a 10 ms grid, in kPa (no reference above N = 1000).  FONSim runs with its defaults and
``step=(1e-4, 1e-2)``; it is skipped with a note when it is not installed
(``pip install fonsim``).  Wall times of the simulation only (build excluded), s.

Run:  python benchmarks/bench_fonsim.py [--sizes 1,10,30,100,1000,10000] [--fonsim-max 30]
"""
from __future__ import annotations

import argparse
import contextlib
import io
import math
import time

import numpy as np

P_ATM, RHO_STP, M_AIR, R_GAS = 1.013e5, 1.23, 28.965e-3, 8.314  # FONSim's constants, SI
D, K_FACTOR, VOLUME, P_SUPPLY = 0.5e-3, 0.6, 50e-6, 3.0e5
GRID = np.arange(0.0, 2.0 + 1e-9, 0.01)


def pneunet_chain(n, t_stop=2.0, rtol=1e-5):
    """pneunet: (every container's pressure on GRID (n_t, n) in kPa, seconds)."""
    from pneunet import Circuit

    temperature = _matched_temperature()
    r = 4 / (math.pi * D ** 2) * math.sqrt(K_FACTOR * P_ATM / RHO_STP) * 1e-9  # kPa·s/mg
    c = Circuit(f"chain {n}", ambient=P_ATM / 1e3, temperature=temperature, flow_band=1e-3,
                rtol=rtol, atol=rtol)
    c.pressure_source("P1", "n0", P_SUPPLY / 1e3)
    for k in range(1, n + 1):
        c.resistor(f"R{k}", f"n{k - 1}", f"n{k}", R=r)
        c.volume(f"V{k}", f"n{k}", V=VOLUME * 1e6)
    start = time.perf_counter()
    sol = c.tran(t_stop, t_step=0.01)
    seconds = time.perf_counter() - start
    grid = GRID[GRID <= t_stop]
    return np.column_stack([np.interp(grid, sol.t, sol.pressure(f"n{k}"))
                            for k in range(1, n + 1)]), seconds


def _run_quietly(fons, system, t_stop, step):
    """(FONSim simulation run for ``t_stop`` s with its (min, max) ``step``, wall s of
    the run alone), FONSim's progress printing swallowed."""
    with contextlib.redirect_stdout(io.StringIO()):
        sim = fons.Simulation(system, duration=t_stop, step=step)
        start = time.perf_counter()
        sim.run()
        return sim, time.perf_counter() - start


def fonsim_chain(n, t_stop=2.0):
    """FONSim: (every container's pressure on GRID (n_t, n) in kPa, seconds), or None."""
    try:
        import fonsim as fons
    except ImportError:
        return None
    system = fons.System(f"chain {n}")
    system.add(fons.PressureSource("source", pressure=P_SUPPLY))
    for k in range(1, n + 1):
        system.add(fons.FlowRestrictor(f"r{k}", fluid=fons.air, diameter=D, k=K_FACTOR))
        system.add(fons.Container(f"c{k}", fluid=fons.air, volume=VOLUME))
    system.connect("source", "r1")
    for k in range(1, n):
        system.connect_common(f"r{k}", f"c{k}", f"r{k + 1}")
    system.connect(f"r{n}", f"c{n}")
    sim, seconds = _run_quietly(fons, system, t_stop, (1e-4, 1e-2))
    grid = GRID[GRID <= t_stop]
    return np.column_stack([np.interp(grid, sim.times, system.get(f"c{k}").get("pressure") / 1e3)
                            for k in range(1, n + 1)]), seconds


def _matched_temperature():
    from pneunet import AIR

    return AIR.molar_mass_g_mol * 1e-3 * P_ATM / (R_GAS * RHO_STP)


def pneunet_oscillator(t_stop, rtol=1e-5):
    """The paper's oscillator (axi valve, R_out = 2·R_f, 200 mL tank, 1 mL at the valve
    output) venting to FONSim's atmosphere: (Oscillation of the tank pressure, seconds)."""
    from pneunet.engine.oscillation import analyze_oscillation
    from pneunet.design.paper_circuits import oscillator

    c = oscillator(p_low=P_ATM / 1e3, V_out=1.0, temperature=_matched_temperature(),
                   rtol=rtol, atol=rtol)
    start = time.perf_counter()
    sol = c.tran(t_stop)
    seconds = time.perf_counter() - start
    return analyze_oscillation(sol.t, sol.pressure("tank")), seconds


def fonsim_oscillator(t_stop):
    """The same oscillator in FONSim with a user-written membrane valve component (the
    law and partials of :mod:`pneunet.physics.laws`): (Oscillation, seconds), or None."""
    try:
        import fonsim as fons
        from fonsim.components.terminals import terminal_fluidic
        from fonsim.core.component import Component
        from fonsim.core.terminal import Terminal
    except ImportError:
        return None
    from pneunet.engine.oscillation import analyze_oscillation
    from pneunet.physics.laws import valve_flow_and_partials
    from pneunet.physics.valve_params import PAPER_VALVES

    axi = PAPER_VALVES["axi"].as_dict()

    class MembraneValve(Component):
        """Terminals a (in), b (out), c (control, no flow); SI units."""

        def __init__(self, label):
            super().__init__(label)
            self.set_terminals(*(Terminal(x, terminal_fluidic, {"pressure": f"p{i}",
                                                               "massflow": f"mf{i}"})
                                 for i, x in enumerate("abc")))

            @self.auto
            def evaluate(p0, p1, p2, mf0, mf1, mf2):
                law, grad = valve_flow_and_partials(p0 / 1e3, p1 / 1e3, p2 / 1e3, **axi)
                jacobian = [{"mf0": 1.0, **{f"p{i}": -float(g) * 1e-9 for i, g in
                                            enumerate(grad)}},
                            {"mf0": 1.0, "mf1": 1.0}, {"mf2": 1.0}]
                return np.array([mf0 - float(law) * 1e-6, mf0 + mf1, mf2]), jacobian
            self.evaluate = evaluate

    def restrictor(label, r, d=1e-3):  # K-factor of a quadrature resistance r (kPa·s/mg)
        k = (r * 1e9 * math.pi * d ** 2 / 4) ** 2 * RHO_STP / P_ATM
        return fons.FlowRestrictor(label, fluid=fons.air, diameter=d, k=k)

    system = fons.System("oscillator")
    system.add(fons.PressureSource("supply", pressure=496e3), MembraneValve("X1"),
               restrictor("Rout", 2 * axi["Rf"]), restrictor("Rvent", 3.0),
               fons.Container("Vout", fluid=fons.air, volume=1e-6),
               fons.Container("tank", fluid=fons.air, volume=200e-6),
               fons.PressureSource("low", pressure=P_ATM))
    system.connect("supply", "X1")
    system.connect_common("X1", "Vout", "Rout")
    system.connect_common("Rout", "tank", "Rvent", "X1")
    system.connect("Rvent", "low")
    sim, seconds = _run_quietly(fons, system, t_stop, (1e-5, 1e-2))
    return analyze_oscillation(sim.times, system.get("tank").get("pressure") / 1e3), seconds


def oscillator_table(have_fonsim, t_stop=20.0):
    reference, _ = pneunet_oscillator(t_stop, rtol=1e-9)
    print(f"\noscillator, {t_stop:g} s (reference period {reference.period_s:.4f} s, "
          "pneunet rtol 1e-9)")
    print("| simulator | s | period s | period error |")
    print("|---|---|---|---|")
    runs = [("pneunet", pneunet_oscillator(t_stop))]
    runs += [("FONSim", fonsim_oscillator(t_stop))] if have_fonsim else []
    for name, (osc, seconds) in runs:
        print(f"| {name} | {seconds:.2f} | {osc.period_s:.4f} | "
              f"{abs(osc.period_s / reference.period_s - 1):.1e} |")


# -- issue 34: a water line through the transition, and the balloon that snaps through ------
FONSIM_WATER = (999.0, 9.77e-4)  # kg/m³, Pa·s (FONSim's ``water``)


def pneunet_water(rtol=1e-5):
    """FONSim's test_02 (water): source at 0.2 bar gauge, a 2 mm × 0.1 m tube (ε 0.0015 mm),
    two accumulators k = 10¹⁰ Pa/m³ holding 1 and 5 mL at its end (0.3 bar gauge together),
    1 s: (node pressure on GRID in kPa gauge, seconds)."""
    from pneunet import Circuit, Liquid

    water = Liquid("fonsim_water", *FONSIM_WATER, bulk_modulus=2.2e6)
    c = Circuit("water", ambient=P_ATM / 1e3, fluid=water, rtol=rtol, atol=rtol)
    c.pressure_source("P1", "s", "20kPag")
    c.tube("T1", "s", "x", length="0.1m", diameter="2mm", roughness="0.0015mm", segments=1)
    for name in ("A0", "A1"):  # p = k·v + p_atm: 0.1 mL/kPa, 1 mL at 10 kPa gauge
        c.accumulator(name, "x", V0=1.0, k=0.1, pref="10kPag", p0="30kPag")
    start = time.perf_counter()
    sol = c.tran(1.0, t_step=0.01)
    seconds = time.perf_counter() - start
    return np.interp(GRID[GRID <= 1.0], sol.t, sol.pressure("x")) - P_ATM / 1e3, seconds


def fonsim_water():
    """The same in FONSim (its own test, CircularTube's laminar–Haaland blend), or None."""
    try:
        import fonsim as fons
    except ImportError:
        return None
    system = fons.System("water")
    system.add(fons.PressureSource("src", pressure=fons.cnorm.pressure_atmospheric + 0.2e5),
               fons.CircularTube("tube", fons.water, diameter=2e-3, length=0.1))
    for label, ml in (("a0", 1.0), ("a1", 5.0)):
        acc = fons.LinearAccumulator(label, fluid=fons.water, k=1e5 / 10e-6, v0=0,
                                     p0=fons.cnorm.pressure_atmospheric)
        acc.states[0].initial_value = ml * 1e-6 * fons.water.rho
        system.add(acc)
    system.connect("src", "tube")
    system.connect("a0", "tube")
    system.connect(("a0", "a"), ("a1", "a"))
    sim, seconds = _run_quietly(fons, system, 1.0, (1e-4, 1e-2))
    p = system.get("a0").get("pressure")
    return np.interp(GRID[GRID <= 1.0], sim.times, p / 1e3) - fons.cnorm.pressure_atmospheric / 1e3, \
        seconds


BALLOON_TIMES = [0.0, 0.5, 3.0, 3.2, 4.0, 4.2, 8.0]
BALLOON_GAUGE_KPA = [0.0, 65.0, 65.0, 89.0, 89.0, 65.0, 65.0]


def _balloon_curve():
    """FONSim's packaged 60 mm balloon (volume mL, pressure mbar) as FONSim reads it
    (autocorrect: V from 0, p from 0 gauge): (V mL, p kPa gauge), or None without FONSim."""
    try:
        import importlib.resources as resources
        text = (resources.files("fonsim") / "resources" /
                "Measurement_60mm_balloon_actuator_01.csv").read_text()
    except (ImportError, ModuleNotFoundError, FileNotFoundError):
        return None
    rows = np.array([[float(x) for x in line.split(",")] for line in text.splitlines()[3:]
                     if line.strip()])
    return rows[:, 1] - rows[0, 1], (rows[:, 2] - rows[0, 2]) / 10.0


def pneunet_balloon(curve, t_stop=8.0, rtol=1e-5):
    """The balloon behind a FlowRestrictor (d 0.5 mm, K 0.6) under 65 kPa gauge, a pulse to
    89 kPa (over its 87 kPa peak) from 3 to 4.2 s: ((V before, V after) mL, volume on the
    GRID, seconds)."""
    from pneunet import Circuit
    from pneunet.physics.waveforms import PiecewiseLinear

    amb = P_ATM / 1e3
    r = 4 / (math.pi * D ** 2) * math.sqrt(K_FACTOR * P_ATM / RHO_STP) * 1e-9
    c = Circuit("balloon", ambient=amb, temperature=_matched_temperature(), rtol=rtol,
                atol=rtol)
    c.pressure_source("P1", "s", PiecewiseLinear(BALLOON_TIMES,
                                                 [amb + g for g in BALLOON_GAUGE_KPA]))
    c.resistor("R1", "s", "b", R=r)
    volume, gauge = curve
    c.pv_volume("B1", "b", table=(gauge + amb, volume + 1e-3), V0=1e-3)  # V > 0: 1 µL more
    start = time.perf_counter()
    sol = c.tran(t_stop, t_step=0.01)
    seconds = time.perf_counter() - start
    v = sol.signals["volume_B1"] - 1e-3
    grid = np.arange(0.0, t_stop + 1e-9, 0.01)
    return (np.interp(2.9, sol.t, v), v[-1]), np.interp(grid, sol.t, v), seconds


def fonsim_balloon(t_stop=8.0):
    """The same in FONSim (FreeActuator, its curve linear between the points), or None."""
    try:
        import fonsim as fons
    except ImportError:
        return None
    atm = fons.cnorm.pressure_atmospheric
    system = fons.System("balloon")
    system.add(fons.PressureSource("src", pressure=lambda t: atm + 1e3 * np.interp(
                   t, BALLOON_TIMES, BALLOON_GAUGE_KPA)),
               fons.FlowRestrictor("r", fluid=fons.air, diameter=D, k=K_FACTOR),
               fons.FreeActuator("b", fluid=fons.air))
    system.connect("src", "r")
    system.connect("r", "b")
    sim, seconds = _run_quietly(fons, system, t_stop, (1e-4, 1e-2))
    mass = system.get("b").get_state("mass")
    p = system.get("b").get("pressure", "a")
    v = mass / fons.air.rho_stp * atm / p * 1e6  # mL
    grid = np.arange(0.0, t_stop + 1e-9, 0.01)
    return (np.interp(2.9, sim.times, v), v[-1]), np.interp(grid, sim.times, v), seconds


def issue34_table(have_fonsim):
    """The water line and the balloon: times and differences."""
    ours, ours_s = pneunet_water()
    print("\nwater, two accumulators through a 2 mm × 0.1 m tube (FONSim's test_02), 1 s")
    print("| simulator | s | p(0.05 s) kPag | p(0.2 s) kPag | differs from pneunet by |")
    print("|---|---|---|---|---|")
    at = (lambda p, t: p[int(round(t / 0.01))])
    print(f"| pneunet | {ours_s:.3f} | {at(ours, 0.05):.3f} | {at(ours, 0.2):.3f} | — |")
    theirs = fonsim_water() if have_fonsim else None
    if theirs:
        worst = np.max(np.abs(theirs[0] - ours)[1:])  # FONSim's t = 0: before its accumulators meet
        print(f"| FONSim | {theirs[1]:.3f} | {at(theirs[0], 0.05):.3f} | "
              f"{at(theirs[0], 0.2):.3f} | {worst:.3f} kPa ({worst / 10:.1%} of the swing) |")
    curve = _balloon_curve()
    if curve is None:
        print("\nballoon: FONSim's measured curve needs FONSim installed; skipped")
        return
    print("\nballoon (FONSim's 60 mm curve) behind a restrictor: 65 kPag, pulse to 89 kPag, 8 s")
    print("| simulator | s | V at 2.9 s mL | V at 8 s mL | differs from pneunet by |")
    print("|---|---|---|---|---|")
    (before, after), v_ours, seconds = pneunet_balloon(curve)
    print(f"| pneunet | {seconds:.3f} | {before:.2f} | {after:.2f} | — |")
    theirs = fonsim_balloon() if have_fonsim else None
    if theirs:
        (b2, a2), v_theirs, s2 = theirs
        print(f"| FONSim | {s2:.3f} | {b2:.2f} | {a2:.2f} | "
              f"{np.max(np.abs(v_theirs - v_ours)):.2f} mL at most |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1,10,30,100,300,1000,10000")
    parser.add_argument("--fonsim-max", type=int, default=30,
                        help="largest N given to FONSim (its time grows fast with N)")
    args = parser.parse_args(argv)
    try:
        import fonsim  # noqa: F401
        have_fonsim = True
    except ImportError:
        have_fonsim = False
        print("note: FONSim is not installed (pip install fonsim): its columns are empty")
    print("| N | pneunet s | pneunet error kPa | FONSim s | FONSim error kPa |")
    print("|---|---|---|---|---|")
    pneunet_chain(1)  # warm up: imports and first-call costs
    for n in (int(s) for s in args.sizes.split(",")):
        ref, _ = pneunet_chain(n, rtol=1e-10) if n <= 1000 else (None, None)
        ours, ours_s = pneunet_chain(n)
        theirs = fonsim_chain(n) if have_fonsim and n <= args.fonsim_max else None
        err = (lambda p: f"{np.max(np.abs(p - ref)):.2g}" if ref is not None else "—")
        cells = [f"{ours_s:.2f}", err(ours)]
        cells += [f"{theirs[1]:.2f}", err(theirs[0])] if theirs else ["—", "—"]
        print(f"| {n} | " + " | ".join(cells) + " |", flush=True)
    oscillator_table(have_fonsim)
    issue34_table(have_fonsim)


if __name__ == "__main__":
    main()
