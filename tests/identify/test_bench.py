"""Virtual test bench: protocol, regulator, noise, plug-in flow models."""
import numpy as np
import pytest

from pneunet.common.errors import ParameterError
from pneunet.truth.valves.identify import OutletRegulator, paper_protocol, simulate_bench
from pneunet.physics.valve_params import PAPER_VALVES


def test_paper_protocol_has_4410_points_in_experiment_order():
    p = paper_protocol()
    assert len(p) == 4410
    assert p["p_in_cmd_kPa"].min() == 121 and p["p_in_cmd_kPa"].max() == 596
    assert (p["p_out_cmd_kPa"] <= p["p_in_cmd_kPa"] - 25).all()
    assert (np.diff(p["time_s"]) > 0).all()
    first = p.iloc[:21]
    assert list(first["p_ctrl_cmd_kPa"]) == list(np.arange(596, 95, -25))
    assert (p["sweep"] == -1).all()
    up = paper_protocol(sweeps="downup")
    assert len(up) == 210 * 41 and set(up["sweep"]) == {-1, 1}


def test_bench_is_deterministic_and_has_canonical_columns():
    a = simulate_bench(PAPER_VALVES["axi"], seed=3)
    b = simulate_bench(PAPER_VALVES["axi"], seed=3)
    c = simulate_bench(PAPER_VALVES["axi"], seed=4)
    for col in ("time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s", "sweep"):
        assert col in a
    assert a.equals(b)
    assert not np.allclose(a["mdot_mg_s"], c["mdot_mg_s"])


def test_regulator_raises_outlet_pressure_like_the_paper():
    d = simulate_bench(PAPER_VALVES["axi"], noise_mdot=0, noise_rel=0, noise_p=0,
                       setpoint_error=0)
    rise = d["p_out_true_kPa"] - d["p_out_cmd_kPa"]
    # paper: measured p_out deviated from its command by up to 220 kPa
    assert 200 < rise.max() < 250
    # Fig. 7: at p_in 396 and p_ctrl 96 the open valve's p_out never went below ~227 kPa
    s = d[(d.p_in_cmd_kPa == 396) & (d.p_ctrl_cmd_kPa == 96) & (d.p_out_cmd_kPa.between(171, 221))]
    assert (s["p_out_kPa"] > 210).all()
    # the fixed point holds: p_out = max(command, floor(flow))
    floor = OutletRegulator().floor(d["mdot_true_mg_s"])
    np.testing.assert_allclose(d["p_out_true_kPa"], np.maximum(d["p_out_cmd_kPa"], floor),
                               atol=1e-3)
    # max flow about the paper's 871 mg/s at p_in 596
    assert 840 < d["mdot_true_mg_s"].max() < 900
    off = simulate_bench(PAPER_VALVES["axi"], regulator=None, noise_mdot=0, noise_rel=0,
                         noise_p=0, setpoint_error=0)
    np.testing.assert_array_equal(off["p_out_kPa"], off["p_out_cmd_kPa"])


def test_noise_and_bias_have_the_given_size():
    d = simulate_bench(PAPER_VALVES["axi"], noise_mdot=0.5, noise_rel=0.0, bias=7.0, seed=2)
    error = d["mdot_mg_s"] - d["mdot_true_mg_s"]
    assert error.mean() == pytest.approx(7.0, abs=0.05)
    assert error.std() == pytest.approx(0.5, rel=0.08)


def test_callable_flow_sees_time_and_sweep():
    seen = {}

    def leaky(frame):
        seen["columns"] = set(frame.columns)
        # a drifting leak: 2 mg/s per hour on top of the paper valve
        from pneunet.physics.laws import valve_flow

        base = valve_flow(frame["p_in_kPa"], frame["p_out_kPa"], frame["p_ctrl_kPa"],
                          **PAPER_VALVES["axi"].as_dict())
        return base + 2.0 * frame["time_s"].to_numpy() / 3600 * (frame["sweep"] < 0)

    d = simulate_bench(leaky, noise_mdot=0, noise_rel=0, noise_p=0, setpoint_error=0,
                       regulator=None)
    assert {"p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "time_s", "sweep"} <= seen["columns"]
    closed_last = d[(d.p_ctrl_cmd_kPa == 596)].iloc[-1]
    assert closed_last["mdot_mg_s"] == pytest.approx(2.0 * closed_last["time_s"] / 3600)


def test_bad_flow_model_is_refused():
    with pytest.raises(ParameterError):
        simulate_bench("axi")
    with pytest.raises(ParameterError, match="returned 3 values"):
        simulate_bench(lambda frame: np.zeros(3))
