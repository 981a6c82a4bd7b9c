"""Hostile command lines (issue 33): every count a user can type is checked against the
limits before anything is allocated, every number is finite and in range, every file a
command writes is checked before any work, and a write that fails later is one message.
Each case is exit 2 with one located message and no traceback, in well under a second."""
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main

ROOT = Path(__file__).parents[2]
OSC = str(ROOT / "netlists" / "oscillator_design.pn")
BENCH = str(ROOT / "examples" / "data" / "bench_axi.csv")
SWEEP = ["sweep", OSC, "--analysis", "meas", "--workers", "1", "--no-progress"]
DESIGN = ["design", OSC, "--vary", "Rout=0.6:3", "--target", "period=3s", "--workers", "1"]
TRACE = ["fit-trace", str(ROOT / "examples" / "data" / "oscillator_rec.csv"),
         str(ROOT / "netlists" / "oscillator.pn"), "--fit", "Rout=1:0.5:2"]

#: a size fuzzer: each count a user can type, far past its limit (message fragment)
SIZES = [
    (SWEEP + ["--param", "Rout=lin:0.1:1:1000000000"], "(limit max_sweep_points = 100000)"),
    (SWEEP + ["--param", "Rout=log:0.1:1:1e12"], "(limit max_sweep_points = 100000)"),
    (SWEEP + ["--param", "Rout=lin:0.1:1:1000", "--param", "Rvent=lin:1:9:1000"],
     "the --param grid asks for 1e+06 (limit max_sweep_points = 100000)"),
    (SWEEP + ["--tol", "Rout=1:0.1", "--mc", "1e9"], "--mc asks for 1e+09 (limit max_samples"),
    (SWEEP + ["--tol", "Rout=1:0.1", "--lhs", "1000000"], "--lhs asks for 1e+06"),
    (SWEEP + ["--param", "Rout=lin:0.1:1:1000", "--tol", "Rvent=3:1", "--mc", "1000"],
     "the --param grid times the samples asks for 1e+06"),
    (SWEEP + ["--param", "Rout=lin:0.1:1:10", "--workers", "1000000"], "must be >= 1 and <= 256"),
    (DESIGN + ["--yield", "1000000000", "--tolerance", "X1.pclose=±5kPa"],
     "--yield asks for 1e+09 (limit max_samples = 100000)"),
    (DESIGN + ["--starts", "1e7"], "--starts asks for 1e+07"),
    (DESIGN + ["--max-evaluations", "1e8"], "--max-evaluations asks for 1e+08"),
    (["piping", "--actuators", "1000000000"], "--actuators asks for 1e+09 (limit max_elements"),
    (["fit", BENCH, "--bootstrap", "1e9"], "--bootstrap asks for 1e+09 (limit max_samples"),
    (["fit", BENCH, "--max-rows", "0"], "argument --max-rows: 0: must be >= 1"),
]

