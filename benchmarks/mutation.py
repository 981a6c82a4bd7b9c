"""Mutation testing of the core modules with cosmic-ray (issue 39).

Each module is mutated in a throw-away clone of the committed repository (never in the
working tree) and every mutant is run against the module's fast tests only (seconds a
mutant); a mutant the tests do not fail "survives".  Results: per module the killed
fraction and the survivors (file, line, operator), kept in benchmarks/README.md with a
reason for each one left.

Run:  pip install '.[mutation]'
      python benchmarks/mutation.py                      # the modules run so far
      python benchmarks/mutation.py verdict laws --keep /tmp/mut   # chosen ones, keep the clone
      python benchmarks/mutation.py laws --keep /tmp/mut --retest  # survivors, newer tests

Operators: cosmic-ray's core set minus the binary-operator replacements by >>, <<, |, &,
^, // and % (on float arrays they raise at once or are never plausible slips; they cost a
test run each).  One test run per mutant, one process: the machine's cores are shared.
"""
from __future__ import annotations

import argparse
import ast
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTEST = "python -m pytest -x -q -n 0 -p no:cacheprovider"

#: module → (path, fast tests that guard it)
MODULES = {
    "verdict": ("pneunet/truth/core/verdict.py",
                "tests/diagnose/test_verdict_threshold.py"),
    "intervals": ("pneunet/truth/core/intervals.py",
                  "tests/diagnose/test_interval_sandwich.py "
                  "tests/diagnose/test_interval_coverage.py"),
    "laws": ("pneunet/physics/laws.py",
             "tests/core/test_law_partials.py tests/core/test_valve_law_reference.py "
             "tests/core/test_scalar_laws.py tests/core/test_element_conformance.py"),
    "noise": ("pneunet/truth/core/noise.py",
              "tests/diagnose/test_noise_floor.py tests/diagnose/test_logic.py"
              "::test_noise_floor_estimate_follows_flow_dependent_noise "
              "tests/traces/test_logger_resolution.py -k 'not adequate'"),
    "includes": ("pneunet/netlist/includes.py",
                 "tests/netlist/test_include_rules.py tests/netlist/test_includes.py"),
    "assembly": ("pneunet/engine/assembly.py",
                 "tests/core/test_assembly.py tests/core/test_algebraic_block.py "
                 "tests/core/test_element_conformance.py tests/core/test_float_plan.py "
                 "tests/core/test_valve_family_routes.py "
                 "-k 'assembly or algebraic or jacobian or fast_flows or floats_equal "
                 "or without_a_float_path or users_valve_has_no_dp'"),
    "float_plan": ("pneunet/engine/float_plan.py",
                   "tests/core/test_float_plan.py tests/core/test_algebraic_block.py "
                   "tests/core/test_assembly.py"),
    "valves": ("pneunet/physics/elements/valves.py",
               "tests/core/test_valve_family_routes.py tests/core/test_valve_law_reference.py "
               "tests/core/test_scalar_laws.py tests/core/test_element_conformance.py "
               "tests/core/test_law_partials.py tests/netlist/test_hostile.py -k valve"),
    "relax_one": ("pneunet/engine/solvers/folds.py", "tests/core/test_float_plan.py"),
}
#: module → the one function of its file that is mutated (the rest left as it is)
ONLY = {"relax_one": "FoldMonitor._relax_one"}
DEFAULT = ("verdict", "intervals", "laws")
EXCLUDED = [r"core/ReplaceBinaryOperator_.*_(RShift|LShift|BitOr|BitAnd|BitXor|FloorDiv|Mod)$"]


def config(path: str, tests: str, timeout: float) -> str:
    return "\n".join([
        "[cosmic-ray]",
        f'module-path = "{path}"',
        f"timeout = {timeout}",
        "excluded-modules = []",
        f'test-command = "{PYTEST} {tests}"',
        "",
        "[cosmic-ray.distributor]",
        'name = "local"',
        "",
        "[cosmic-ray.filters.operators-filter]",
        "exclude-operators = [" + ", ".join(f"'{e}'" for e in EXCLUDED) + "]",
        ""])


def run(cmd, cwd, **kw):
    return subprocess.run(cmd, cwd=cwd, check=True, text=True, **kw)


def mutate(name: str, work: Path, timeout: float) -> dict:
    path, tests = MODULES[name]
    cfg, session = work / f"{name}.toml", work / f"{name}.sqlite"
    cfg.write_text(config(path, tests, timeout))
    start = time.perf_counter()
    run(["cosmic-ray", "init", str(cfg), str(session)], work)
    run(["cr-filter-operators", str(session), str(cfg)], work)
    skip_annotations(session, work)
    if name in ONLY:
        skip_outside(session, function_lines(work / path, ONLY[name]))
    run(["cosmic-ray", "baseline", str(cfg)], work)  # the tests pass unmutated
    run(["cosmic-ray", "exec", str(cfg), str(session)], work)
    return {**results(session, work), "minutes": (time.perf_counter() - start) / 60}


