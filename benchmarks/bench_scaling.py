"""Scaling benchmark: N identical valve cells on one supply line (issue 2, item 6).

Each cell k has
  * a control pressure source  PULSE(ambient → 400 kPa, rise/fall 50 ms, 2 s high,
    period 4 s) whose delay is staggered over ``PHASES`` groups (0.25 s apart),
  * a control volume (10 mL) fed from it through a resistor (R 5 kPa·s/mg),
  * an axi membrane valve from the shared supply line to the actuator volume
    (50 mL), controlled by the control volume (normally open: a high control
    pressure closes it),
  * a vent resistor (R 3) from the actuator to atm.
The supply line is a volume (20 mL per cell) fed from a 496 kPa source through a
resistor of 0.3/N kPa·s/mg, so every cell sees the same line dynamics whatever N.
Every node has a volume: the same equations are an ODE ṗ = −F(t, p)/C, which
scipy's BDF integrates with the same analytic sparse Jacobian, and a SPICE
netlist (volumes as capacitors, laws as behavioural current sources with the
same regularisation sr(d) = d/(d²+ε²)^¼), which ngspice integrates.

Switching times are staggered over a fixed number of phase groups, not per
cell: a solver with one global step must resolve every switching edge, so with
N distinct edges the step count grows with N and any such solver costs ~N².

Run:  python benchmarks/bench_scaling.py [--quick] [--sizes 10,100,1000,3000]
          [--rtol 1e-5] [--ngspice-max 1000] [--no-scipy] [--no-ngspice] [--oscillator]
      python benchmarks/bench_scaling.py --schedule independent|groups
          [--sizes 100,300,1000,3000,10000] [--rtol 5e-6] [--single-max 3000] [--repeat 5]
          (multirate against single-rate IDA: benchmarks/scaling_schedules.py)
      python benchmarks/bench_scaling.py --schedule compare [--sizes 3000] [--repeat 3]
          (the same cells switched independently against on 8 phase groups, as a user
          runs them: method auto, alternating fresh processes; issue 35)
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

T_STOP = 10.0
PHASES = 8
AMBIENT = 101.325
P_SUPPLY = 496.0
P_CTRL_HIGH = 400.0


# -- the network ---------------------------------------------------------------------------
def build(n, rtol=1e-5, atol=1e-5, delays=None, method="auto"):
    """The network of N cells; ``delays`` (n,) s: each cell's control delay (default:
    staggered over PHASES groups)."""
    from pneunet import Circuit
    from pneunet.physics.waveforms import Pulse

    if delays is None:
        delays = 0.25 * (np.arange(n) % PHASES) + 0.2
    c = Circuit(f"scaling N={n}", rtol=rtol, atol=atol, ambient=AMBIENT, method=method)
    c.pressure_source("PS", "sup", P_SUPPLY)
    c.resistor("RS", "sup", "line", R=0.3 / n)
    c.volume("VL", "line", V=f"{20 * n}mL", p0=P_SUPPLY)
    for k, delay in enumerate(delays):
        c.pressure_source(f"PC{k}", f"c{k}", Pulse(AMBIENT, P_CTRL_HIGH, delay=delay, rise=0.05,
                                                  fall=0.05, width=2.0, period=4.0))
        c.resistor(f"RC{k}", f"c{k}", f"ctl{k}", R=5.0)
        c.volume(f"VC{k}", f"ctl{k}", V="10mL")
        c.valve(f"X{k}", "line", f"act{k}", f"ctl{k}", model="axi")
        c.volume(f"VA{k}", f"act{k}", V="50mL")
        c.resistor(f"RV{k}", f"act{k}", "atm", R=3.0)
    return c


def actuators(n):
    return [f"act{k}" for k in range(n)]


def check_times(n):
    """Source corners in [1 s, T_STOP] and T_STOP: every solver lands on them exactly."""
    from pneunet.engine.assembly import CircuitDAE

    corners = CircuitDAE(build(min(n, PHASES))).breakpoints(1.0, T_STOP)
    return np.append(corners, T_STOP)


def sample(t, values, times):
    """Rows of ``values`` (n_t, m) at the given times (the last row at each time)."""
    idx = [np.flatnonzero(np.abs(t - x) <= 1e-9 * T_STOP) for x in times]
    missing = [x for x, i in zip(times, idx) if not i.size]
    if missing:
        raise RuntimeError(f"no output at t = {missing[:3]} s")
    return values[[i[-1] for i in idx]]


# -- pneunet --------------------------------------------------------------------------------
def run_pneunet(n, rtol, backend="sksundae"):
    from pneunet.engine.simulate import transient

    circuit = build(n, rtol)
    t0 = time.perf_counter()
    sol = transient(circuit, T_STOP, backend=backend)
    wall = time.perf_counter() - t0
    acts = np.column_stack([sol.pressure(a) for a in actuators(n)])
    return dict(wall=wall, solver=sol.stats["wall_time_s"], samples=sample(sol.t, acts, check_times(n)),
                steps=len(sol.t) - 1, res=sol.stats["residual_calls"],
                jac=sol.stats["jacobian_calls"])


# -- scipy solve_ivp BDF on the same equations ---------------------------------------------
def run_scipy(n, rtol, atol):
    from scipy.integrate import solve_ivp
    from scipy.sparse import diags

    from pneunet.engine.assembly import CircuitDAE

    circuit = build(n, rtol)
    t0 = time.perf_counter()  # from the same point as pneunet's: assembling the equations
    dae = CircuitDAE(circuit)
    assert dae.differential.all()
    y = dae.initial_state(0.0)
    zeros = np.zeros(dae.n)
    inv_c = diags(1.0 / dae.capacitance(0.0, y))  # isothermal volumes: C is constant
    calls = {"f": 0, "j": 0}

    def f(t, p):
        calls["f"] += 1
        return -(inv_c @ dae.evaluate(t, p, zeros)[0])

    def jac(t, p):
        calls["j"] += 1
        return -(inv_c @ dae.csc(dae.evaluate(t, p, zeros, cj=0.0)[1]))

    stops = np.unique(np.concatenate([[0.0], dae.breakpoints(0.0, T_STOP), [T_STOP]]))
    steps = 0
    ends = []
    for a, b in zip(stops[:-1], stops[1:]):  # restart on every source corner, as IDA stops there
        r = solve_ivp(f, (a, b), y, method="BDF", jac=jac, rtol=rtol, atol=atol)
        if not r.success:
            raise RuntimeError(f"scipy BDF failed at t = {r.t[-1]}: {r.message}")
        y = r.y[:, -1]
        ends.append(y)
        steps += len(r.t) - 1
    wall = time.perf_counter() - t0
    acts = np.array(ends)[:, [dae.node_index(a) for a in actuators(n)]]
    return dict(wall=wall, samples=sample(stops[1:], acts, check_times(n)), steps=steps,
                res=calls["f"], jac=calls["j"])


# -- ngspice -------------------------------------------------------------------------------
def _sr(a, b, band):
    """SPICE expression of sr(a² − b²) with the circuit's flow band."""
    d = f"(v({a})*v({a})-v({b})*v({b}))"
    return f"{d}/pwr({d}*{d}+{band * band:.10g},0.25)"


