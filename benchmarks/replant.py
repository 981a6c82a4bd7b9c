"""Plant again the bugs of issue 39's audit, one at a time, and name the tests that fail.

Each bug is a patch (old text → new text, each old text found exactly once) applied in a
throw-away clone of the committed repository (never the working tree, where others run
tests); the bug's chosen tests run on it (one process), the patch is undone and the next
bug planted.  A bug no test fails (tests failing unplanted do not count) is reported as "NOT CAUGHT"
and the exit code is 1.

Run:  python benchmarks/replant.py                    # every bug (≈ 10 min on 2 shared cores)
      python benchmarks/replant.py verdict-tolerance yield-level   # chosen ones
      python benchmarks/replant.py --list             # the bugs and their tests
      python benchmarks/replant.py --keep /tmp/replant   # clone there (pulled if it exists)
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTEST = [sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider",
          "--tb=no", "-rfE"]


@dataclass(frozen=True)
class Bug:
    """One planted bug: a description, its patches (path, old, new) and the tests to run."""

    what: str
    patches: tuple
    tests: tuple


BUGS = {
    "eq19-saturation": Bug(
        "valve saturation term of eq. 19 dropped (1/R = u^e/R_f)",
        (("pneunet/physics/laws.py", "q = 1.0 + ue * ue", "q = 1.0 + 0.0 * ue"),),
        ("tests/core/test_valve_law_reference.py", "tests/core/test_law_partials.py",
         "tests/core/test_paper_numbers.py")),
    "mckibben-end": Bug(
        "McKibben end correction dropped (k_end read as 1)",
        (("pneunet/physics/elements/mckibben.py", 'self.column("L0"), self.column("k_end")',
          'self.column("L0"), 0 * self.column("k_end") + 1'),),
        ("tests/core/test_mckibben.py",)),
    "fold-threshold": Bug(
        "fold threshold 1e-2 → 1e-1",
        (("pneunet/engine/options.py", "fold_threshold: float = 1e-2",
          "fold_threshold: float = 1e-1"),),
        ("tests/core/test_algebraic_block.py", "tests/core/test_paper_numbers.py",
         "tests/core/test_solver_diagnostics.py", "tests/core/test_stability.py")),
    "coupling-tol": Bug(
        "multirate coupling tolerance 30 → 3000 local tolerances",
        (("pneunet/engine/multirate.py", "COUPLING_TOL = 30 ", "COUPLING_TOL = 3000 "),),
        ("tests/core/test_multirate.py",)),
    "include-symlink": Bug(
        "include check without symbolic-link resolution (names checked as written)",
        (("pneunet/netlist/includes.py", "path = Path(os.path.realpath(folder / name))",
          "path = Path(os.path.abspath(folder / name))"),
         ("pneunet/netlist/includes.py", "real = opened.real_path()", "real = opened.path")),
        ("tests/netlist/test_includes.py", "tests/netlist/test_include_rules.py")),
    "valve-z": Bug(
        "valve fit's 95 % intervals 1.8× too wide (z 1.96 → 3.5)",
        (("pneunet/truth/valves/identify/fit.py", "Z95 = 1.959963984540054", "Z95 = 3.5"),),
        ("tests/identify/test_fit.py",)),
    "truth-z": Bug(
        "truth core's (circuit fits') intervals 1.8× too wide (t quantile × 1.786)",
        (("pneunet/truth/core/intervals.py", "tq = stats.t.ppf(0.5 + confidence / 2, dof)",
          "tq = 1.786 * stats.t.ppf(0.5 + confidence / 2, dof)"),),
        ("tests/diagnose/test_interval_coverage.py", "tests/diagnose/test_interval_sandwich.py")),
    "diagnose-z": Bug(
        "a valve diagnosis' effect intervals 1.8× too wide (1.96 → 3.5 standard errors)",
        (("pneunet/truth/valves/diagnose/fitting.py",
          "return (self.values[i] - 1.96 * self.stderr[i], self.values[i] + 1.96 * self.stderr[i])",
          "return (self.values[i] - 3.5 * self.stderr[i], self.values[i] + 3.5 * self.stderr[i])"),),
        ("tests/diagnose/test_confusion.py",)),
    "verdict-tolerance": Bug(
        "verdict tolerance 1.5 → 2.5 × the noise floor",
        (("pneunet/truth/core/verdict.py", "TOLERANCE = 1.5", "TOLERANCE = 2.5"),),
        ("tests/diagnose/test_verdict_threshold.py",)),
    "yield-level": Bug(
        "yield's Wilson interval at 50 % instead of 95 %",
        (("pneunet/design/yields.py", "proportion_ci(0.95,", "proportion_ci(0.5,"),),
        ("tests/design/test_yield.py",)),
    "eq25-reverse": Bug(
        "eq. 25's reverse-flow rule broken (a_in always on p_in: −606 for −531 mg/s)",
        (("pneunet/physics/laws.py",
          "return a_in * xp.maximum(p_in, p_out) + a_out * xp.minimum(p_in, p_out) - p_ctrl",
          "return a_in * p_in + a_out * p_out - p_ctrl"),),
        ("tests/core/test_valve_law_reference.py", "tests/core/test_law_partials.py")),
}


def git(work: Path, *args, **kw):
    return subprocess.run(["git", *args], cwd=work, check=True, text=True, **kw)


def plant(work: Path, bug: Bug) -> None:
    for path, old, new in bug.patches:
        f = work / path
        text = f.read_text()
        if text.count(old) != 1:
            raise SystemExit(f"{path}: {old!r} found {text.count(old)} times, not once "
                             "(the code changed: update the patch in benchmarks/replant.py)")
        f.write_text(text.replace(old, new))


def run(work: Path, bug: Bug) -> tuple:
    """(failed test ids, pytest's last line, seconds) of the bug's tests on the clone."""
    start = time.perf_counter()
    out = subprocess.run([*PYTEST, *bug.tests], cwd=work, text=True, capture_output=True)
    failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", out.stdout, flags=re.M)
    lines = out.stdout.strip().splitlines()
    return failed, lines[-1] if lines else out.stderr.strip()[-200:], \
        time.perf_counter() - start


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bugs", nargs="*", help=f"of {', '.join(BUGS)} (default: all)")
    ap.add_argument("--keep", type=Path, help="clone here and keep it (default: a temp dir)")
    ap.add_argument("--list", action="store_true", help="list the bugs and their tests")
    args = ap.parse_args(argv)
    if set(args.bugs) - set(BUGS):
        ap.error(f"unknown bug {sorted(set(args.bugs) - set(BUGS))}")
    if args.list:
        for name, bug in BUGS.items():
            print(f"{name}: {bug.what}\n    {' '.join(bug.tests)}")
        return 0
    missed = []
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp) / "pneunet"
        if work.exists():
            git(work, "checkout", "-q", "--", ".")
            git(work, "pull", "-q", "--ff-only", str(ROOT), "HEAD")
        else:
            git(ROOT, "clone", "-q", "--local", str(ROOT), str(work))
        where = subprocess.run([sys.executable, "-c", "import pneunet; print(pneunet.__file__)"],
                               cwd=work, text=True, capture_output=True).stdout.strip()
        if not where.startswith(str(work)):
            raise SystemExit(f"the clone's tests would import {where}, not the clone's pneunet")
        names = args.bugs or list(BUGS)
        tests = tuple(dict.fromkeys(t for n in names for t in BUGS[n].tests))
        broken, last, secs = run(work, Bug("unplanted", (), tests))
        print(f"unplanted: {last}, {secs:.0f} s", flush=True)
        for test in broken:  # failing before any bug: not counted as catching one
            print(f"    fails already: {test}", flush=True)
        for name in names:
            bug = BUGS[name]
            plant(work, bug)
            try:
                failed, last, secs = run(work, bug)
            finally:
                git(work, "checkout", "-q", "--", ".")
            failed = [t for t in failed if t not in broken]
            print(f"{name}: {bug.what}\n    {'caught' if failed else 'NOT CAUGHT'} "
                  f"({last}, {secs:.0f} s)", flush=True)
            for test in failed:
                print(f"    fails: {test}", flush=True)
            if not failed:
                missed.append(name)
    if missed:
        print(f"not caught: {', '.join(missed)}")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
