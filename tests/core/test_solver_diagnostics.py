"""SUNDIALS output is captured, parsed into pneunet warnings and counted, never printed raw."""
import json
import re
import warnings
from pathlib import Path

import pytest

from pneunet.common import solver_messages as diagnostics
from pneunet.common.solver_messages import SolverWarning, parse
from pneunet.common.errors import SolverError
from pneunet.design.paper_circuits import oscillator

RAW = ("[WARNING]", "[rank 0]", "Error: -", "ida_ls.c", "feedstock")

WARNING_LINE = ("[WARNING][rank 0][/home/conda/feedstock_root/build/sundials/src/ida/"
                "ida_ls.c:1687][idaLsPerf] Warning: at t = 2.0025, poor iterative algorithm "
                "performance.\n")
HANDLER_LINE = ("\n[IDAHandleFailure, Error: -4] At t = 1.5, corrector convergence failed "
                "repeatedly\n\n")


def assert_no_raw_sundials(text):
    assert not [word for word in RAW if word in text], text[:500]


@pytest.fixture(autouse=True)
def fresh_announcements(monkeypatch):
    """Each test sees the first warning of each kind (they are shown once per process)."""
    monkeypatch.setattr(diagnostics, "_announced", set())


def test_parse_takes_kind_time_and_text_without_build_path_and_keeps_other_output():
    messages, rest = parse("user output\n" + WARNING_LINE + HANDLER_LINE)
    assert [(m.kind, m.time) for m in messages] == [("idaLsPerf", 2.0025),
                                                    ("IDAHandleFailure -4", 1.5)]
    assert messages[0].text.startswith("at t = 2.0025, poor iterative")
    assert rest == "user output\n"


def test_parse_reads_the_scikits_odes_format_and_names_what_it_means():
    messages, rest = parse("\n[IDA ERROR]  IDASolve\n  At t = 5.9999 and h = 3.6e-43, the "
                           "corrector convergence failed repeatedly or with |h| = hmin.\n\n")
    assert [(m.kind, m.time) for m in messages] == [("IDASolve", 5.9999)] and rest == ""
    sentence = diagnostics.Diagnostics(tuple(messages)).sentences()[0]
    assert "Newton's corrector did not converge" in sentence and "recovered" in sentence


def test_recovered_solver_failures_are_one_warning_counted_in_stats_and_never_raw(capfd):
    # the fold indicator turned almost off: IDA's corrector fails at each fold, the
    # driver restarts it with small steps and finishes
    circuit = oscillator(fold_threshold=1e-8)
    with pytest.warns(SolverWarning) as caught:
        sol = circuit.tran(6.0)
    out, err = capfd.readouterr()
    assert_no_raw_sundials(out + err)
    assert sol.stats["solver_messages"] >= 1
    kinds = sol.stats["solver_diagnostics"]["kinds"]
    assert "IDAHandleFailure -4" in kinds and sol.stats["solver_diagnostics"]["recovered"]
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1 and "recovered" in texts[0] and re.search(r"t = \d", texts[0])
    # at a fold the valve output (the algebraic node) jumps: the fastest pressure there
    assert "near node out" in texts[0] and sol.stats["solver_diagnostics"]["where"] == "node out"
    with warnings.catch_warnings():  # the same kind again: counted, not shown again
        warnings.simplefilter("error", SolverWarning)
        assert circuit.tran(6.0).stats["solver_messages"] >= 1


def test_a_solve_that_stops_carries_its_messages_and_says_the_result_ends(capfd):
    # a 1e-6 mL volume at the valve output, a hard switch, tolerances far too loose
    circuit = oscillator(flow_band=1e-6, rtol=1e-2, atol=10.0, dead_volume=1e-6)
    with pytest.warns(SolverWarning, match="stopped"), pytest.raises(SolverError) as info:
        circuit.tran(5.0)
    assert_no_raw_sundials("".join(capfd.readouterr()))
    assert info.value.diagnostics.recovered is False
    assert info.value.diagnostics.as_data()["count"] >= 1


def test_clean_runs_count_zero_messages(capfd):
    sol = oscillator().tran(2.0)
    assert sol.stats["solver_messages"] == 0 and "solver_diagnostics" not in sol.stats
    assert capfd.readouterr() == ("", "")


def test_other_output_during_a_solve_is_written_back(capfd, monkeypatch):
    from pneunet.engine import simulate

    real = simulate.consistent_state

    def chatty(*args, **kwargs):
        print("from python")
        return real(*args, **kwargs)
    monkeypatch.setattr(simulate, "consistent_state", chatty)
    oscillator().tran(0.5)
    assert "from python" in capfd.readouterr().out