def spice_name(node: str) -> str:
    """A node name SPICE accepts (references become ``atm``)."""
    return "atm" if node in ("0", "gnd", "atm") else re.sub(r"[^A-Za-z0-9_]", "_", node)


def _valve_conductance(v, i, o, c):
    """SPICE expression of the valve conductance G(Δp) (eq. 19) for ValveParams ``v``."""
    hi, lo = f"max(v({i}),v({o}))", f"min(v({i}),v({o}))"
    u = (f"max({v.ain:.10g}*{hi}+{v.aout:.10g}*{lo}-v({c})-{v.pclose:.10g},0)"
         f"/{v.ptrans - v.pclose:.10g}")
    ue = f"pwr({u},{v.e:.10g})"  # never a parameter named e: SPICE reads it as 2.718
    return f"{ue}/({v.Rf:.10g}*sqrt(1+{ue}*{ue}))"


def spice_netlist(circuit, reltol, t_step, t_stop=T_STOP, dead_capacitance=0.0):
    """The circuit as a SPICE deck: kPa as volts, mg/s as amperes, mg/kPa as farads.

    Volumes and actuators (isothermal) are capacitors, resistors and valves
    B-sources with the same regularised root; a valve with a ``backward`` model
    switches parameters where p_out > p_in, as pneunet does.  ``dead_capacitance``
    (mg/kPa) adds a capacitor at every unknown node without a volume (ngspice
    cannot step across the folds of an algebraic node).  Every unknown node starts
    (``uic``) at pneunet's consistent initial state.
    """
    from pneunet.engine.assembly import CircuitDAE
    from pneunet.engine.simulate import consistent_state

    dae = CircuitDAE(circuit)
    y0, _ = consistent_state(dae, 0.0, dae.initial_state(0.0))
    band = circuit.options.flow_band
    gas, temperature = circuit.options.gas_model, circuit.options.temperature
    lines = [f"* {circuit.title}", f"VATM atm 0 {circuit.options.ambient}"]
    stored = set()
    for e in circuit.elements.values():
        p = e.params
        nd = [spice_name(x) for x in e.nodes]
        name = spice_name(e.name)
        if e.kind == "pressure_source":
            w = p["value"]
            src = w.netlist() if hasattr(w, "netlist") else f"DC {w}"
            lines.append(f"V{name} {nd[0]} 0 {src}")
        elif e.kind == "resistor":
            lines.append(f"B{name} {nd[0]} {nd[1]} I={_sr(nd[0], nd[1], band)}/{p['R']:.10g}")
        elif e.kind in ("volume", "actuator"):
            if p["n"] != 1.0:
                raise ValueError(f"element {e.name}: only isothermal volumes translate to ngspice")
            volume = p["V"] if np.isfinite(p["V"]) else \
                np.pi / 4 * p["diameter"] ** 2 * p["length"] * 1e-3
            lines.append(f"C{name} {nd[0]} 0 {gas.capacitance(volume, temperature):.10g}")
            stored.add(e.nodes[0])
        elif e.kind == "valve":
            i, o, c = nd
            flow = f"{_valve_conductance(p['model'], i, o, c)}*{_sr(i, o, band)}"
            if p["backward"]:
                back = f"{_valve_conductance(p['backward'], i, o, c)}*{_sr(i, o, band)}"
                flow = f"(v({i})>=v({o}) ? {flow} : {back})"
            lines.append(f"B{name} {i} {o} I={flow}")
        else:
            raise ValueError(f"element {e.name}: kind {e.kind!r} has no ngspice translation "
                             "in this benchmark")
    if dead_capacitance > 0:
        lines += [f"CDEAD_{spice_name(x)} {spice_name(x)} 0 {dead_capacitance:g}"
                  for x in dae.node_names if x not in stored]
    ics = [f"v({spice_name(x)})={v:.10g}" for x, v in zip(dae.node_names, y0)]
    lines += [".ic " + " ".join(ics[i:i + 50]) for i in range(0, len(ics), 50)]
    lines += [f".options reltol={reltol:g} abstol=1e-6 vntol=1e-6 chgtol=1e-12 itl4=50",
              f".tran {t_step:g} {t_stop:g} uic", ".end"]
    return "\n".join(lines) + "\n"


