"""pneunet design: the chosen values, re-simulated independently, meet the targets."""
import json

import pytest

from pneunet.interfaces.cli import main
from pneunet.design import design


def resimulated_period(path, values):
    """Period (s) of p(tank) over the second half of the netlist's transient, simulated
    without the design machinery."""
    from pneunet.engine import measure
    from pneunet.netlist import parse_file

    sol = parse_file(path, overrides=values).circuit.tran(14.0)
    return measure.period(sol.t, sol.pressure("tank"), t_from=7.0)


def test_design_meets_period_when_resimulated(short_oscillator, capsys):
    status = main(["design", str(short_oscillator), "--vary", "Rout=0.6:3",
                   "--vary", "Rvent=1:10", "--target", "period=2s±0.1s",
                   "--target", "swing>=120kPa", "--starts", "6", "--workers", "2", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert status == 0 and out["met"]
    assert set(out["values"]) == {"Rout", "Rvent"}
    assert abs(resimulated_period(short_oscillator, out["values"]) - 2.0) <= 0.1
    assert out["metrics"]["swing"] >= 120
    assert out["simulations"] >= 6


def test_unreachable_target_reports_closest_design_and_limiting_bound(short_oscillator):
    # the period grows with R_vent (2.3 s at 2, 3.0 s at 3): it cannot reach 30 s
    result = design(short_oscillator, {"Rvent": (2.0, 3.0)}, ["period=30s"], n_start=4,
                    tries=1, max_nfev=4, workers=1)
    assert not result.met
    assert result.limiting == [{"parameter": "Rvent", "bound": "high", "value": 3.0}]
    assert result.values["Rvent"] == pytest.approx(3.0)
    row = result.targets[0]
    assert row["miss"] == pytest.approx(abs(row["achieved"] - 30) - row["tolerance"])


@pytest.mark.parametrize("args, message", [
    (["--vary", "Rout=3:0.6"], "empty, low 3 ≥ high 0.6"),
    (["--vary", "Rout=-1:3"], "low end -1 is not positive"),
    (["--vary", "Rot=0.6:3"], "did you mean 'Rout'?"),
    (["--vary", "Vtnk.V=40:400"], "did you mean 'Vtank'?"),
    (["--vary", "V=40:400"], "an element parameter is ELEMENT.PARAM: Vtank.V"),
    (["--vary", "Rout=0.6:3", "--target", "perod=3s"], "did you mean 'period'?"),
    (["--vary", "Rout=0.6:3", "--target", "period=3kPa"], "needs s, got kPa"),
    (["--vary", "Rout=0.6:3", "--target", "duty@tnk=0.4"], "did you mean 'tank'?"),
    (["--vary", "Rout=0.6:3", "--starts", "-3"], "argument --starts: -3: must be >= 1"),
    (["--vary", "Rout=0.6:3", "--target", "period=-3s"], "period = -3 s can never be measured"),
    (["--vary", "Rout=0.6:3", "--target", "duty=1.5"], "duty lies in [0, 1]"),
    (["--vary", "Rout=0.6:3", "--yield", "1e9", "--tolerance", "X1.pclose=±5kPa"],
     "--yield asks for 1e+09 (limit max_samples = 100000)"),
    (["--vary", "Rout=0.6:3", "--max-evaluations", "inf"], "'inf' is not a whole number"),
])
def test_bad_input_is_exit_2_before_simulating(short_oscillator, capsys, args, message):
    argv = ["design", str(short_oscillator), "--json"] + args
    if "--target" not in args:
        argv += ["--target", "period=3s"]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and message in captured.err and "Traceback" not in captured.err


def test_a_wildcard_target_stands_for_every_matching_meas():
    from pneunet.design.spec import parse_targets

    measures = {"sel0": "kPa", "idle0": "kPa", "sel1": "kPa"}
    targets = parse_targets(["sel*>=296kPa", "period=3s"], measures)
    assert [(t.key, t.op, t.value) for t in targets] == [
        ("sel0", ">=", 296.0), ("sel1", ">=", 296.0), ("period", "=", 3.0)]
    with pytest.raises(Exception, match="no .meas name matches 'act\\*'"):
        parse_targets(["act*>=1kPa"], measures)



def test_fill_time_target_is_the_netlists_meas(capsys):
    """An actuator fill time (.meas FILLTIME) as a target, checked at the netlist's own
    values (no --vary): the achieved value is the one the netlist runner measures."""
    from pathlib import Path

    from pneunet.netlist import parse_file
    from pneunet.netlist.runner import run_deck

    netlist = str(Path(__file__).resolve().parents[2] / "netlists" / "fill_time.pn")
    fill = run_deck(parse_file(netlist)).measures["fill_valve"]  # 0.136 s
    assert main(["design", netlist, "--target", "fill_valve<=140ms", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["metrics"]["fill_valve"] == pytest.approx(fill) and out["values"] == {}
    assert main(["design", netlist, "--target", "fill_valve<=130ms", "--json"]) == 1
    row = json.loads(capsys.readouterr().out)["targets"][0]
    assert not row["met"] and row["miss"] == pytest.approx(fill - 0.130)