def annotations(path: Path) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """(start, end) (line, column) of each annotation in a module: never evaluated (every
    core module has ``from __future__ import annotations``), so a mutant there is no
    change of behaviour and is not counted (mutmut leaves them out too)."""
    spans = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            anns = [node.returns] + [x.annotation for x in [*a.posonlyargs, *a.args,
                                                            *a.kwonlyargs, a.vararg, a.kwarg] if x]
        else:
            anns = [node.annotation] if isinstance(node, ast.AnnAssign) else []
        spans += [((n.lineno, n.col_offset), (n.end_lineno, n.end_col_offset))
                  for n in anns if n is not None]
    return spans


def in_annotation(mutation: dict, spans) -> bool:
    start, end = tuple(mutation["start_pos"]), tuple(mutation["end_pos"])
    return any(a <= start and end <= b for a, b in spans)


def function_lines(path: Path, qualname: str) -> tuple[int, int]:
    """First and last line of a function (``Class.method``) in a module."""
    body = ast.parse(path.read_text()).body
    for part in qualname.split("."):
        node = next((n for n in body if getattr(n, "name", None) == part), None)
        if node is None:
            raise SystemExit(f"{qualname} not found in {path}")
        body = node.body
    return node.lineno, node.end_lineno


def skip_outside(session: Path, lines: tuple[int, int]):
    """Mark skipped, before they run, the mutants outside these lines (ONLY)."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item in list(db.pending_work_items):
            if not all(lines[0] <= m.start_pos[0] <= lines[1] for m in item.mutations):
                db.set_result(item.job_id, WorkResult(output="Outside the function mutated",
                                                      worker_outcome=WorkerOutcome.SKIPPED))


def skip_annotations(session: Path, work: Path):
    """Mark the mutants inside annotations skipped before they run."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item in list(db.pending_work_items):
            spans = annotations(work / item.mutations[0].module_path)
            if all(in_annotation({"start_pos": m.start_pos, "end_pos": m.end_pos}, spans)
                   for m in item.mutations):
                db.set_result(item.job_id, WorkResult(output="In an annotation",
                                                      worker_outcome=WorkerOutcome.SKIPPED))


def results(session: Path, work: Path) -> dict:
    """Mutants run, killed, skipped and the survivors (path, line, operator, occurrence);
    mutants inside annotations count as skipped (also in sessions run before they were)."""
    dump = run(["cosmic-ray", "dump", str(session)], work, capture_output=True).stdout
    jobs = [json.loads(line) for line in dump.splitlines() if line.strip()]
    spans = {}
    ann = [all(in_annotation(m, spans.setdefault(m["module_path"], annotations(
        work / m["module_path"]))) for m in w["mutations"]) for w, _ in jobs]
    done = [(w, r) for (w, r), a in zip(jobs, ann)
            if r is not None and r.get("test_outcome") and not a]
    skipped = [w for (w, r), a in zip(jobs, ann)
               if a or (r is not None and r.get("worker_outcome") == "skipped")]
    survivors = [(m["module_path"], m["start_pos"][0], m["operator_name"], m["occurrence"])
                 for w, r in done for m in w["mutations"] if r["test_outcome"] == "survived"]
    killed = sum(r["test_outcome"] != "survived" for _, r in done)
    return {"mutants": len(done), "killed": killed, "skipped": len(skipped),
            "score": killed / len(done) if done else float("nan"), "survivors": survivors}


def retest(name: str, work: Path) -> dict:
    """The survivors of a kept session run again against the tests committed since (the
    clone pulled first): the score after new tests, without running every mutant again."""
    path, tests = MODULES[name]
    run(["git", "pull", "-q", "--ff-only", str(ROOT), "HEAD"], work)
    start = time.perf_counter()
    out = results(work / f"{name}.sqlite", work)
    left = []
    for mpath, line, op, occ in out["survivors"]:
        res = run(["cosmic-ray", "mutate-and-test", mpath, op, str(occ), f"{PYTEST} {tests}"],
                  work, capture_output=True).stdout
        if json.loads(res.strip().splitlines()[-1])["test_outcome"] == "survived":
            left.append((mpath, line, op, occ))
    killed = out["mutants"] - len(left)
    return {**out, "killed": killed, "score": killed / out["mutants"], "survivors": left,
            "minutes": (time.perf_counter() - start) / 60}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("modules", nargs="*",
                    help=f"of {', '.join(MODULES)} (default: {' '.join(DEFAULT)})")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per mutant's tests")
    ap.add_argument("--keep", type=Path, help="clone here and keep it (default: a temp dir)")
    ap.add_argument("--retest", action="store_true",
                    help="only run the survivors of the --keep clone's sessions again")
    args = ap.parse_args(argv)
    if set(args.modules) - set(MODULES):
        ap.error(f"unknown module {sorted(set(args.modules) - set(MODULES))}")
    if args.retest and not (args.keep and args.keep.exists()):
        ap.error("--retest needs --keep DIR of an earlier run")
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp) / "pneunet"
        if not work.exists():
            run(["git", "clone", "-q", "--local", str(ROOT), str(work)], ROOT)
        for name in args.modules or DEFAULT:
            out = retest(name, work) if args.retest else mutate(name, work, args.timeout)
            print(f"{name}: {out['killed']}/{out['mutants']} killed "
                  f"({100 * out['score']:.1f} %), {out['minutes']:.1f} min", flush=True)
            for path, line, op, occ in out["survivors"]:
                print(f"  survived: {path}:{line} {op} #{occ}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
