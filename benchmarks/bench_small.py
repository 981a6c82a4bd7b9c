"""Small circuits against ngspice, side by side in one run (issue 15).

    python benchmarks/bench_small.py                   # 3 circuits + demux6, 5 repeats
    python benchmarks/bench_small.py --repeats 7 --no-demux6
    git archive COMMIT | tar -x -C /tmp/base           # an earlier tree, then (issue 35):
    python benchmarks/bench_small.py --only oscillator --no-demux6 --repeats 15 --baseline /tmp/base

The oscillator (``.tran 10ms 50s``), the flow amplifier (30 s) and the 3-bit
demultiplexer (16 s) from ``netlists/`` run in pneunet and in ngspice on the same
equations (bench_scaling.spice_netlist: capacitors, B-sources with the same
regularised root sr(d) = d/(d²+ε²)^¼, reltol 1e-6, abstol 1e-6 mg/s).  ngspice
cannot step across a fold of an algebraic node ("timestep too small"), so every
node without a volume gets a dead capacitance of 1e-4 mg/kPa (≈ 0.008 mL) there.

Printed per circuit (medians of ``--repeats`` runs):
* in-process transient: pneunet's ``transient`` (netlist parsed outside the timer,
  imports warmed up) against ngspice's "Total analysis time" (target ≤ 0.5×);
* whole process: ``python -m pneunet run FILE.pn`` (CSV written) against
  ``ngspice -b deck.cir`` (data written), target ≤ 4× (issue 35: ≤ 2.5×); the child
  processes keep their bytecode in a temporary ``PYTHONPYCACHEPREFIX`` as an installed
  package does (``--no-bytecode-cache``: compiled per process, as under
  ``PYTHONDONTWRITEBYTECODE=1``); with ``--baseline TREE`` an earlier source tree's whole
  process (wall and CPU time) alternating with this one's, and for the oscillator both
  trees' import time (``-X importtime``) and module count;
* accuracy against pneunet at rtol = atol = 1e-9: the oscillator's period, the
  others' largest relative pressure deviation on the output grid;
* for the oscillator, steps and residual calls per simulated second.
The 6-bit demultiplexer (390 unknowns, 64 s; ``--no-demux6`` leaves it out) runs with
``method=auto`` (hub first) and single-rate IDA, alternating: in-process times, the
whole process's peak memory (targets 5 s, 300 MB) and both runs' deviation from
single-rate IDA at rtol 1e-8 (``--no-reference`` skips that 22 s run).
ngspice is skipped with a note when it is not installed
(``apt-get install -y ngspice`` on Debian/Ubuntu).
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_scaling import mean_period, spice_name, spice_netlist  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEAD_CAPACITANCE = 1e-4  # mg/kPa at ngspice's algebraic nodes
SPICE_RELTOL = 1e-6

CASES = [  # name, netlist, t_step, t_stop (s), compared nodes
    ("oscillator", "oscillator.pn", 0.01, 50.0, ["tank"]),
    ("amplifier", "amplifier.pn", 0.01, 30.0, ["muscle"]),
    ("demux3", "demux3.pn", 0.01, 16.0, [f"act[{k}]" for k in range(8)]),
]


def circuit_of(netlist, **options):
    from pneunet.netlist import parse_file

    circuit = parse_file(os.path.join(REPO, "netlists", netlist)).circuit
    circuit.options = circuit.options.replace(**options)
    return circuit


def median_time(run, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


# -- pneunet --------------------------------------------------------------------------------
def pneunet_in_process(netlist, t_step, t_stop, nodes, repeats):
    from pneunet.engine.simulate import transient

    circuit = circuit_of(netlist)
    transient(circuit, t_stop, t_step=t_step)  # warm-up (first-call imports)
    wall = median_time(lambda: transient(circuit, t_stop, t_step=t_step), repeats)
    sol = transient(circuit, t_stop, t_step=t_step)
    return dict(wall=wall, t=sol.t, p=np.column_stack([sol.pressure(x) for x in nodes]),
                stats=sol.stats)


def pneunet_reference(netlist, t_step, t_stop, nodes):
    from pneunet.engine.simulate import transient

    sol = transient(circuit_of(netlist, rtol=1e-9, atol=1e-9), t_stop, t_step=t_step)
    return sol.t, np.column_stack([sol.pressure(x) for x in nodes])


def netlist_with_tran(netlist, t_step, t_stop, folder):
    """A copy of the netlist whose .tran is ``.tran t_step t_stop``."""
    with open(os.path.join(REPO, "netlists", netlist)) as fh:
        text = fh.read()
    text = re.sub(r"^\.tran .*$", f".tran {t_step:g} {t_stop:g}", text, flags=re.M)
    path = os.path.join(folder, netlist)
    with open(path, "w") as fh:
        fh.write(text)
    return path


def pneunet_process(path, repeats, folder, baseline=None):
    """Median wall times (s) of ``python -m pneunet run`` in this tree and, alternating
    with it, in the ``baseline`` tree (None without one); and {tree: median CPU s}."""
    trees = [REPO] + ([baseline] if baseline else [])
    times, cpu = {tree: [] for tree in trees}, {tree: [] for tree in trees}
    for tree in trees:  # warm-up: the bytecode cache, the parser tables' cache
        cmd, env = _run_command(path, folder, tree)
        subprocess.run(cmd, check=True, cwd=tree, env=env)
    for _ in range(repeats):
        for tree in trees:
            cmd, env = _run_command(path, folder, tree)
            t0 = time.perf_counter()
            proc = subprocess.Popen(cmd, cwd=tree, env=env)
            _, status, usage = os.wait4(proc.pid, 0)
            times[tree].append(time.perf_counter() - t0)
            cpu[tree].append(usage.ru_utime + usage.ru_stime)
            if status:
                raise RuntimeError(f"{cmd} failed in {tree}")
    return [float(np.median(times[tree])) for tree in trees] + [None] * (2 - len(trees)) + \
        [{tree: float(np.median(c)) for tree, c in cpu.items()}]


def import_ms(path, folder, trees, repeats):
    """{tree: (median time (ms) of the imports of ``pneunet run``, modules imported)}:
    ``python -X importtime``, the top-level modules' cumulative times, trees alternating."""
    totals, counts = {tree: [] for tree in trees}, {tree: [] for tree in trees}
    for _ in range(repeats):
        for tree in trees:
            cmd, env = _run_command(path, folder, tree)
            err = subprocess.run([cmd[0], "-X", "importtime"] + cmd[1:], check=True,
                                 cwd=tree, env=env, capture_output=True, text=True).stderr
            totals[tree].append(sum(int(m) for m in re.findall(
                r"^import time:\s+\d+ \|\s+(\d+) \| \S", err, flags=re.M)) / 1e3)
            counts[tree].append(len(re.findall(r"^import time:\s+\d+ \|", err, flags=re.M)))
    return {tree: (float(np.median(totals[tree])), int(np.median(counts[tree])))
            for tree in trees}


