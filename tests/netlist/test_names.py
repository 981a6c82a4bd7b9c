"""Unknown names in --param, --set, --fit, model overrides and the Python API are errors
with a did-you-mean before any simulation; --strict makes a one-connection node an error."""
from pathlib import Path

import pytest

from pneunet.design import sweep as S
from pneunet.design.circuits import oscillator
from pneunet.interfaces.cli import main
from pneunet.common.errors import NetlistError, ParameterError
from pneunet.netlist import parse_file

OSC = Path(__file__).parents[2] / "netlists" / "oscillator.pn"


def test_override_of_an_undefined_param_is_an_error_with_did_you_mean():
    with pytest.raises(NetlistError) as info:
        parse_file(OSC, overrides={"Rot": 1.0})
    assert info.value.message == "parameter 'Rot' is not defined by a .param line"
    assert info.value.hint == "did you mean 'Rout'?" and info.value.where == str(OSC)
    with pytest.raises(NetlistError, match="not a finite number"):
        parse_file(OSC, overrides={"Rout": float("nan")})


@pytest.mark.parametrize("point, fragment", [
    ({"Rot": 1.0}, "did you mean 'Rout'?"),
    ({"X1.pclos": 90.0}, "did you mean 'pclose'?"),
    ({"X9.pclose": 90.0}, "no element 'X9'"),
])
def test_sweep_and_fit_names_are_checked_before_any_work(point, fragment):
    """The check the sweep and fit-trace commands make: build the first point, no simulation."""
    with pytest.raises((NetlistError, ParameterError)) as info:
        S.check_points(S.NetlistBuilder(OSC), [point])
    assert fragment in str(info.value)


def test_builtin_oscillator_rejects_unknown_names():
    with pytest.raises(ParameterError, match="did you mean 'Rvent'"):
        S.check_points(oscillator, [{"Rvnt": 3.0}])
    S.check_points(oscillator, [{"Rvent": 3.0, "X1.pclose": 90.0}])


@pytest.mark.parametrize("args, fragment", [
    (["--param", "Rot=list:1,2"], "parameter 'Rot' is not defined by a .param line"),
    (["--param", "X1.pclos=list:90,95"], "X1 has no parameter 'pclos'"),
    (["--param", "Rout=list:1,nan"], "Rout = nan: not a finite number"),
    (["--limit", "max_elemnts=3", "--param", "Rout=list:1,2"], "did you mean 'max_elements'"),
])
def test_sweep_cli_exit_2_before_simulating(args, fragment, tmp_path, capsys):
    out = tmp_path / "s.csv"
    assert main(["sweep", str(OSC), *args, "--out", str(out), "--workers", "1",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err
    assert not out.exists() and not (tmp_path / "s.csv.jsonl").exists()


def test_strict_turns_the_single_connection_warning_into_exit_2(tmp_path, capsys):
    path = tmp_path / "typo.pn"
    path.write_text("P1 supply 300kPa\nR1 supply tank 1\nVtank tank 10mL\nRvent tnak atm 1\n")
    assert main(["check", str(path)]) == 0
    assert main(["check", "--strict", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:4:1: error: node 'tnak' has one connection (Rvent); did you mean 'tank'?" in err
    assert main(["run", "--strict", str(path), "-o", str(tmp_path / "o"), "-q"]) == 2


REC = Path(__file__).parents[2] / "examples" / "data" / "oscillator_rec.csv"


@pytest.mark.parametrize("args, fragment", [
    (["--fit", "Rot=1.4:0.3:5"], "parameter 'Rot' is not defined by a .param line"),
    (["--fit", "Rout=1.4:0.3:5", "--set", "Rvnt=3"], "did you mean 'Rvent'?"),
    (["--fit", "X1.pclos=90:80:100"], "X1 has no parameter 'pclos'"),
])
def test_fit_trace_names_are_checked_before_fitting(args, fragment, capsys):
    assert main(["fit-trace", str(REC), str(OSC), *args, "--no-progress", "--max-nfev", "1"]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err
