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
def build(n, rtol=1e-5, atol=1e-5):
    from pneunet import Circuit
    from pneunet.waveforms import Pulse

    c = Circuit(f"scaling N={n}", rtol=rtol, atol=atol, ambient=AMBIENT)
    c.pressure_source("PS", "sup", P_SUPPLY)
    c.resistor("RS", "sup", "line", R=0.3 / n)
    c.volume("VL", "line", V=f"{20 * n}mL", p0=P_SUPPLY)
    for k in range(n):
        delay = 0.25 * (k % PHASES) + 0.2
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


# -- pneunet --------------------------------------------------------------------------------
def run_pneunet(n, rtol, backend="sksundae"):
    from pneunet.simulate import transient

    circuit = build(n, rtol)
    t0 = time.perf_counter()
    sol = transient(circuit, T_STOP, backend=backend)
    wall = time.perf_counter() - t0
    final = np.array([sol.pressure(a)[-1] for a in actuators(n)])
    return dict(wall=wall, solver=sol.stats["wall_time_s"], final=final,
                steps=len(sol.t) - 1, res=sol.stats["residual_calls"],
                jac=sol.stats["jacobian_calls"])


# -- scipy solve_ivp BDF on the same equations ---------------------------------------------
def run_scipy(n, rtol, atol):
    from scipy.integrate import solve_ivp
    from scipy.sparse import diags

    from pneunet.assembly import CircuitDAE

    dae = CircuitDAE(build(n, rtol))
    assert dae.differential.all()
    t0 = time.perf_counter()
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
    for a, b in zip(stops[:-1], stops[1:]):  # restart on every source corner, as IDA stops there
        r = solve_ivp(f, (a, b), y, method="BDF", jac=jac, rtol=rtol, atol=atol)
        if not r.success:
            raise RuntimeError(f"scipy BDF failed at t = {r.t[-1]}: {r.message}")
        y = r.y[:, -1]
        steps += len(r.t) - 1
    wall = time.perf_counter() - t0
    final = y[[dae.node_index(a) for a in actuators(n)]]
    return dict(wall=wall, final=final, steps=steps, res=calls["f"], jac=calls["j"])


# -- ngspice -------------------------------------------------------------------------------
def _sr(a, b, band):
    """SPICE expression of sr(a² − b²) with the circuit's flow band."""
    d = f"(v({a})*v({a})-v({b})*v({b}))"
    return f"{d}/pwr({d}*{d}+{band * band:.10g},0.25)"


def spice_netlist(circuit, reltol, t_step, t_stop=T_STOP):
    """The circuit as a SPICE deck: kPa as volts, mg/s as amperes, mg/kPa as farads."""
    from pneunet.assembly import CircuitDAE

    dae = CircuitDAE(circuit)
    band = circuit.options.flow_band
    cap = dae.capacitance(0.0, dae.initial_state(0.0))
    node = {name: name for name in circuit.nodes}
    for ref in ("0", "gnd", "atm"):
        node[ref] = "atm"
    lines = [f"* {circuit.title}", f"VATM atm 0 {circuit.options.ambient}"]
    ics = []
    for e in circuit.elements.values():
        p = e.params
        nd = [node[x] for x in e.nodes]
        if e.kind == "pressure_source":
            w = p["value"]
            src = w.netlist() if hasattr(w, "netlist") else f"DC {w}"
            lines.append(f"V{e.name} {nd[0]} 0 {src}")
        elif e.kind == "resistor":
            lines.append(f"B{e.name} {nd[0]} {nd[1]} I={_sr(nd[0], nd[1], band)}/{p['R']:.10g}")
        elif e.kind == "volume":
            i = dae.node_index(e.nodes[0])
            lines.append(f"C{e.name} {nd[0]} 0 {cap[i]:.10g}")
            p0 = p["p0"] if np.isfinite(p["p0"]) else circuit.options.ambient
            ics.append(f"v({nd[0]})={p0:.10g}")
        elif e.kind == "valve":
            v = p["model"]
            i, o, c = nd
            hi, lo = f"max(v({i}),v({o}))", f"min(v({i}),v({o}))"
            u = (f"max({v.ain:.10g}*{hi}+{v.aout:.10g}*{lo}-v({c})-{v.pclose:.10g},0)"
                 f"/{v.ptrans - v.pclose:.10g}")
            ue = f"pwr({u},{v.e:.10g})"  # never a parameter named e: SPICE reads it as 2.718
            lines.append(f"B{e.name} {i} {o} I={ue}/({v.Rf:.10g}*sqrt(1+{ue}*{ue}))"
                         f"*{_sr(i, o, band)}")
        else:
            raise ValueError(f"element {e.name}: kind {e.kind!r} has no ngspice translation "
                             "in this benchmark")
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
    final = data[-1, 1::2]
    m = re.search(r"Total analysis time \(seconds\) = ([\d.]+)", proc.stdout + proc.stderr)
    steps = re.search(r"Transient timepoints\s*=\s*(\d+)", proc.stdout + proc.stderr)
    return dict(wall=wall, analysis=float(m.group(1)) if m else np.nan, final=final,
                steps=int(steps.group(1)) if steps else -1)


