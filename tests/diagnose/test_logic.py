"""Logic of the diagnosis on reduced protocols (≈ 600 points) and the command line."""
import json

import numpy as np
import pytest

from pneunet.interfaces.cli import main
from pneunet.truth.valves.diagnose import diagnose
from pneunet.truth.valves.diagnose.features import noise_floor, prepare
from pneunet.truth.valves.diagnose.scenarios import bench, reduced_protocol, scenario_truth
from pneunet.physics.valve_effects import ValveModel
from pneunet.common.errors import DataError, ParameterError

REQUIRED_KEYS = {"adequate", "unexplained", "accepted", "ranking", "baseline", "final",
                 "where", "noise_floor"}


@pytest.fixture(scope="module")
def leak_small():
    return bench(scenario_truth("leak"), reduced=True, seed=2)


def test_reduced_protocol_has_both_directions():
    proto = reduced_protocol()
    assert set(proto["sweep"]) == {-1, 1} and 400 < len(proto) < 800


def test_sweeps_are_found_with_and_without_sweep_column(leak_small):
    df, _ = prepare(leak_small)
    n_true = leak_small.groupby(["p_in_cmd_kPa", "p_out_cmd_kPa"]).ngroups
    assert df["group"].nunique() == n_true
    bare = leak_small.drop(columns=["sweep"])
    df2, notes = prepare(bare)
    assert df2["group"].nunique() == n_true
    assert (df2["sweep"].to_numpy() == leak_small["sweep"].to_numpy()).mean() > 0.9
    assert any("derived from row order" in n for n in notes)


def test_bad_data_raise_clear_errors(leak_small):
    with pytest.raises(DataError, match="lacks column"):
        diagnose(leak_small.drop(columns=["mdot_mg_s"]), progress=False)
    with pytest.raises(DataError, match="sweep"):
        diagnose(leak_small.iloc[:40], progress=False)
    with pytest.raises(ParameterError, match="unknown effect"):
        diagnose(leak_small, effects=["leek"], progress=False)


def test_noise_floor_estimate_follows_flow_dependent_noise():
    truth = scenario_truth("clean")
    data = bench(truth, seed=4, noise_mdot=2.0, noise_rel=0.0, noise_p=0.0)
    df, _ = prepare(data)
    pred = truth(df)
    est = noise_floor(df, df["mdot_mg_s"].to_numpy() - pred, pred)
    assert abs(est["rmse"] / 2.0 - 1) < 0.15


def test_reduced_leak_is_named_and_report_json_complete(leak_small):
    diag = diagnose(leak_small, progress=False)
    j = diag.to_json()
    assert REQUIRED_KEYS <= set(j)
    assert j["accepted"] == ["leak"]
    assert {"effect", "cv_rmse", "gain", "accepted"} <= set(j["ranking"][0])
    for key in ("baseline", "final"):
        assert {"rmse", "rmse_open", "cv_rmse"} <= set(j[key])
    assert [w["importance"] for w in j["where"]] == sorted(
        [w["importance"] for w in j["where"]], reverse=True)
    json.dumps(j)  # serialisable
    text = diag.report()
    assert "Error waterfall" in text and "+ leak" in text and "leak_G=" in text
    model = ValveModel.from_card_params(j["final"]["params"])
    assert np.allclose(model(leak_small), diag.model(leak_small))


def test_one_sweep_direction_skips_hysteresis_and_says_why(leak_small):
    down = leak_small.copy()
    down["sweep"] = -1
    diag = diagnose(down, effects=["hysteresis", "leak"], progress=False)
    hyst = [c for c in diag.ranking if c.effect == "hysteresis"][0]
    assert not hyst.screened and "one direction" in hyst.reason
    assert any("one sweep direction" in n for n in diag.notes)


def test_cli_json_card_and_plots(tmp_path, leak_small, capsys):
    csv = tmp_path / "bench.csv"
    leak_small.to_csv(csv, index=False)
    card = tmp_path / "v.model"
    rc = main(["diagnose", str(csv), "--json", "--no-progress", "--effects", "leak", "laminar",
               "--model-out", str(card), "--plots", str(tmp_path / "figs")])
    assert rc == 0
    j = json.loads(capsys.readouterr().out)
    assert REQUIRED_KEYS <= set(j) and j["accepted"] == ["leak"]
    assert [r["effect"] for r in j["ranking"]] == ["leak", "laminar"]
    line = card.read_text().splitlines()[-1]
    assert line.startswith(".model VDIAG VALVE(") and "leak_G=" in line
    params = dict(kv.split("=") for kv in line[line.index("(") + 1:-1].split())
    # only accepted effects go into the card
    assert ValveModel.from_card_params({k: float(v) for k, v in params.items()}).effect_ids == [
        "leak"]
    for name in ("waterfall.png", "residual_maps.png", "where.png"):
        assert (tmp_path / "figs" / name).stat().st_size > 10_000


def test_cli_plugin_registers_user_effect(tmp_path, leak_small, capsys):
    plugin = tmp_path / "my_effects.py"
    plugin.write_text(
        "from pneunet.physics.valve_effects import Effect, Param, register_effect\n"
        "@register_effect(replace=True)\n"
        "class Gain(Effect):\n"
        "    '''Flow-sensor gain error: ṁ_meas = (1 + g) ṁ. Null value 0.'''\n"
        "    id = 'sensor-gain'\n"
        "    params = {'g': Param('1', -0.5, 0.5, 0.0, 'gain error', init=0.001)}\n"
        "    order = 90\n"
        "    def flow(self, m, x, g):\n"
        "        return m * (1 + g)\n")
    csv = tmp_path / "bench.csv"
    leak_small.to_csv(csv, index=False)
    try:
        rc = main(["diagnose", str(csv), "--json", "--no-progress", "--plugin", str(plugin),
                   "--effects", "sensor-gain", "leak"])
        assert rc == 0
        j = json.loads(capsys.readouterr().out)
        assert {r["effect"] for r in j["ranking"]} == {"sensor-gain", "leak"}
        assert j["accepted"] == ["leak"]
    finally:
        from pneunet.physics.valve_effects import unregister_effect
        unregister_effect("sensor-gain")