def spice_control(names, raw):
    return (".control\nset noaskquit\nset filetype=ascii\nrun\n"
            f"wrdata {raw} " + " ".join(f"v({x})" for x in names) + "\nrusage all\n.endc\n")


def run_ngspice(circuit, names, reltol, t_step=0.1):
    exe = shutil.which("ngspice")
    if exe is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        deck = os.path.join(tmp, "deck.cir")
        raw = os.path.join(tmp, "out.txt")
        text = spice_netlist(circuit, reltol, t_step)
        text = text.replace(".end\n", spice_control(names, raw) + ".end\n")
        with open(deck, "w") as fh:
            fh.write(text)
        t0 = time.perf_counter()
        proc = subprocess.run([exe, "-b", deck], capture_output=True, text=True)
        wall = time.perf_counter() - t0
        # ngspice -b exits 1 after some successful runs: judge by the data it wrote
        data = np.loadtxt(raw, ndmin=2) if os.path.exists(raw) else np.zeros((1, 1))
        if abs(data[-1, 0] - T_STOP) > 1e-9 * T_STOP:
            raise RuntimeError("ngspice failed:\n" + proc.stdout[-2000:] + proc.stderr[-2000:])
    samples = sample(data[:, 0], data[:, 1::2], check_times(len(names)))
    m = re.search(r"Total analysis time \(seconds\) = ([\d.]+)", proc.stdout + proc.stderr)
    steps = re.search(r"Transient timepoints\s*=\s*(\d+)", proc.stdout + proc.stderr)
    return dict(wall=wall, analysis=float(m.group(1)) if m else np.nan, samples=samples,
                steps=int(steps.group(1)) if steps else -1)