#: numbers that are not finite or out of range
NUMBERS = [
    (["fit", BENCH, "--C", "inf"], "argument --C: 'inf': a finite number is needed"),
    (["fit", BENCH, "--C", "1e12"], "C must lie in (0, 1000] kPa^-2"),
    (["fit", BENCH, "--C", "-1"], "argument --C: -1: must be > 0"),
    (["fit", BENCH, "--bootstrap", "-1"], "argument --bootstrap: -1: must be >= 0"),
    (["fit", BENCH, "--ambient", "-1", "--gauge"], "argument --ambient: -1: must be > 0 kPa"),
    (["fit", BENCH, "--mdot-min", "nan"], "--mdot-min takes a number >= 0"),
    (["fit", BENCH, "--remove-bias", "inf"], "--remove-bias takes 'min' or a finite number"),
    (["diagnose", BENCH, "--max-effects", "-1"], "argument --max-effects: -1: must be >= 0"),
    (["diagnose", BENCH, "--folds", "1"], "argument --folds: 1: must be >= 2"),
    (["diagnose", BENCH, "--ambient", "nan", "--gauge"], "'nan': a finite number is needed"),
    (["branches", "--rout", "-1"], "argument --rout: -1: must be > 0 kPa*s/mg"),
    (["branches", "--rvent", "nan"], "argument --rvent: 'nan': a finite number is needed"),
    (["branches", "--pH", "inf"], "argument --pH: 'inf'"),
    (["branches", "--simulate", "-5"], "argument --simulate: -5: must be >= 0 s"),
    (SWEEP + ["--param", "Rout=lin:1:2:2", "--t-stop", "inf"], "argument --t-stop: 'inf'"),
    (SWEEP + ["--param", "Rout=lin:1:2:0"], "N must be a whole number >= 1"),
    (SWEEP + ["--param", "Rout=lin:1:2:2.5"], "N must be a whole number >= 1"),
    (SWEEP + ["--tol", "Rout=1:0.1", "--mc", "-5"], "argument --mc: -5: must be >= 0"),
    (DESIGN[:-4] + ["--target", "period=-3s", "--workers", "1"], "can never be measured"),
    (DESIGN[:-4] + ["--target", "duty=1.5", "--workers", "1"], "duty lies in [0, 1]"),
    (["piping", "--level", "1.5"], "argument --level: 1.5: must be <= 0.999"),
    (["piping", "--actuators", "0"], "argument --actuators/-n: 0: must be >= 1"),
    (["check", OSC, "--limit", "max_subckt_depth=100000"], "can be at most 150"),
    (TRACE + ["--train-fraction", "1"], "argument --train-fraction: 1: must be < 1"),
    (TRACE + ["--train-fraction", "0"], "argument --train-fraction: 0: must be > 0"),
    (TRACE + ["--train-fraction", "nan"], "'nan': a finite number is needed"),
    (TRACE + ["--max-nfev", "0"], "argument --max-nfev: 0: must be >= 1"),
    (TRACE + ["--max-nfev", "2.5"], "argument --max-nfev: '2.5' is not a whole number"),
    (TRACE + ["--max-nfev", "1e9"], "--max-nfev asks for 1e+09 (limit max_samples = 100000)"),
    (TRACE + ["--workers", "0"], "argument --workers: 0: must be >= 1 and <= 256"),
    (TRACE + ["--max-rows", "4"], "argument --max-rows: 4: must be >= 5"),
]


@pytest.mark.parametrize("argv, message", SIZES + NUMBERS,
                         ids=[" ".join(a[:1] + a[-2:])[:60] for a, _ in SIZES + NUMBERS])
def test_a_size_or_number_out_of_range_is_exit_2_before_any_work(argv, message, capsys):
    start = time.perf_counter()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert time.perf_counter() - start < 5
    assert message in err and "Traceback" not in err and err.count("error:") == 1, err


def test_a_pulse_with_a_tiny_period_is_refused_before_its_corners_are_made(tmp_path, capsys):
    net = tmp_path / "pulse.pn"
    net.write_text("P1 a PULSE(96kPa 496kPa 0 1n 1n 1n 4n)\nR1 a b 1\nV1 b 10mL\nR2 b atm 1\n"
                   ".tran 1e4\n")
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "P1: error: PULSE(96 496 0 1e-09 1e-09 1e-09 4e-09) has 1e+13 corners" in err
    assert "--limit max_output_points=N" in err
    net.write_text("P1 a PULSE(96kPa 496kPa 0 1m 1m 1m 4m)\nR1 a b 1\nV1 b 10mL\nR2 b atm 1\n"
                   ".tran 1\n")  # 1,000 corners: within max_output_points=2000, not 500
    assert main(["check", str(net)]) == 0
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q",
                 "--limit", "max_output_points=500"]) == 2
    assert "corners in 1 s" in capsys.readouterr().err


