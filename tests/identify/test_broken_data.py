"""Every file of the broken-data corpus (tests/identify/broken_data/, expectations in
expected.json: the command, an exact message fragment and the location) is exit 2
through the CLI with one message naming the file and the place, and no traceback."""
import json
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main

CORPUS = Path(__file__).parent / "broken_data"
EXPECTED = json.loads((CORPUS / "expected.json").read_text())
#: what each command needs besides the file (nothing is fitted: the data fail first)
ARGS = {"fit": [], "diagnose": ["--no-progress"], "fit-trace": ["--fit", "Rout=1.4:0.3:5"]}


def test_corpus_is_complete():
    files = {p.name for p in CORPUS.glob("*.csv")}
    assert files == set(EXPECTED) and len(files) >= 20


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_broken_file_exits_2_with_file_message_and_place(name, capsys):
    case = EXPECTED[name]
    path = CORPUS / name
    assert main([case["command"], str(path), *ARGS[case["command"]]]) == 2
    captured = capsys.readouterr()
    err = captured.err
    assert "Traceback" not in err and captured.out == ""
    assert err.count("error:") == 1, err
    first = err.splitlines()[0]
    assert str(path) in first, err
    assert case["message"] in err, err
    assert case["where"] in err, err
    assert "hint:" in err, err
