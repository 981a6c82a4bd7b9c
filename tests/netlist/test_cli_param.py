"""Issue 32: `pneunet run --param NAME=VALUE` sets a .param for one run, and `pneunet
design` checks (and takes the yield of) given values without a search."""
import json

import pytest

from pneunet.interfaces.cli import main
from pneunet.netlist import parse_netlist, runner

NET = """* rc
.param R=1 V=10
P1 a 200kPa
R1 a b {R}
V1 b {V}
.tran 1ms 0.05s
.meas tran pb FIND p(b) AT=0.01
"""


@pytest.fixture()
def net(tmp_path):
    path = tmp_path / "rc.pn"
    path.write_text(NET)
    return path


def _pb(overrides):
    return runner.run_deck(parse_netlist(NET, overrides=overrides)).measures["pb"]


def test_run_param_sets_the_value_of_that_run(net, tmp_path, capsys):
    assert main(["run", str(net), "--param", "R=2", "--param", "V=0.02L", "-q", "--json",
                 "-o", str(tmp_path / "out")]) == 0
    got = json.loads(capsys.readouterr().out)["measures"]["pb"]
    assert got == pytest.approx(_pb({"R": 2.0, "V": 20.0}), rel=1e-12)
    assert got != pytest.approx(_pb({}), rel=1e-3)


@pytest.mark.parametrize("arg, text", [
    ("Rr=2", "parameter 'Rr' is not defined by a .param line"),
    ("R", "expected NAME=VALUE"),
    ("R=fast", "expected NAME=VALUE"),
    ("R=2furlongs/fortnight", "--param 'R=2furlongs/fortnight'"),
])
def test_a_bad_run_param_is_exit_2_with_one_message(net, tmp_path, capsys, arg, text):
    assert main(["run", str(net), "--param", arg, "-q", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert text in err and "Traceback" not in err


def test_design_checks_given_values_and_their_yield_without_a_search(net, capsys):
    assert main(["design", str(net), "--param", "R=2", "--target", "pb=150kPa±100kPa",
                 "--yield", "4", "--tolerance", "R=±10%", "--json", "-q"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["values"] == {"R": 2.0}
    assert out["metrics"]["pb"] == pytest.approx(_pb({"R": 2.0}), rel=1e-12)
    assert out["yield"]["n"] == 4
