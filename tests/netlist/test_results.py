"""A result holding NaN or inf is exit 2 naming the signal and the time, never exit 0;
a simulation that cannot be completed is exit 2 with one message."""
import numpy as np
import pytest

from pneunet.interfaces.cli import main
from pneunet.engine.solution import Solution
from pneunet.common.errors import SolverError
from pneunet.netlist import runner

NET = "P1 a 200kPa\nR1 a tank 1\nVtank tank 10mL\nR2 tank atm 1\n.tran 0.5s 1s\n"


def test_non_finite_values_are_named_with_their_time():
    table = {"time_s": np.array([0.0, 0.5, 1.0]), "p_tank_kPa": np.array([101.0, 150.0, 180.0]),
             "mdot_R1_mg_s": np.array([1.0, np.inf, np.nan])}
    with pytest.raises(SolverError) as info:
        runner.check_finite(table, "tran")
    assert info.value.message == ".tran result: mdot_R1_mg_s is inf at time_s = 0.5"
    assert info.value.time == 0.5 and info.value.exit_code == 2
    with pytest.raises(SolverError, match=r"\.op result: p_tank is nan"):
        runner.check_finite({"signal": ["p_a", "p_tank"], "value": [200.0, np.nan],
                             "unit": ["kPa", "kPa"]}, "op")
    runner.check_finite({"time_s": [0.0, 1.0], "p_tank_kPa": [101.0, 1e300]}, "tran")


def test_run_with_a_nan_result_exits_2_and_writes_nothing(tmp_path, monkeypatch, capsys):
    net = tmp_path / "n.pn"
    net.write_text(NET)

    def nan_tran(deck, analysis, progress=False):
        return Solution(np.array([0.0, 0.5, 1.0]),
                        {"p_tank": np.array([101.0, np.nan, 101.0])}, {"p_tank": "kPa"})

    monkeypatch.setattr(runner, "run_analysis", nan_tran)
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert ".tran result: p_tank_kPa is nan at time_s = 0.5" in err and "Traceback" not in err
    assert not (tmp_path / "out" / "tran.csv").exists()


def test_a_solver_failure_is_exit_2(tmp_path, monkeypatch, capsys):
    net = tmp_path / "n.pn"
    net.write_text(NET)

    def fail(deck, analysis, progress=False):
        raise SolverError("IDA cannot converge at t = 0.25 s", time=0.25)

    monkeypatch.setattr(runner, "run_analysis", fail)
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("error:") == 1 and "cannot converge at t = 0.25 s" in err