def _outputs(tmp_path):
    """(command line, message) for every file a command writes, named badly."""
    afile = tmp_path / "afile"
    afile.write_text("")
    folder = tmp_path / "folder"
    folder.mkdir()
    long = str(tmp_path / ("a" * 300))
    under = str(afile / "x")
    net = str(ROOT / "netlists" / "oscillator.pn")
    bad = {"file": (under, "is a file, not a folder: cannot write"),
           "long": (long, "bytes in one name (255 at most)"),
           "folder": (str(folder), "is a folder; name a file")}
    cases = []
    for kind in ("file", "long"):
        path, message = bad[kind]
        cases += [(["run", net, "-o", path], message),
                  (["fit", BENCH, "--plots", path], message),
                  (["diagnose", BENCH, "--plots", path], message)]
    for kind in ("file", "long", "folder"):
        path, message = bad[kind]
        cases += [(["fit", BENCH, "--model-out", path], message),
                  (["diagnose", BENCH, "--model-out", path], message),
                  (SWEEP + ["--param", "Rout=lin:1:2:2", "--out", path], message),
                  (SWEEP + ["--param", "Rout=lin:1:2:2", "--store", path], message),
                  (DESIGN + ["--yield", "2", "--tolerance", "X1.pclose=±5kPa", "--samples",
                             path], message)]
        plot = path + ".png" if kind != "folder" else path
        cases += [(["branches", "--plot", plot], message), (["piping", "--plot", plot], message),
                  (TRACE + ["--plot", plot], message), (TRACE + ["--waterfall", plot], message),
                  (SWEEP + ["--param", "Rout=lin:1:2:2", "--plot", plot], message),
                  (DESIGN + ["--yield", "2", "--tolerance", "X1.pclose=±5kPa", "--tornado",
                             plot], message)]
    cases += [(["fit", BENCH, "--plots", str(afile)], "is a file; name a folder"),
              (["run", net, "-o", str(afile)], "is a file; name a folder"),
              (["piping", "--plot", str(tmp_path / "x.xyz")], "unknown plot format '.xyz'"),
              (["branches", "--plot", str(tmp_path / "noext")], "unknown plot format"),
              (["fit", BENCH, "--model-out", ""], "'' is not a file name")]
    return cases


def test_every_output_path_is_checked_before_any_work(tmp_path, capsys):
    cases = _outputs(tmp_path)
    assert len(cases) == 44
    for argv, message in cases:
        start = time.perf_counter()
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert time.perf_counter() - start < 5, argv
        assert message in err and "Traceback" not in err and err.count("error:") == 1, (argv,
                                                                                        err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "folder"]  # nothing made


@pytest.mark.parametrize("shell, message", [
    ("{pneunet} check {osc} > /dev/full", "error: standard output: No space left on device"),
    ("{pneunet} fit {bench} --bootstrap 0 --json > /dev/full",
     "error: standard output: No space left on device"),
    ("{pneunet} fit {bench} --bootstrap 0 --model-out /dev/full",
     "error: /dev/full: No space left on device"),
    ("{pneunet} check -v {osc} | head -c1 > /dev/null", ""),
], ids=["check>full", "json>full", "model-out", "broken-pipe"])
def test_a_write_that_fails_later_is_one_message_and_a_closed_pipe_is_quiet(shell, message):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    command = shell.format(pneunet=f"{sys.executable} -m pneunet", osc=OSC, bench=BENCH)
    done = subprocess.run(["bash", "-c", command + "; exit ${PIPESTATUS[0]}"],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    if message:
        assert done.returncode == 2 and done.stderr.strip() == message, done.stderr
    else:
        assert done.returncode == 0 and done.stderr == ""


def test_clean_errors_exit_2_not_1(tmp_path, capsys):
    """Errors the attacker saw exit 1 (issue 33, class 7): too few sweeps, an empty design
    range, a closure pressure outside (p_L, p_H); and an output named with an ESC byte is
    quoted escaped, never raw."""
    few = tmp_path / "few.csv"
    few.write_text("".join(Path(BENCH).read_text().splitlines(keepends=True)[:63]))
    folder = tmp_path / "o\x1b[31m"
    folder.mkdir()
    cases = [(["diagnose", str(few)], "only 3 sweep(s) found; the diagnosis needs at least 5"),
             (DESIGN[:2] + ["--vary", "Rout=3:0.6", "--target", "period=3s"],
              "range of Rout: empty, low 3 ≥ high 0.6"),
             (["branches", "--pL", "300", "--pH", "200"], "lies outside (p_L, p_H)"),
             (["fit", BENCH, "--model-out", str(folder)], "o\\x1b[31m is a folder")]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert message in err and "\x1b" not in err and err.count("error:") == 1, err
