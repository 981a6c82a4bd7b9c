"""Done-when 1 of issue 16: no raw SUNDIALS line reaches file descriptor 1 or 2 when the
shipped netlists, a 4-bit demultiplexer and a sweep run (fit-trace --json: tests/traces).
The runs are cut short; a circuit that does draw SUNDIALS messages is in
tests/core/test_solver_diagnostics.py."""
import json
import re
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main

NETLISTS = Path(__file__).parents[1] / "netlists"
RAW = re.compile(r"\[(WARNING|ERROR)\]\[rank|\[\w+, Error: -?\d+\]|\.c:\d+\]")


def shortened(text, t_stop=2.0):
    """The netlist with its .tran cut to ``t_stop`` seconds."""
    return re.sub(r"^\.tran\s+(\S+)\s+\S+", rf".tran \1 {t_stop}s", text, flags=re.MULTILINE)


def demux4(demux3):
    """The 3-bit demultiplexer grown to 4 bits: 16 cells of 4 valves, 4 inverters (68 valves)."""
    text = demux3.replace("PA[0:2] a_0[0:2]", "PA[0:3] a_0[0:3]")
    text = text.replace("Xinv[0:2] data a_0[0:2] a_1[0:2]", "Xinv[0:3] data a_0[0:3] a_1[0:3]")
    text = text.replace(".subckt CELL data c0 c1 c2 act", ".subckt CELL data c0 c1 c2 c3 act")
    text = text.replace("X2 n2 act c2", "X2 n2 n3 c2")
    text = text.replace("Vn2 n2 0.5mL", "Vn2 n2 0.5mL\nX3 n3 act c3 mirror "
                        "backward=mirror_backward\nVn3 n3 0.5mL")
    text = text.replace("Xcell[0:7] data a_{index%2}[0] a_{floor(index/2)%2}[1] "
                        "a_{floor(index/4)%2}[2] act[0:7]",
                        "Xcell[0:15] data a_{index%2}[0] a_{floor(index/2)%2}[1] "
                        "a_{floor(index/4)%2}[2] a_{floor(index/8)%2}[3] act[0:15]")
    text = text.replace("Aact[0:7] act[0:7]", "Aact[0:15] act[0:15]")
    return text.replace("Rleak[0:7] act[0:7]", "Rleak[0:15] act[0:15]")


def run_clean(capfd, tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    code = main(["run", str(path), "-o", str(tmp_path / "out"), "--no-progress"])
    out, err = capfd.readouterr()
    assert not RAW.search(out + err), (out + err)[:800]
    return code, out


@pytest.mark.parametrize("netlist", sorted(NETLISTS.glob("*.pn")), ids=lambda p: p.stem)
def test_shipped_netlists_print_no_raw_solver_line(tmp_path, capfd, netlist):
    code, out = run_clean(capfd, tmp_path, netlist.name, shortened(netlist.read_text()))
    assert code == 0 and ".tran: wrote" in out


def test_a_4bit_demultiplexer_prints_no_raw_solver_line(tmp_path, capfd):
    text = demux4((NETLISTS / "demux3.pn").read_text())
    code, out = run_clean(capfd, tmp_path, "demux4.pn", shortened(text, 4.0))
    assert code == 0 and "unknowns=68" in out


def test_sweep_json_is_only_json_on_stdout(tmp_path, capfd):
    code = main(["sweep", "--circuit", "oscillator", "--param", "Rout=list:0,1.132",
                 "--t-stop", "6", "--workers", "1", "--analysis", "oscillation", "--json",
                 "--out", str(tmp_path / "s.csv")])
    out, err = capfd.readouterr()
    assert code == 0 and not RAW.search(out + err)
    summary = json.loads(out)
    assert summary["points"] == 2 and summary["failed"] == 0
    assert [row["solver_messages"] for row in summary["rows"]] == [0, 0]


def test_branches_json_is_only_json_and_counts_the_solver_messages(capfd):
    code = main(["branches", "--simulate", "8", "--json"])
    out, err = capfd.readouterr()
    assert code == 0 and not RAW.search(out + err)
    assert json.loads(out)["simulated"]["solver_messages"] == {"count": 0}


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_q_silences_the_solver_warnings_of_every_command(tmp_path, capfd, monkeypatch, command):
    from pneunet.common import solver_messages as diagnostics

    monkeypatch.setattr(diagnostics, "_announced", set())  # shown once per process
    shipped = (NETLISTS / "oscillator.pn").read_text()
    netlist = tmp_path / "osc.pn"  # its fold indicator almost off: IDA's corrector fails
    netlist.write_text(shipped.replace(".options ambient=96kPa",
                                       ".options ambient=96kPa fold_threshold=1e-8")
                       .replace(".tran 10ms 30s", ".tran 10ms 6s").replace("FROM=10s", "FROM=1s"))
    args = {"run": ["run", str(netlist), "-o", str(tmp_path / "out")],
            "sweep": ["sweep", str(netlist), "--param", "Rvent=list:3", "--workers", "1",
                      "--out", str(tmp_path / "s.csv")]}[command]
    main(args)
    assert "warning: IDA" in capfd.readouterr().err
    main([*args, "-q"] if command == "run" else [*args, "--fresh", "-q"])
    assert "warning" not in capfd.readouterr().err
