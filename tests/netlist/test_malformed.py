"""Each malformed netlist yields the right error at the right line and column, exit code 2."""
import re
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main
from pneunet.common.errors import NetlistError, printable
from pneunet.netlist import parse_file

CORPUS = sorted((Path(__file__).parent / "malformed").glob("*.pn"))
HEADER = re.compile(r"^\* expect: (\d+):(\d+): (.+)$")


def expectation(path):
    m = HEADER.match(path.read_bytes().split(b"\n")[0].decode())
    assert m, f"{path.name}: first line must be '* expect: LINE:COL: substring'"
    return int(m.group(1)), int(m.group(2)), m.group(3)


def test_corpus_is_large_enough():
    assert len(CORPUS) >= 60


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_error_line_column(path, opened_files):
    """The error, its place and its caret; nothing opened outside the corpus folder."""
    line, column, text = expectation(path)
    opened, err = opened_files(lambda: parse_file(path).validate())
    assert all(p.startswith(str(path.parent.resolve())) for p in opened), opened
    assert isinstance(err, NetlistError), f"{type(err).__name__}: {err}"
    assert err.span is not None
    assert (err.span.line, err.span.column) == (line, column), err.report()
    assert text in err.message or text in (err.hint or ""), err.report()
    # the report points at the offending character with a caret (long lines: a window)
    report = err.report()
    assert f"{path}:{line}:{column}: error:" in report
    shown, caret = report.splitlines()[1:3]
    source = path.read_bytes().decode("utf-8", errors="replace").split("\n")[line - 1]
    pos = caret.index("^")
    assert len(shown) <= 4 + 122 and len(caret) == pos + 1
    if column <= len(source.rstrip()):
        assert shown[pos] == printable(source[column - 1].replace("\t", " "))[0]
    else:
        assert pos == len(shown)


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_cli_exit_code_2(path, capsys, tmp_path):
    line, column, _ = expectation(path)
    assert main(["run", str(path), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f":{line}:{column}: error:" in err
    assert "Traceback" not in err


def test_check_exit_code_2(capsys):
    assert main(["check", str(CORPUS[0])]) == 2


def test_save_of_a_signal_the_element_lacks_exit_2(capsys, tmp_path):
    """``T(VC)`` saves the chamber's temperature; ``Tgas(VC)`` is an error at its column
    naming ``T(VC)``, as written in .save (issue 32: the hint named the column T_VC_K)."""
    text = ("P1 s 400kPa\nR1 s x 1.0\nthermal_inlet I1 x v vT\n"
            "thermal_chamber VC v vT V=50mL tau=0.3\n.tran 10ms 0.2s\n.save p(v) {}\n")
    good, bad = tmp_path / "good.pn", tmp_path / "bad.pn"
    good.write_text(text.format("T(VC)"))
    bad.write_text(text.format("Tgas(VC)"))
    assert main(["run", str(good), "-o", str(tmp_path / "g"), "-q"]) == 0
    assert (tmp_path / "g" / "tran.csv").read_text().splitlines()[0] == "time_s,p_v_kPa,T_VC_K"
    assert main(["run", str(bad), "-o", str(tmp_path / "b"), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:6:12: error: element 'VC' (thermal_chamber) has no signal Tgas(...)" in err
    assert "its signals: T(VC)" in err and "Traceback" not in err


def test_byte_order_mark_is_accepted_and_non_utf8_bytes_are_located(capsys, tmp_path):
    """A UTF-8 BOM (Windows editors) parses; a byte that is not UTF-8 is exit 2 at its
    line and column, no traceback."""
    good, bad = tmp_path / "bom.pn", tmp_path / "latin1.pn"
    good.write_bytes(b"\xef\xbb\xbfP1 a 200kPa\nR1 a atm 1\nV1 a 10mL\n")
    bad.write_bytes(b"P1 a 200kPa\nR1 a atm 1 ; r\xe9sistance\nV1 a 10mL\n")
    assert parse_file(good).circuit.elements["P1"].kind == "pressure_source"
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:2:15: error: byte 0xe9 is not UTF-8" in err and "Traceback" not in err


def test_a_node_with_one_connection_is_warned_with_a_did_you_mean(capsys, tmp_path):
    """``Rvent tnak atm`` (tank misspelt) makes a node with one connection: check and run
    say so on stderr, naming the line and the likely node; the shipped netlists have none."""
    path = tmp_path / "typo.pn"
    path.write_text("P1 supply 300kPa\nR1 supply tank 1\nVtank tank 10mL\n"
                    "Rvent tnak atm 1\n.tran 10ms 0.1s\n")
    assert main(["check", str(path)]) == 0
    err = capsys.readouterr().err
    assert f"{path}:4:1: node 'tnak' has one connection (Rvent); did you mean 'tank'?" in err
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "-q"]) == 0
    assert "did you mean 'tank'" in capsys.readouterr().err
    for shipped in sorted((Path(__file__).parents[2] / "netlists").glob("*.pn")):
        assert main(["check", str(shipped)]) == 0
        assert "warning" not in capsys.readouterr().err, shipped


def test_output_file_in_the_way_and_absurd_output_grid_exit_2(capsys, tmp_path):
    """``-o`` naming an existing file, and ``.tran 1e-9 30s`` (3·10¹⁰ output points): exit 2
    with what to change, no traceback and no allocation attempt; the limit is named and an
    unknown --limit name is exit 2."""
    net = tmp_path / "n.pn"
    net.write_text("P1 a 200kPa\nR1 a atm 1\nV1 a 10mL\n.tran 10ms 0.1s\n")
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["run", str(net), "-o", str(blocker), "-q"]) == 2
    assert f"{blocker} is a file; name a folder" in capsys.readouterr().err
    net.write_text("P1 a 200kPa\nR1 a atm 1\nV1 a 10mL\n.tran 1e-9 30s\n")
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{net}:4:7: error: .tran 1e-09 30 asks for 3e+10 output points (limit " \
        "max_output_points = 10000000)" in err and "Traceback" not in err
    assert main(["run", str(net), "-o", str(tmp_path / "out"), "-q", "--limit",
                 "max_output_points=1e11", "--limit", "max_elemnts=5"]) == 2
    assert "unknown limit 'max_elemnts'" in capsys.readouterr().err


def test_max_output_points_raised_by_limit_reaches_the_engine(capsys, tmp_path):
    """``--limit max_output_points`` governs the run, not only the parse: a limit below
    the default refuses a grid the default allows, and a .tran over the engine's default
    runs once the limit is raised (checked on the API: the engine takes the deck's word)."""
    from pneunet import Circuit
    from pneunet.common.errors import PneunetError

    net = tmp_path / "n.pn"
    net.write_text("P1 a 200kPa\nR1 a atm 1\nV1 a 10mL\n.tran 10ms 1s\n")
    assert main(["run", str(net), "-o", str(tmp_path / "o1"), "-q", "--limit",
                 "max_output_points=50"]) == 2
    assert "max_output_points = 50" in capsys.readouterr().err
    assert main(["run", str(net), "-o", str(tmp_path / "o2"), "-q"]) == 0
    c = Circuit("c")
    c.pressure_source("P1", "a", 200.0)
    c.resistor("R1", "a", "atm", R=1.0)
    c.volume("V1", "a", V=10.0)
    with pytest.raises(PneunetError, match="max_output_points = 5e\\+01"):
        c.tran(1.0, t_step=0.01, max_output_points=50)
    assert len(c.tran(1.0, t_step=0.01, max_output_points=200).t) == 101
