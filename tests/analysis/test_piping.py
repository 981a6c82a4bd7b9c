"""Piping-footprint study (issue 12, paper Fig. 1B): cross-sections by hand, fill times in
a sensible order, and one power line's fill time against a finite-volume line fed through
the valve law (eqs. 13, 19, 25 with the paper's axi parameters) written here."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.sparse import diags

from pneunet import ParameterError
from pneunet.design.piping import (PipingSpec, Tubing, build, cross_section, piping_study,
                                   plot_piping, with_sizes)

from reference_lines import R_AIR, T, line_flow  # tests/ is on pytest's sys.path


def test_fig1b_cross_sections_by_hand():
    """Four 4 mm lines against one 4 mm supply line and four 3 mm control lines:
    1 − (16 + 4·9)/(4·16) = 18.75 %, the paper's 19 %; by bore (2.5 and 1.2 mm)
    1 − (6.25 + 4·1.44)/(4·6.25) = 52 %.  Demux: two 3 mm address lines, 1 − 34/64."""
    spec = PipingSpec()
    assert cross_section(spec, "individual") == pytest.approx(4 * math.pi / 4 * 16)
    assert cross_section(spec, "supply+control") == pytest.approx(math.pi / 4 * (16 + 36))
    assert cross_section(spec, "demux") == pytest.approx(math.pi / 4 * (16 + 18))
    assert cross_section(spec, "supply+control", "bore") == pytest.approx(
        math.pi / 4 * (6.25 + 4 * 1.44))
    study = piping_study(spec, designs=["individual", "supply+control", "demux"])
    table = study.table
    assert table.loc["supply+control", "saving_outer_pct"] == pytest.approx(18.75)
    assert table.loc["supply+control", "saving_bore_pct"] == pytest.approx(51.96)
    assert table.loc["demux", "saving_outer_pct"] == pytest.approx(100 * (1 - 34 / 64))
    assert list(table["lines"]) == [4, 5, 3]


@pytest.mark.parametrize("n, bits", [(2, 1), (3, 2), (8, 3), (9, 4), (64, 6)])
def test_address_lines_are_log2_of_the_actuators(n, bits):
    spec = PipingSpec(actuators=n)
    assert spec.bits == bits
    assert cross_section(spec, "demux") == pytest.approx(math.pi / 4 * (16 + bits * 9))


def test_fill_times_are_in_a_physical_order(tmp_path):
    spec = PipingSpec(actuators=4)
    study = piping_study(spec)
    r = study.results
    # own lines: all at once as fast as one; a shared supply line is slower when all draw
    assert r["individual"].all_s == pytest.approx(r["individual"].alone_s[0], rel=1e-3)
    assert r["supply+control"].all_s > 1.2 * r["supply+control"].alone_s[0]
    # a valve behind a control line opens later than one driven at the source
    assert r["supply+control"].alone_s[0] > r["individual"].alone_s[0]
    # the demultiplexer: a chain of valves behind address lines and inverters, one at a time
    assert np.all(r["demux"].alone_s > r["supply+control"].alone_s)
    assert r["demux"].all_s == pytest.approx(r["demux"].alone_s.sum())
    # a longer control line delays the fill; a wider supply line speeds up "all"
    longer = piping_study(PipingSpec(actuators=4, length=3000.0), ["supply+control"])
    wider = piping_study(with_sizes(spec, supply="4/6"), ["supply+control"])
    assert longer.results["supply+control"].alone_s[0] > r["supply+control"].alone_s[0]
    assert wider.results["supply+control"].all_s < r["supply+control"].all_s
    # every actuator filled; the others stay at ambient while one fills
    sol = build(spec, "supply+control", [0]).tran(2.0, t_step=0.01)
    assert sol.pressure("act0")[-1] > spec.filled
    assert max(sol.pressure(f"act{k}").max() for k in (1, 2, 3)) < spec.ambient + 1.0
    assert plot_piping(study, tmp_path / "piping.png").stat().st_size > 10_000
    assert study.as_dict()["table"][0]["design"] == "individual"


def _valve_flow(p_in, p_out, p_ctrl, rf=0.566, pclose=96.42, ptrans=155.1, e=1.99, ain=0.32,
                aout=0.71):
    """mg/s, the paper's axi valve: Δp = a_in·p_in + a_out·p_out − p_ctrl (p_in > p_out),
    u = (Δp − p_close)/(p_trans − p_close), ṁ = u^e/(R_f·√(1 + u^2e))·√(p_in² − p_out²)."""
    u = max((ain * p_in + aout * p_out - p_ctrl - pclose) / (ptrans - pclose), 0.0)
    return u ** e / (rf * np.sqrt(1 + u ** (2 * e))) * np.sqrt(max(p_in ** 2 - p_out ** 2, 0.0))


def test_one_power_line_fills_as_a_finite_volume_line_behind_the_valve():
    """Design "individual", one actuator: source 496 kPa → valve (control 96 kPa from t = 0)
    → 1 m of 2.5 mm line (200 nodes) → 50 mL; filled at 90 % of the gauge (456 kPa)."""
    spec = PipingSpec(actuators=1)
    cells, length, d = 200, spec.length * 1e-3, spec.power.bore * 1e-3
    dx = length / cells
    caps = np.full(cells + 1, np.pi / 4 * d ** 2 * dx) / (R_AIR * T)   # kg/Pa
    caps[[0, -1]] /= 2
    caps[-1] += spec.volume * 1e-6 / (R_AIR * T)

    def rate(t, p):
        inflow = np.r_[_valve_flow(spec.p_supply, p[0] / 1e3, spec.ambient) * 1e-6,
                       line_flow(p[:-1], p[1:], dx, d)]
        return (inflow - np.r_[inflow[1:], 0.0]) / caps

    def filled(t, p):
        return p[-1] - spec.filled * 1e3
    filled.terminal = True
    ref = solve_ivp(rate, (0.0, 5.0), np.full(cells + 1, spec.ambient * 1e3), method="BDF",
                    jac_sparsity=diags([1.0, 1.0, 1.0], [-1, 0, 1], shape=(cells + 1,) * 2),
                    rtol=1e-8, atol=1e-3, events=filled).t_events[0][0]
    study = piping_study(spec, designs=["individual"])
    assert study.results["individual"].alone_s[0] == pytest.approx(ref, rel=0.01)


@pytest.mark.parametrize("make, message", [
    (lambda: PipingSpec(actuators=0), "actuators=0"),
    (lambda: PipingSpec(length=-1.0), "length=-1.0"),
    (lambda: PipingSpec(level=1.2), "level=1.2"),
    (lambda: PipingSpec(actuators=3, positions=(0, 100)), "one distance >= 0 mm per actuator"),
    (lambda: Tubing(3.0, 2.0), "bore must be"),
    (lambda: piping_study(PipingSpec(actuators=1), ["demux"]), "at least 2 actuators"),
    (lambda: piping_study(PipingSpec(), ["star"]), "unknown piping design 'star'"),
])
def test_bad_input_is_named(make, message):
    with pytest.raises(ParameterError, match=message):
        make()


def test_command_line_prints_the_table_and_json(tmp_path, capsys):
    import json

    from pneunet.interfaces.cli import main

    assert main(["piping", "-n", "2", "--length", "0.5m", "--designs",
                 "individual,supply+control", "--plot", str(tmp_path / "p.png")]) == 0
    out = capsys.readouterr().out
    assert "supply+control" in out and "saving %" in out and (tmp_path / "p.png").is_file()
    assert main(["piping", "-n", "2", "--designs", "individual", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["spec"]["actuators"] == 2 and len(data["fill_alone_s"]["individual"]) == 2
    assert main(["piping", "-n", "2", "--spacing", "20cm", "--designs", "individual"]) == 0
    assert "+ 200 mm per actuator" in capsys.readouterr().out
    assert main(["piping", "--control", "3/2"]) == 2
    assert "control: tubing 3/2 mm" in capsys.readouterr().err
    assert main(["piping", "--length", "3kg"]) == 2
    assert "--length" in capsys.readouterr().err


def test_a_longer_control_line_delays_and_smooths_the_valve():
    """The control pressure at the valve falls later and more slowly on a longer line, and
    the axi valve opens only once it is below a_in·p_in + a_out·p_out − p_close
    = 0.32·496 + 0.71·96 − 96.42 = 130.4 kPa (eq. 25, actuator still at ambient)."""
    from pneunet.design.piping import control_line_delays

    result = control_line_delays(PipingSpec(t_stop=3.0), lengths=(500.0, 2000.0))
    short, long_ = result.table.loc[500.0], result.table.loc[2000.0]
    for column in ("ctrl_10_s", "ctrl_50_s", "ctrl_90_s", "actuator_moves_s", "fill_s"):
        assert long_[column] > short[column], column
    assert long_["ctrl_90_s"] - long_["ctrl_10_s"] > 3 * (short["ctrl_90_s"] - short["ctrl_10_s"])
    t, ctl, act = result.traces[2000.0]
    opens = np.flatnonzero(act > 96.0 + 1e-3)[0]
    assert ctl[opens] == pytest.approx(130.4, abs=3.0)


def test_actuators_along_the_robot_fill_in_the_order_of_their_distance():
    """Actuators 0, 200, 400 mm along the robot: their own lines are 1.0, 1.2, 1.4 m; the
    shared lines run along the robot with a tap at each actuator."""
    spec = PipingSpec(actuators=3, positions=(0.0, 200.0, 400.0))
    c = build(spec, "supply+control", [0])
    lengths = {name: sum(e.params["length"] for n, e in c.elements.items()
                         if n.startswith(name + ".")) for name in ("TS0", "TS1", "TC2")}
    assert lengths == pytest.approx({"TS0": 1000.0, "TS1": 200.0, "TC2": 1400.0})
    demux = build(spec, "demux", [2])   # address lines and their complements tapped too
    assert {"TA0_0", "TA0_2", "TB1_1", "a1_1"} <= set(demux.nodes)
    study = piping_study(spec)
    for design in ("individual", "supply+control"):
        assert np.all(np.diff(study.results[design].alone_s) > 0), design
    assert study.table.loc["individual", "fill_alone_max_s"] > piping_study(
        PipingSpec(actuators=3), ["individual"]).table.loc["individual", "fill_alone_max_s"]