# -- report --------------------------------------------------------------------------------
def agreement(a, b):
    return float(np.max(np.abs(a - b) / np.abs(b)))


def exponent(sizes, times):
    return [np.log(times[i + 1] / times[i]) / np.log(sizes[i + 1] / sizes[i])
            for i in range(len(sizes) - 1)]


def oscillator_process_time(reltol):
    """Whole-process time of the small oscillator: `pneunet run` (or python -c) vs ngspice."""
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    netlist = os.path.join(repo, "netlists", "oscillator.pn")
    env = dict(os.environ, PYTHONPATH=repo + os.pathsep + os.environ.get("PYTHONPATH", ""))
    if os.path.exists(netlist):  # 30 s of the R_out = 2R_f oscillator
        cmd, how = [sys.executable, "-m", "pneunet", "run", netlist], "pneunet run netlists/oscillator.pn"
    else:
        code = ("from pneunet import Circuit\n"
                "c=Circuit('osc')\nc.pressure_source('PH','supply',496)\n"
                "c.valve('X1','supply','out','tank',model='axi')\n"
                "c.resistor('Rout','out','tank',R=1.132)\nc.volume('V1','tank',V='200mL')\n"
                "c.pressure_source('PL','low',96)\nc.resistor('Rvent','tank','low',R=3)\n"
                "s=c.tran(30)\nprint(s.pressure('tank')[-1])\n")
        cmd, how = [sys.executable, "-c", code], "python -c (Python API; netlists/oscillator.pn missing)"

    def best_of(run, k=3):
        times = []
        for _ in range(k):
            t0 = time.perf_counter()
            run()
            times.append(time.perf_counter() - t0)
        return min(times)

    def py():
        subprocess.run(cmd, check=True, capture_output=True, env=env)
    t_py = best_of(py)
    t_sp = None
    exe = shutil.which("ngspice")
    if exe:
        from pneunet.paper_circuits import oscillator

        # as netlists/oscillator.pn (30 s, ambient 96); ngspice gets a 0.05 mL dead volume
        # at 'out' (it aborts at the first time point with 'out' algebraic)
        c = oscillator(V_out=0.05)
        text = spice_netlist(c, min(reltol, 1e-5), 0.01, t_stop=30.0)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "osc.cir")
            with open(path, "w") as fh:
                fh.write(text.replace(".end\n", ".control\nset noaskquit\nrun\n.endc\n.end\n"))

            def sp():
                subprocess.run([exe, "-b", path], capture_output=True)  # exits 1 even on success
            t_sp = best_of(sp)
    return how, t_py, t_sp


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,100,1000,3000")
    ap.add_argument("--quick", action="store_true", help="sizes 10,100")
    ap.add_argument("--rtol", type=float, default=1e-5, help="pneunet and scipy rtol")
    ap.add_argument("--spice-reltol", type=float, default=1e-4,
                    help="ngspice reltol (its LTE control is looser per unit of reltol)")
    ap.add_argument("--ngspice-max", type=int, default=3000, help="largest N run in ngspice")
    ap.add_argument("--scipy-max", type=int, default=3000, help="largest N run in scipy")
    ap.add_argument("--no-scipy", action="store_true")
    ap.add_argument("--no-ngspice", action="store_true")
    ap.add_argument("--reference", type=int, default=100,
                    help="largest N with a tight-tolerance pneunet reference (rtol 1e-9)")
    ap.add_argument("--oscillator", action="store_true",
                    help="also time the small oscillator as whole processes")
    args = ap.parse_args(argv)
    sizes = [10, 100] if args.quick else [int(s) for s in args.sizes.split(",")]
    have_spice = shutil.which("ngspice") is not None and not args.no_ngspice
    if not have_spice and not args.no_ngspice:
        print("note: ngspice not found (apt-get install -y ngspice): ngspice columns skipped")
    print(f"{T_STOP:g} s of N valve cells; pneunet (sksundae) and scipy BDF at rtol "
          f"{args.rtol:g}; ngspice reltol {args.spice_reltol:g}, abstol 1e-6; "
          f"{os.cpu_count()} cores (shared)")
    rows = []
    for n in sizes:
        row = {"N": n}
        row["pn"] = run_pneunet(n, args.rtol)
        pn = row["pn"]
        print(f"\nN={n:5d} unknowns={2 * n + 1}")
        print(f"  pneunet : {pn['wall']:8.2f} s (solver {pn['solver']:.2f} s)  steps {pn['steps']}"
              f"  residual calls {pn['res']}  Jacobian calls {pn['jac']}")
        ref = None
        if n <= args.reference:
            ref = run_pneunet(n, 1e-9)["final"]
            row["pn_err"] = agreement(pn["final"], ref)
            print(f"  pneunet error vs rtol-1e-9 reference: {row['pn_err']:.2e}")
        if not args.no_scipy and n <= args.scipy_max:
            sp = row["sp"] = run_scipy(n, args.rtol, 1e-5)
            msg = f"  scipy   : {sp['wall']:8.2f} s  steps {sp['steps']}  f calls {sp['res']}  " \
                  f"Jacobian calls {sp['jac']}  agreement with pneunet {agreement(sp['final'], pn['final']):.2e}"
            if ref is not None:
                msg += f"  error {agreement(sp['final'], ref):.2e}"
            print(msg + f"  ratio scipy/pneunet {sp['wall'] / pn['wall']:.1f}×")
        if have_spice and n <= args.ngspice_max:
            ng = row["ng"] = run_ngspice(build(n, args.rtol), actuators(n), args.spice_reltol)
            msg = (f"  ngspice : {ng['wall']:8.2f} s (analysis {ng['analysis']:.2f} s)  timepoints "
                   f"{ng['steps']}  agreement with pneunet {agreement(ng['final'], pn['final']):.2e}")
            if ref is not None:
                msg += f"  error {agreement(ng['final'], ref):.2e}"
            print(msg + f"  ratio ngspice/pneunet {ng['wall'] / pn['wall']:.1f}×")
        sys.stdout.flush()
        rows.append(row)
    if len(sizes) > 1:
        print("\ngrowth exponents (log time ratio / log N ratio) between successive sizes:")
        for key, label in (("pn", "pneunet"), ("sp", "scipy"), ("ng", "ngspice")):
            have = [(r["N"], r[key]["wall"]) for r in rows if key in r]
            if len(have) > 1:
                ex = exponent([h[0] for h in have], [h[1] for h in have])
                print(f"  {label:8s} " + "  ".join(f"{have[i][0]}→{have[i + 1][0]}: {x:.2f}"
                                                   for i, x in enumerate(ex)))
        big = [r for r in rows if r["N"] >= 100]
        if len(big) > 1:
            a, b = big[0], big[-1]
            print(f"  pneunet {a['N']}→{b['N']}: "
                  f"{np.log(b['pn']['wall'] / a['pn']['wall']) / np.log(b['N'] / a['N']):.2f} (target ≤ 1.1)")
    if args.oscillator:
        how, t_py, t_sp = oscillator_process_time(args.spice_reltol)
        print(f"\nsmall oscillator, whole process (best of 3): {how}: {t_py:.2f} s")
        if t_sp is not None:
            print(f"  ngspice -b (reltol ≤ 1e-5): {t_sp:.2f} s   ratio {t_py / t_sp:.1f}× (target ≤ 2×)")
    return rows


if __name__ == "__main__":
    main()
