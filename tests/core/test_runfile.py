"""A whole run saved to one file (JSON or NPZ) loads back equal to the original (issue 14)."""
import json

import numpy as np
import pytest

from pneunet import Circuit, DataError, ParameterError, Solution, read_run
from pneunet.netlist import parse_netlist


def _assert_equal(loaded, original):
    np.testing.assert_array_equal(loaded.t, original.t)
    assert list(loaded.signals) == list(original.signals)
    for name in original.signals:
        np.testing.assert_array_equal(loaded.signals[name], original.signals[name])
    assert dict(loaded.units) == dict(original.units)
    assert dict(loaded.stats) == dict(original.stats)
    assert (loaded.title, loaded.jumps) == (original.title, original.jumps)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_simulated_run_round_trips_with_netlist_options_and_versions(tmp_path, suffix):
    c = Circuit("fill", ambient=98.0, rtol=1e-7)
    c.pressure_source("P1", "a", 300.0)
    c.check_valve("D1", "a", "b", R=1.0, pcrack=20.0, Rleak=500.0)
    c.accumulator("A1", "b", V0=20.0, k=0.05)
    sol = c.tran(1.0, t_step=0.01)
    run = read_run(sol.save(tmp_path / ("run" + suffix), circuit=c))
    _assert_equal(run.solution, sol)
    assert run.options["ambient"] == 98.0 and run.options["rtol"] == 1e-7
    assert set(run.versions) == {"python", "pneunet", "numpy", "scipy", "scikit-sundae"}
    again = parse_netlist(run.netlist).circuit  # the circuit, rerun from the file's text
    np.testing.assert_allclose(again.tran(1.0, t_step=0.01).pressure("b"), sol.pressure("b"),
                               rtol=1e-9)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_exact_floats_nan_jumps_and_stats(tmp_path, suffix):
    t = np.array([0.0, 0.1, 0.1, 1 / 3])
    sol = Solution(t, {"p_x": [1 / 7, np.nan, np.inf, -1e-300], "opening_X1": [0, 1, 0.5, 2]},
                   {"p_x": "kPa", "opening_X1": "1"},
                   {"steps": 7, "backend": "IDA", "notes": ["a", {"b": 1.5}]}, "t", (0.1,))
    loaded = read_run(sol.save(tmp_path / ("r" + suffix))).solution
    _assert_equal(loaded, sol)
    assert read_run(tmp_path / ("r" + suffix)).netlist is None


def test_bad_run_files_are_named_errors(tmp_path):
    sol = Solution([0.0, 1.0], {"p_x": [1.0, 2.0]}, {"p_x": "kPa"})
    with pytest.raises(ParameterError, match="ends in .json or .npz"):
        sol.save(tmp_path / "run.csv")
    (tmp_path / "other.json").write_text(json.dumps({"format": "something"}))
    with pytest.raises(DataError, match="not a pneunet run file"):
        read_run(tmp_path / "other.json")
    (tmp_path / "broken.npz").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(DataError, match="cannot read a run file"):
        read_run(tmp_path / "broken.npz")


def test_run_command_writes_the_whole_transient(tmp_path):
    from pathlib import Path

    from pneunet.interfaces.cli import main

    netlist = Path(__file__).parents[2] / "netlists" / "oscillator.pn"
    assert main(["run", str(netlist), "-q", "-o", str(tmp_path), "--run-file", "npz"]) == 0
    run = read_run(tmp_path / "tran.npz")
    header = (tmp_path / "tran.csv").read_text().splitlines()[0].split(",")
    columns = np.loadtxt(tmp_path / "tran.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(run.solution.t, columns[:, 0], rtol=1e-8)
    tank = header.index("p_tank_kPa")
    np.testing.assert_allclose(run.solution.pressure("tank"), columns[:, tank], rtol=1e-8)
    assert "tank" in run.netlist and run.solution.stats["steps"] > 0