def test_cli_run_json_reports_the_messages_as_data_and_q_silences_them(tmp_path, capfd):
    from pneunet.interfaces.cli import main

    shipped = (Path(__file__).parents[2] / "netlists" / "oscillator.pn").read_text()
    netlist = tmp_path / "osc.pn"
    netlist.write_text(shipped.replace(".options ambient=96kPa",
                                       ".options ambient=96kPa fold_threshold=1e-8")
                       .replace(".tran 10ms 30s", ".tran 10ms 8s").replace("FROM=10s", "FROM=2s"))
    assert main(["run", str(netlist), "-o", str(tmp_path / "a"), "--json"]) == 0
    out, err = capfd.readouterr()
    assert_no_raw_sundials(out + err)
    report = json.loads(out)
    assert report["solver_messages"]["tran"]["count"] >= 1
    assert "warning: IDA IDAHandleFailure -4" in err
    assert main(["run", str(netlist), "-o", str(tmp_path / "b"), "-q"]) == 0
    assert capfd.readouterr() == ("", "")


def _folding(point):
    return oscillator(fold_threshold=1e-8)


def _stopping(point):
    return oscillator(flow_band=1e-6, rtol=1e-2, atol=10.0, dead_volume=1e-6)


def _lenient(circuit):
    """An analysis that goes on after a failed simulation."""
    try:
        circuit.tran(5.0)
    except SolverError:
        pass
    return {"x": 1.0}


@pytest.mark.filterwarnings("ignore::pneunet.common.solver_messages.SolverWarning")
def test_sweep_counts_points_with_messages_and_a_swallowed_solver_failure_as_failed(capfd):
    from pneunet.design.sweep import run_sweep

    folding = run_sweep(_folding, [{"Rvent.R": 3.0}], _lenient, workers=1, progress=False)
    assert folding.failed == 0 and folding.with_solver_messages == 1
    assert folding.table["solver_messages"].iloc[0] >= 1
    stopping = run_sweep(_stopping, [{"Rvent.R": 3.0}], _lenient, workers=1, progress=False)
    assert stopping.failed == 1
    assert "stopped" in stopping.table["error"].iloc[0]
    assert_no_raw_sundials("".join(capfd.readouterr()))


class _Stream:
    def __init__(self, tty):
        self.tty, self.text = tty, ""

    def isatty(self):
        return self.tty

    def write(self, text):
        self.text += text

    def flush(self):
        pass


@pytest.mark.parametrize("tty", [False, True])
def test_progress_bars_draw_only_on_a_terminal(monkeypatch, tty):
    import sys

    from pneunet.common.progress import progress_bar

    stream = _Stream(tty)
    monkeypatch.setattr(sys, "stderr", stream)
    bar = progress_bar(True, total=2, desc="transient")
    bar.update(2)
    bar.close()
    assert ("transient" in stream.text) is tty
    assert progress_bar(False, total=2).disable


def test_a_transient_bar_reaches_the_terminal_through_the_solver_capture(monkeypatch):
    import sys

    stream = _Stream(True)
    monkeypatch.setattr(sys, "stderr", stream)
    oscillator().tran(1.0, progress=True)
    assert "transient" in stream.text and "1/1 s" in stream.text


def _fold_run(_):
    return oscillator(fold_threshold=1e-8).tran(5.0).stats["solver_messages"]


@pytest.mark.filterwarnings("ignore::pneunet.common.solver_messages.SolverWarning")
def test_messages_of_simulations_in_worker_processes_reach_the_parents_count():
    from pneunet.common.solver_messages import collect, pool_map, summarize
    from pneunet.common.workers import process_pool

    pool = process_pool(2)
    try:
        with collect() as heard:
            counts = pool_map(pool, _fold_run, [0, 1])
    finally:
        pool.shutdown()
    assert len(heard) == 2 and summarize(heard)["count"] == sum(counts) >= 2


def test_a_process_without_stdout_and_stderr_still_simulates(tmp_path):
    import subprocess
    import sys

    done = tmp_path / "done"
    code = ("from pneunet.design.paper_circuits import oscillator; "
            f"n = oscillator().tran(1.0).t.size; open({str(done)!r}, 'w').write(str(n))")
    subprocess.run([sys.executable, "-c", code], stdout=subprocess.DEVNULL, check=True,
                   stderr=subprocess.DEVNULL, close_fds=True,
                   preexec_fn=lambda: (__import__("os").close(1), __import__("os").close(2)))
    assert int(done.read_text()) > 10