# -- report --------------------------------------------------------------------------------
def agreement(a, b):
    """Largest relative difference of actuator pressures over all check times."""
    return float(np.max(np.abs(a - b) / np.abs(b)))


def exponent(sizes, times):
    return [np.log(times[i + 1] / times[i]) / np.log(sizes[i + 1] / sizes[i])
            for i in range(len(sizes) - 1)]


def mean_period(t, p, settle=10.0):
    """Mean period (s) of upward crossings of the mid level after ``settle``."""
    late = t > settle
    level = 0.5 * (p[late].min() + p[late].max())
    i = np.flatnonzero(late[:-1] & (p[:-1] < level) & (p[1:] >= level))
    crossings = t[i] + (level - p[i]) / (p[i + 1] - p[i]) * (t[i + 1] - t[i])
    return float(np.mean(np.diff(crossings)))


def best_of(run, k=3):
    times = []
    for _ in range(k):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return min(times)


def oscillator_process_time(period_rtol=1e-3):
    """Whole-process time of the 30 s oscillator: `pneunet run` vs ngspice at matched accuracy.

    ngspice needs a dead volume at the valve output (without one it aborts at the
    first fold, "timestep too small"), and its period converges to the jump
    period only as that volume shrinks: it gets the largest dead volume and
    loosest reltol whose period is within ``period_rtol`` of pneunet's at rtol 1e-8.
    """
    from pneunet.design.paper_circuits import oscillator

    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    netlist = os.path.join(repo, "netlists", "oscillator.pn")
    env = dict(os.environ, PYTHONPATH=repo + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory() as tmp:
        t_py = best_of(lambda: subprocess.run(
            [sys.executable, "-m", "pneunet", "run", netlist, "-o", tmp], check=True,
            capture_output=True, env=env))
    how = "pneunet run netlists/oscillator.pn (CSV of 3000 points + 5 .meas)"
    exe = shutil.which("ngspice")
    if exe is None:
        return how, t_py, None, None
    reference = oscillator(valve="axi_0p6mm", rtol=1e-8, atol=1e-8).tran(30.0)
    ref_period = mean_period(reference.t, reference.pressure("tank"))
    for dead_ml, reltol in ((0.05, 1e-4), (0.05, 1e-5), (0.01, 1e-5), (0.002, 1e-5),
                            (0.002, 1e-6), (0.0005, 1e-6)):
        c = oscillator(valve="axi_0p6mm", V_out=dead_ml)
        text = spice_netlist(c, reltol, 0.01, t_stop=30.0)
        with tempfile.TemporaryDirectory() as tmp:
            path, raw = os.path.join(tmp, "osc.cir"), os.path.join(tmp, "out.txt")
            with open(path, "w") as fh:
                fh.write(text.replace(".end\n", ".control\nset noaskquit\nset filetype=ascii\n"
                                      f"run\nwrdata {raw} v(tank)\n.endc\n.end\n"))
            t_sp = best_of(lambda: subprocess.run([exe, "-b", path], capture_output=True))
            data = np.loadtxt(raw, ndmin=2) if os.path.exists(raw) else np.zeros((1, 2))
        if abs(data[-1, 0] - 30.0) > 1e-6:  # "timestep too small": ngspice gave up
            print(f"  ngspice oscillator, dead volume {dead_ml:g} mL, reltol {reltol:g}: "
                  f"failed at t = {data[-1, 0]:.3g} s")
            continue
        error = abs(mean_period(data[:, 0], data[:, 1]) / ref_period - 1)
        setting = f"dead volume {dead_ml:g} mL, reltol {reltol:g}: period error {error:.1e}"
        print(f"  ngspice oscillator, {setting}, {t_sp:.2f} s")
        if error <= period_rtol:
            return how, t_py, t_sp, setting
    return how, t_py, t_sp, setting + " (target accuracy not reached)"


LADDERS = {  # tolerances tried, loosest first, when calibrating to the target error
    "pneunet": [1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6],
    "scipy": [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6],
    "ngspice": [1e-3, 3e-4, 1e-4, 3e-5, 1e-5],
}


def runners(have_spice, no_scipy):
    out = {"pneunet": lambda n, tol: run_pneunet(n, tol)}
    if not no_scipy:
        out["scipy"] = lambda n, tol: run_scipy(n, tol, 1e-5)
    if have_spice:
        out["ngspice"] = lambda n, tol: run_ngspice(build(n), actuators(n), tol)
    return out


def calibrate(tools, n, reference, target, fixed):
    """Per tool, the loosest tolerance whose error at N = n is within ``target``."""
    chosen = {}
    print(f"\ncalibration at N={n}: error = max relative deviation of all actuator pressures "
          f"at {len(check_times(n))} source corners from pneunet at rtol 1e-9; target ≤ {target:g}")
    for name, run in tools.items():
        if fixed.get(name) is not None:
            chosen[name] = fixed[name]
            print(f"  {name:8s} tolerance {fixed[name]:g} (given)")
            continue
        for tol in LADDERS[name]:
            r = run(n, tol)
            err = agreement(r["samples"], reference)
            print(f"  {name:8s} tolerance {tol:<7g} error {err:.2e}  wall {r['wall']:.2f} s")
            chosen[name] = tol
            if err <= target:
                break
        else:
            print(f"  {name:8s} no tolerance reached the target: using the tightest")
    return chosen


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,100,1000,3000")
    ap.add_argument("--quick", action="store_true", help="sizes 10,100")
    ap.add_argument("--target-error", type=float, default=5e-4,
                    help="accuracy every tool is tuned to (matched accuracy)")
    ap.add_argument("--calibrate-n", type=int, default=100, help="N used to tune tolerances")
    ap.add_argument("--rtol", type=float, help="pneunet rtol (skips its calibration)")
    ap.add_argument("--scipy-rtol", type=float, help="scipy rtol (skips its calibration)")
    ap.add_argument("--spice-reltol", type=float, help="ngspice reltol (skips its calibration)")
    ap.add_argument("--ngspice-max", type=int, default=3000, help="largest N run in ngspice")
    ap.add_argument("--scipy-max", type=int, default=3000, help="largest N run in scipy")
    ap.add_argument("--no-scipy", action="store_true")
    ap.add_argument("--no-ngspice", action="store_true")
    ap.add_argument("--reference", type=int, default=100,
                    help="largest N with a tight-tolerance pneunet reference (rtol 1e-9)")
    ap.add_argument("--oscillator", action="store_true",
                    help="also time the small oscillator as whole processes")
    ap.add_argument("--schedule", choices=("independent", "groups", "compare"),
                    help="compare the multirate method with single-rate IDA on this control "
                         "schedule (issue 18) instead")
    ap.add_argument("--single-max", type=int, default=3000,
                    help="with --schedule: largest N run single-rate")
    ap.add_argument("--reference-max", type=int, default=300,
                    help="with --schedule: largest N with an rtol 1e-8 reference")
    ap.add_argument("--repeat", type=int, default=1,
                    help="with --schedule: multirate runs per N (median shown)")
    args = ap.parse_args(argv)
    if args.schedule == "compare":  # issue 35 item 3: independent against groups, N cells
        from scaling_schedules import compare

        return compare(int(args.sizes.split(",")[-1]) if args.sizes else 3000,
                       args.rtol or 5e-6, args.repeat if args.repeat > 1 else 3)
    if args.schedule:
        from scaling_schedules import study

        sizes = [100, 300] if args.quick else [int(s) for s in (
            args.sizes if args.sizes != "10,100,1000,3000" else "100,300,1000,3000,10000").split(",")]
        return study(sizes, args.schedule, args.rtol or 5e-6, args.single_max, args.reference_max,
                     args.repeat)
    sizes = [10, 100] if args.quick else [int(s) for s in args.sizes.split(",")]
    have_spice = shutil.which("ngspice") is not None and not args.no_ngspice
    if not have_spice and not args.no_ngspice:
        print("note: ngspice not found (apt-get install -y ngspice): ngspice columns skipped")
    run_pneunet(1, 1e-5)  # warm-up: imports (sksundae, scipy, networkx) are not timed

    tools = runners(have_spice, args.no_scipy)
    print(f"{T_STOP:g} s of N valve cells; {os.cpu_count()} cores (shared); wall times exclude "
          f"imports; ngspice abstol 1e-6, scipy atol 1e-5, pneunet atol 1e-5")
    references = {}

    def reference(n):
        if n not in references:
            references[n] = run_pneunet_reference(n)
        return references[n]
    fixed = {"pneunet": args.rtol, "scipy": args.scipy_rtol, "ngspice": args.spice_reltol}
    need = [k for k in tools if fixed.get(k) is None]
    tol = calibrate(tools, args.calibrate_n, reference(args.calibrate_n) if need else None,
                    args.target_error, fixed)
    rows = []
    for n in sizes:
        row = {"N": n}
        print(f"\nN={n:5d} unknowns={2 * n + 1}")
        ref = reference(n) if n <= args.reference else None
        for name, run in tools.items():
            limit = {"scipy": args.scipy_max, "ngspice": args.ngspice_max}.get(name, n)
            if n > limit:
                continue
            r = row[name] = run(n, tol[name])
            msg = f"  {name:8s}: {r['wall']:8.2f} s  tolerance {tol[name]:g}  steps {r['steps']}"
            if name == "pneunet":
                msg += (f" (solver {r['solver']:.2f} s)  residual calls {r['res']}  "
                        f"Jacobian calls {r['jac']}")
            else:
                pn = row["pneunet"]
                msg += (f"  agreement with pneunet {agreement(r['samples'], pn['samples']):.2e}"
                        f"  time ratio {name}/pneunet {r['wall'] / pn['wall']:.1f}×")
            if ref is not None:
                msg += f"  error {agreement(r['samples'], ref):.2e}"
            print(msg)
            sys.stdout.flush()
        rows.append(row)
    if len(sizes) > 1:
        print("\ngrowth exponents (log time ratio / log N ratio) between successive sizes:")
        for name in tools:
            have = [(r["N"], r[name]["wall"]) for r in rows if name in r]
            if len(have) > 1:
                ex = exponent([h[0] for h in have], [h[1] for h in have])
                print(f"  {name:8s} " + "  ".join(f"{have[i][0]}→{have[i + 1][0]}: {x:.2f}"
                                                 for i, x in enumerate(ex)))
        big = [r for r in rows if r["N"] >= 100]
        if len(big) > 1:
            a, b = big[0], big[-1]
            print(f"  pneunet {a['N']}→{b['N']}: {np.log(b['pneunet']['wall'] / a['pneunet']['wall']) / np.log(b['N'] / a['N']):.2f} (target ≤ 1.1)")
    if args.oscillator:
        print("\nsmall oscillator, whole process, best of 3 (period within 0.1 % of rtol 1e-8):")
        how, t_py, t_sp, setting = oscillator_process_time()
        print(f"  {how}: {t_py:.2f} s")
        if t_sp is not None:
            print(f"  ngspice -b ({setting}): {t_sp:.2f} s   ratio {t_py / t_sp:.1f}× (target ≤ 2×)")
    return rows


def run_pneunet_reference(n):
    from pneunet.engine.simulate import transient

    sol = transient(build(n, 1e-9, 1e-9), T_STOP)
    acts = np.column_stack([sol.pressure(a) for a in actuators(n)])
    return sample(sol.t, acts, check_times(n))


if __name__ == "__main__":
    main()