#: where the child processes keep their compiled bytecode (None: they compile every module
#: each run, as under PYTHONDONTWRITEBYTECODE=1); set by main
PYCACHE = None


def _run_command(path, folder, tree):
    env = dict(os.environ, PYTHONPATH=tree)
    if PYCACHE:  # as an installed package runs: every module compiled once, not per process
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = os.path.join(PYCACHE, os.path.basename(tree) or "tree")
    return [sys.executable, "-m", "pneunet", "run", path, "-q", "-o", folder], env


def peak_memory_mb(cmd) -> tuple[float, float]:
    """Wall time (s) and peak resident memory (MB) of one child process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    if status:
        raise RuntimeError(f"{cmd} failed")
    return time.perf_counter() - t0, usage.ru_maxrss / 1024


# -- ngspice --------------------------------------------------------------------------------
def ngspice_runs(netlist, t_step, t_stop, nodes, repeats, folder):
    """Median whole-process and analysis times of ``ngspice -b`` and its pressures."""
    exe = shutil.which("ngspice")
    deck = os.path.join(folder, "deck.cir")
    raw = os.path.join(folder, "out.txt")
    text = spice_netlist(circuit_of(netlist), SPICE_RELTOL, t_step, t_stop=t_stop,
                         dead_capacitance=DEAD_CAPACITANCE)
    control = (".control\nset noaskquit\nset filetype=ascii\nrun\nwrdata " + raw + " "
               + " ".join(f"v({spice_name(x)})" for x in nodes) + "\nrusage all\n.endc\n")
    with open(deck, "w") as fh:
        fh.write(text.replace(".end\n", control + ".end\n"))
    walls, analysis = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        proc = subprocess.run([exe, "-b", deck], capture_output=True, text=True)
        walls.append(time.perf_counter() - t0)
        out = proc.stdout + proc.stderr
        m = re.search(r"Total analysis time \(seconds\) = ([\d.]+)", out)
        analysis.append(float(m.group(1)) if m else np.nan)
    data = np.loadtxt(raw, ndmin=2)
    if abs(data[-1, 0] - t_stop) > 1e-6 * t_stop:
        raise RuntimeError(f"ngspice stopped at t = {data[-1, 0]:g} s:\n{out[-1500:]}")
    return dict(wall=float(np.median(walls)), analysis=float(np.median(analysis)),
                t=data[:, 0], p=data[:, 1::2])


# -- accuracy -------------------------------------------------------------------------------
def _on_grid(t, p, t_ref):
    return np.column_stack([np.interp(t_ref, t, p[:, k]) for k in range(p.shape[1])])


def deviation(t, p, t_ref, p_ref):
    """Largest relative deviation of pressures p(t) from the reference on its grid."""
    return float(np.max(np.abs(_on_grid(t, p, t_ref) - p_ref) / p_ref))


def deviation_text(t, p, t_ref, p_ref):
    """The largest deviation of p(t) from the reference on its grid: relative, in kPa,
    and the 99.9th percentile of the relative one."""
    gap = np.abs(_on_grid(t, p, t_ref) - p_ref)
    return (f"{np.max(gap / p_ref):.1e} relative ({np.max(gap):.3f} kPa; 99.9th percentile "
            f"{np.percentile(gap / p_ref, 99.9):.1e})")


def period_error(t, p, t_ref, p_ref):
    return abs(mean_period(t, p[:, 0]) / mean_period(t_ref, p_ref[:, 0]) - 1)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-demux6", action="store_true")
    ap.add_argument("--only", metavar="CIRCUIT", choices=[c[0] for c in CASES], default=None,
                    help="one of the three small circuits only")
    ap.add_argument("--no-ngspice", action="store_true")
    ap.add_argument("--no-reference", action="store_true",
                    help="demux6 without its rtol 1e-8 reference (22 s)")
    ap.add_argument("--baseline", metavar="TREE", default=None,
                    help="an earlier source tree (git archive COMMIT | tar -x -C TREE): its "
                         "whole process and imports are timed alternately with this tree's")
    ap.add_argument("--no-bytecode-cache", action="store_true",
                    help="child processes compile every module each run (as this machine's "
                         "PYTHONDONTWRITEBYTECODE=1 makes them); default: compiled once, into "
                         "a temporary PYTHONPYCACHEPREFIX, as an installed package is")
    args = ap.parse_args(argv)
    global PYCACHE
    PYCACHE = None if args.no_bytecode_cache else tempfile.mkdtemp(prefix="bench_small_pyc_")
    have_spice = shutil.which("ngspice") is not None and not args.no_ngspice
    if not have_spice and not args.no_ngspice:
        print("note: ngspice not found (apt-get install -y ngspice): ngspice columns skipped")
    print(f"bytecode: {'compiled per process' if args.no_bytecode_cache else 'cached'}; "
          f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"{os.cpu_count()} cores (shared); medians of {args.repeats}; ngspice reltol "
          f"{SPICE_RELTOL:g}, dead capacitance {DEAD_CAPACITANCE:g} mg/kPa at algebraic nodes")
    rows = []
    for name, netlist, t_step, t_stop, nodes in CASES:
        if args.only and name != args.only:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            pn = pneunet_in_process(netlist, t_step, t_stop, nodes, args.repeats)
            copy = netlist_with_tran(netlist, t_step, t_stop, tmp)
            pn_proc, base_proc, cpu = pneunet_process(copy, args.repeats, tmp, args.baseline)
            if name == "oscillator":
                imports = import_ms(copy, tmp, list(cpu), args.repeats)
            sp = ngspice_runs(netlist, t_step, t_stop, nodes, args.repeats, tmp) \
                if have_spice else None
        t_ref, p_ref = pneunet_reference(netlist, t_step, t_stop, nodes)
        error = period_error if name == "oscillator" else deviation
        rows.append((name, pn, pn_proc, sp, error(pn["t"], pn["p"], t_ref, p_ref),
                     error(sp["t"], sp["p"], t_ref, p_ref) if sp else np.nan))
        s = pn["stats"]
        print(f"\n{name} ({t_stop:g} s, {s['unknowns']} unknowns): pneunet {pn['wall']:.3f} s "
              f"in process, {pn_proc:.2f} s whole; steps {s['steps']}, residuals "
              f"{s['residual_calls']}, Jacobians {s['jacobian_calls']}, jumps "
              f"{s['branch_jumps']}" + (f"; ngspice analysis {sp['analysis']:.3f} s, whole "
                                         f"{sp['wall']:.2f} s" if sp else ""))
        if base_proc:
            print(f"  baseline {args.baseline}: whole {base_proc:.2f} s; this tree / baseline "
                  f"{pn_proc / base_proc:.3f} (CPU {cpu[REPO]:.3f} / {cpu[args.baseline]:.3f} s"
                  f" = {cpu[REPO] / cpu[args.baseline]:.3f})"
                  + (f"; ngspice whole {base_proc / sp['wall']:.2f}× (this tree "
                     f"{pn_proc / sp['wall']:.2f}×)" if sp else ""))
        if name == "oscillator":
            for tree, (ms, count) in imports.items():
                print(f"  imports of pneunet run ({'this tree' if tree == REPO else tree}): "
                      f"{ms:.0f} ms (-X importtime, median), {count} modules")
            print(f"  per simulated second: {s['steps'] / t_stop:.1f} steps, "
                  f"{s['residual_calls'] / t_stop:.1f} residual calls, "
                  f"{s['jacobian_calls'] / t_stop:.1f} Jacobians")
        sys.stdout.flush()

    print("\n| circuit | pneunet transient s | ngspice analysis s | ratio (≤ 0.5) | pneunet "
          "process s | ngspice process s | ratio (≤ 4) | error pneunet | error ngspice |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, pn, pn_proc, sp, err_pn, err_sp in rows:
        what = "period" if name == "oscillator" else "max rel. p"
        if sp:
            print(f"| {name} | {pn['wall']:.3f} | {sp['analysis']:.3f} | "
                  f"{pn['wall'] / sp['analysis']:.2f} | {pn_proc:.2f} | {sp['wall']:.2f} | "
                  f"{pn_proc / sp['wall']:.2f} | {what} {err_pn:.1e} | {err_sp:.1e} |")
        else:
            print(f"| {name} | {pn['wall']:.3f} | – | – | {pn_proc:.2f} | – | – | "
                  f"{what} {err_pn:.1e} | – |")

    if not args.no_demux6:
        demux6(args)
    print(f"load average at the end {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if PYCACHE:
        shutil.rmtree(PYCACHE, ignore_errors=True)


DEMUX6_NODES = [f"act[{k}]" for k in range(64)]


def demux6(args):
    """The 6-bit demultiplexer: ``method=auto`` (its cells read their inverters' lines
    only: hub first) and single-rate IDA, alternating, medians; the whole process's
    peak memory; both against single-rate IDA at rtol 1e-8 (unless --no-reference)."""
    demux6 = os.path.join(REPO, "netlists", "demux6.pn")
    with tempfile.TemporaryDirectory() as tmp:
        wall, peak = peak_memory_mb([sys.executable, "-m", "pneunet", "run", demux6, "-q",
                                     "-o", tmp])
    from pneunet.engine.simulate import transient

    runs = {"auto": [], "single": []}
    solutions = {}
    for _ in range(args.repeats):
        for method, times in runs.items():
            circuit = circuit_of("demux6.pn", method=method)
            t0 = time.perf_counter()
            solutions[method] = transient(circuit, 64.0, t_step=0.01)
            times.append(time.perf_counter() - t0)
    auto, single = (float(np.median(runs[m])) for m in ("auto", "single"))
    s, r = solutions["auto"].stats, solutions["single"].stats
    print(f"\ndemux6 (64 s, {s['unknowns']} unknowns), medians of {args.repeats} alternating runs:"
          f"\n  method=auto ({s['method']}): {auto:.2f} s (target ≤ 5 s), {single / auto:.2f}× "
          f"faster than single-rate; hub {s.get('hub_steps', 0)} IDA steps, cells "
          f"{s['steps'] - s.get('hub_steps', 0)} steps, {s.get('rejected', 0)} rejected, "
          f"{s.get('passes', 0)} passes"
          f"\n  method=single: {single:.2f} s; steps {r['steps']}, residuals "
          f"{r['residual_calls']}, Jacobians {r['jacobian_calls']}"
          f"\n  whole process (auto) {wall:.2f} s, peak memory {peak:.0f} MB (target ≤ 300 MB)")
    p = {m: np.column_stack([sol.pressure(x) for x in DEMUX6_NODES])
         for m, sol in solutions.items()}
    t = solutions["auto"].t
    print(f"  actuators, auto against single: largest deviation "
          f"{deviation_text(t, p['auto'], solutions['single'].t, p['single'])}")
    if not args.no_reference:
        ref = transient(circuit_of("demux6.pn", method="single", rtol=1e-8, atol=1e-8), 64.0,
                        t_step=0.01)
        p_ref = np.column_stack([ref.pressure(x) for x in DEMUX6_NODES])
        print("  against single-rate IDA at rtol 1e-8:"
              f"\n    auto   {deviation_text(t, p['auto'], ref.t, p_ref)}"
              f"\n    single {deviation_text(solutions['single'].t, p['single'], ref.t, p_ref)}")

if __name__ == "__main__":
    main()
