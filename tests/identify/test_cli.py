"""pneunet fit: report, JSON, model card, plots, exit 2 on bad data."""
import json

import pytest

from pneunet.interfaces.cli import main

CANON = ["time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s"]


@pytest.fixture(scope="module")
def csv(bench, tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "axi.csv"
    d = bench("axi")
    path.write_text("# axi valve, virtual bench\n" + d[CANON + ["sweep"]].to_csv(index=False))
    return path


def test_fit_json_and_model_card(csv, tmp_path, capsys):
    card = tmp_path / "axi.model"
    rc = main(["fit", str(csv), "--json", "--mdot-min", "auto", "--bootstrap", "20",
               "--name", "AXI", "--model-out", str(card)])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["params"]) == {"Rf", "pclose", "ptrans", "e", "ain", "aout"}
    assert out["params"]["Rf"]["value"] == pytest.approx(0.566, rel=0.03)
    assert out["metrics"]["n"] == 4410 and out["metrics"]["n_open"] > 1000
    assert ".model AXI VALVE(Rf=" in card.read_text()


def test_fit_report_and_plots(csv, tmp_path, capsys):
    rc = main(["fit", str(csv), "--bootstrap", "10", "--plots", str(tmp_path / "figs")])
    assert rc == 0
    text = capsys.readouterr().out
    assert "[[Variables]]" in text and ".model VFIT VALVE(" in text
    assert len(list((tmp_path / "figs").glob("*.png"))) == 5


def test_bad_data_exits_2_with_a_message(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,p_in_kPa,p_out_kPa,mdot_mg_s\n0,200,100,3\n")
    assert main(["fit", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "column p_ctrl_kPa is missing" in err and "hint" in err
    assert main(["fit", str(tmp_path / "none.csv")]) == 2
    assert main(["fit", str(bad), "--mdot-min", "lots"]) == 2
