"""Every shipped netlist parses and validates; some run and agree with the Python API."""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from pneunet import Circuit
from pneunet.engine import measure
from pneunet.interfaces.cli import main
from pneunet.netlist import parse_file, parse_netlist
from pneunet.netlist.runner import run_deck

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "netlists").glob("*.pn"))


def test_all_shipped_netlists_are_there():
    names = {p.stem for p in SHIPPED}
    assert {"oscillator", "oscillator_rout0", "amplifier", "fill_time", "inverter",
            "demux3"} <= names


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_parses_and_validates(path, capsys):
    deck = parse_file(path)
    deck.circuit.validate()
    assert deck.analyses and deck.measures
    assert main(["check", str(path)]) == 0
    assert "ok" in capsys.readouterr().out


def test_fill_time_matches_python_api_and_analytic(tmp_path, capsys):
    assert main(["run", str(ROOT / "netlists/fill_time.pn"), "-o", str(tmp_path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    fill = report["measures"]["fill_R"]
    # the same circuit through the Python API
    c = Circuit("fill", ambient=96.0, rtol=1e-7, atol=1e-7)
    c.pressure_source("P1", "supply", "500kPag")
    c.resistor("Rf", "supply", "act_r", 0.566)
    c.actuator("A1", "act_r", length="173mm", diameter="20mm")
    c.valve("X1", "supply", "act_v", "atm", model="axi_0p6mm")
    c.actuator("A2", "act_v", length="173mm", diameter="20mm")
    sol = c.tran(0.4, t_step=1e-3)
    api = measure.transition_time(sol.t, sol.pressure("act_r"), 96.0, 296.0)
    assert fill == pytest.approx(api, rel=1e-9)
    assert fill == pytest.approx(0.1309, abs=5e-4)      # analytic R_f C (asin - asin)
    assert report["measures"]["fill_valve"] < 0.140
    table = pd.read_csv(tmp_path / "tran.csv")
    assert {"time_s", "p_act_r_kPa", "mdot_Rf_mg_s"} <= set(table.columns)


def test_inverter_meas_match_python_api(tmp_path):
    deck = parse_file(ROOT / "netlists/inverter.pn")
    res = run_deck(deck)
    sol = res.results[0][1]
    assert res.measures["out1_when_in_low"] == pytest.approx(
        measure.value_at(sol.t, sol.pressure("out1"), 0.9))
    assert res.measures["out1_when_in_low"] > 450 and res.measures["out1_when_in_high"] < 100
    assert res.measures["out2_when_in_low"] < 100 and res.measures["out2_when_in_high"] > 450


STEP_NETLIST = """
.options ambient=96kPa
.param Rout=1.132 Rvent=3
PH supply 496kPa
X1 supply out tank axi_0p6mm
Rout out tank {Rout}
Vtank tank 200mL
Rvent tank atm {Rvent}
.tran 20ms 14s
.step param Rout list 1.132 1.415
.step param Rvent list 2.5 3
.meas tran period PERIOD p(tank) FROM=5s
.meas tran swing PP p(tank) FROM=5s
"""


def test_step_over_rout_and_rvent(tmp_path, capsys):
    net = tmp_path / "osc_step.pn"
    net.write_text(STEP_NETLIST)
    out = tmp_path / "out"
    assert main(["run", str(net), "-o", str(out), "--quiet"]) == 0
    summary = pd.read_csv(out / "meas_summary.csv")
    assert list(summary.columns) == ["Rout", "Rvent", "period", "swing"]
    assert summary[["Rout", "Rvent"]].values.tolist() == [[1.132, 2.5], [1.132, 3], [1.415, 2.5],
                                                          [1.415, 3]]
    for i in range(1, 5):
        assert (out / f"tran_step{i}.csv").is_file()
    # step 2 equals a plain run of the nominal deck (Rout=1.132, Rvent=3) through the API
    deck = parse_netlist(STEP_NETLIST)
    c = Circuit("osc", ambient=96.0)
    c.pressure_source("PH", "supply", 496)
    c.valve("X1", "supply", "out", "tank", model="axi_0p6mm")
    c.resistor("Rout", "out", "tank", 1.132)
    c.volume("Vtank", "tank", 200)
    c.resistor("Rvent", "tank", "atm", 3)
    sol = c.tran(14, t_step=0.02)
    api = measure.period(sol.t, sol.pressure("tank"), t_from=5)
    assert summary["period"][1] == pytest.approx(api, rel=1e-6)
    assert np.all(summary["swing"] > 50)
