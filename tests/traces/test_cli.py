"""``pneunet fit-trace``: bad recordings give exit code 2 with the file, the column and
what to do; ``--json`` prints only JSON on stdout."""
import json
import re

import numpy as np
import pytest

from pneunet.interfaces.cli import main

from .standalone import oscillator_record

RAW_SUNDIALS = re.compile(r"\[(WARNING|ERROR)\]\[rank|\[\w+, Error: -?\d+\]")


@pytest.fixture(scope="module")
def record():
    return oscillator_record(6.0, noise=0.4, seed=3)


def run(capfd, *args):
    code = main(["fit-trace", *map(str, args)])
    out, err = capfd.readouterr()
    return code, out, err


@pytest.mark.parametrize("damage, words", [
    (lambda df: df.drop(columns="time_s"), ["time_s"]),
    (lambda df: df.assign(p_tank_kPa=np.where(df.index == 7, np.nan, df.p_tank_kPa)),
     ["p_tank_kPa", "missing", "row"]),
    (lambda df: df.iloc[[0, 2, 1] + list(range(3, len(df)))], ["time_s", "goes back", "sort"]),
    (lambda df: df.iloc[[0, 1, 1] + list(range(2, len(df)))], ["time_s", "repeats"]),
    (lambda df: df.rename(columns={"p_out_kPa": "p_nowhere_kPa"}), ["p_nowhere_kPa",
                                                                     "no node"]),
])
def test_broken_recordings_exit_2_naming_file_and_column(tmp_path, capfd, record, damage, words):
    path = tmp_path / "rec.csv"
    damage(record).to_csv(path, index=False)
    code, out, err = run(capfd, path, "--fit", "Rvent=3:1:10", "--json")
    assert code == 2 and out == ""
    assert str(path) in err and "Traceback" not in err
    for w in words:
        assert w in err, (w, err)


def test_record_shorter_than_two_cycles_is_refused(tmp_path, capfd, record):
    path = tmp_path / "short.csv"
    record[record.time_s <= 1.5].to_csv(path, index=False)
    code, out, err = run(capfd, path, "--fit", "Rvent=3:1:10", "--candidates")
    assert code == 2 and "cycle" in err and "record longer" in err


def test_json_is_the_only_thing_on_stdout(tmp_path, capfd, record):
    path = tmp_path / "rec.csv"
    record.to_csv(path, index=False)
    code, out, err = run(capfd, path, "--fit", "Rvent=3.5:1:10", "--set", "V=50",
                         "--max-nfev", "8", "--json", "--no-progress")
    assert code == 0
    assert not RAW_SUNDIALS.search(out + err)  # no SUNDIALS line on fd 1 or 2 (issue 16)
    j = json.loads(out)  # nothing but JSON
    assert j["solver_messages"]["simulations"] > 0 and j["solver_messages"]["stopped"] == 0
    assert set(j["fit"]["values"]) == {"Rvent"}
    lo, hi = j["fit"]["ci"]["Rvent"]
    assert lo < j["fit"]["values"]["Rvent"] < hi
    assert j["fit"]["values"]["Rvent"] == pytest.approx(3.0, rel=0.02)


@pytest.mark.parametrize("ambient", [None, "101.3"])
def test_gauge_columns_are_made_absolute_with_the_netlists_ambient_or_the_one_given(
        tmp_path, capfd, record, ambient):
    """The oscillator vents to its netlist's 96 kPa: a logger's gauge readings against
    that atmosphere fit as the absolute record does; against a stated 101.3 kPa they
    are 5.3 kPa higher and fit worse; the note says which barometric pressure was used."""
    path = tmp_path / "rec.csv"
    gauge = record.rename(columns={"p_tank_kPa": "p_tank_kPag", "p_out_kPa": "p_out_kPag"})
    gauge[["p_tank_kPag", "p_out_kPag"]] -= 96.0
    gauge.to_csv(path, index=False)
    extra = [] if ambient is None else ["--ambient", ambient]
    code, out, err = run(capfd, path, "--fit", "Rvent=3.5:1:10", "--set", "V=50",
                         "--max-nfev", "8", "--json", "--no-progress", *extra)
    assert code == 0
    assert f"made absolute with the barometric pressure {ambient or 96} kPa" in err
    fit = json.loads(out)["fit"]
    rms = max(fit["rmse"].values())
    if ambient is None:  # at the noise: the same record as the absolute one
        assert fit["values"]["Rvent"] == pytest.approx(3.0, rel=0.02) and rms < 0.5
    else:  # 5.3 kPa above what the circuit can do
        assert rms > 1.0


def test_json_writer_turns_unbounded_interval_ends_into_null():
    """An interval whose upper end overflows (a parameter the data do not bound) is null
    in --json output, which stays valid JSON (json has no Infinity)."""
    import json

    import numpy as np

    from pneunet.interfaces.cli.fit_trace import _finite

    out = {"fit": {"ci": {"R": (0.5, float("inf")), "V": np.array([1.0, np.nan])}}, "n": 3}
    text = json.dumps(_finite(out), allow_nan=False)
    assert json.loads(text) == {"fit": {"ci": {"R": [0.5, None], "V": [1.0, None]}}, "n": 3}
