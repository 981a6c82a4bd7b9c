import pytest

from pneunet.design import sizing as design


def test_paper_fill_time_analytic_and_simulated():
    V = design.cylinder_volume(173, 20)
    t = design.fill_time(V, 0.566, 596, 96, 296)
    assert 0.125 < t < 0.131  # paper: < 131 ms
    assert design.simulated_fill_time(V, 0.566, 596, 96, 296) == pytest.approx(t, rel=2e-3)
    # the real valve (control at ambient) is a little slower than its R_f
    assert design.simulated_fill_time(V, None, 596, 96, 296, valve="axi") > t


def test_empty_time_and_normal_flow():
    t = design.empty_time(200, 3.0, 96, 300, 150)
    assert design.simulated_empty_time(200, 3.0, 96, 300, 150) == pytest.approx(t, rel=5e-3)
    assert float(design.to_normal_l_min(871.1)) == pytest.approx(40.4, abs=0.1)
    assert float(design.from_normal_l_min(design.to_normal_l_min(123.0))) == pytest.approx(123.0)


def test_table_2():
    df = design.valve_comparison()
    assert list(df["key"]) == ["axi", "mirror", "festo_vppm", "festo_veab", "clippard",
                               "microfluidic"]
    assert df.set_index("key").loc["axi", "resistance"] == 0.566
    # the membrane valves give the most flow per gram
    assert df.sort_values("flow_per_g", ascending=False)["key"].iloc[0] == "mirror"
