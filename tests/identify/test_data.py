"""load_measurements: formats, units, bias removal and a clear error per bad-data case."""
import numpy as np
import pandas as pd
import pytest

from pneunet.common.errors import DataError
from pneunet.truth.valves.identify import load_measurements, simulate_bench
from pneunet.physics.valve_params import PAPER_VALVES

CANON = ["time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s"]


@pytest.fixture(scope="module")
def small():
    d = simulate_bench(PAPER_VALVES["axi"], seed=5)
    return d[CANON + ["sweep"]].iloc[:200].reset_index(drop=True)


def write(tmp_path, frame, comments=("# bench test", "# ambient 96 kPa")):
    path = tmp_path / "data.csv"
    path.write_text("\n".join(comments) + "\n" + frame.to_csv(index=False))
    return path


def test_canonical_csv_round_trip(tmp_path, small):
    m = load_measurements(write(tmp_path, small))
    assert len(m) == 200 and len(m.excluded) == 0
    np.testing.assert_allclose(m.frame[CANON].to_numpy(), small[CANON].to_numpy())
    assert m.frame["line"].iloc[0] == 4  # two comments, header, first data row


def test_gauge_bar_and_normal_litres(small):
    raw = pd.DataFrame({
        "t": small["time_s"],
        "Pin [bar g]": (small["p_in_kPa"] - 96.0) / 100.0,
        "Pout [bar g]": (small["p_out_kPa"] - 96.0) / 100.0,
        "Pctrl [bar g]": (small["p_ctrl_kPa"] - 96.0) / 100.0,
        "flow [NL/min]": small["mdot_mg_s"] / 1.2932 * 60 / 1000,
    })
    m = load_measurements(raw, gauge=True, ambient_kpa=96.0,
                          units={"pressure": "bar", "flow": "L/min"},
                          columns={"t": "time_s", "Pin [bar g]": "p_in_kPa",
                                   "Pout [bar g]": "p_out_kPa", "Pctrl [bar g]": "p_ctrl_kPa",
                                   "flow [NL/min]": "mdot_mg_s"})
    np.testing.assert_allclose(m.frame["p_in_kPa"], small["p_in_kPa"], rtol=1e-9)
    np.testing.assert_allclose(m.frame["mdot_mg_s"], small["mdot_mg_s"], rtol=2e-3)


def test_psi_per_column_unit(small):
    raw = small.copy()
    raw["p_ctrl_kPa"] = raw["p_ctrl_kPa"] / 6.894757
    m = load_measurements(raw, units={"p_ctrl": "psi"})
    np.testing.assert_allclose(m.frame["p_ctrl_kPa"], small["p_ctrl_kPa"], rtol=1e-6)


def test_flow_bias_removed_like_the_paper():
    d = simulate_bench(PAPER_VALVES["axi"], bias=12.0, noise_mdot=0.05, seed=2)
    m = load_measurements(d, flow_bias="min")
    assert m.bias_mg_s == pytest.approx(12.0, abs=0.3)
    assert m.frame["mdot_mg_s"].min() == 0.0
    assert "bias removed" in m.summary()


def test_missing_column_names_it_and_suggests_mapping(small):
    with pytest.raises(DataError, match="column p_ctrl_kPa is missing") as err:
        load_measurements(small.drop(columns="p_ctrl_kPa"))
    assert "mapping" in err.value.hint


def test_nan_rows_raise_with_row_numbers_or_are_excluded(tmp_path, small):
    bad = small.copy()
    bad.loc[[4, 9], "p_out_kPa"] = np.nan
    path = write(tmp_path, bad)
    with pytest.raises(DataError, match=r"NaN in p_out_kPa: data row\(s\) 5, 10 \(file lines 8, 13\)"):
        load_measurements(path)
    m = load_measurements(path, on_invalid="exclude")
    assert len(m) == 198
    assert list(m.excluded["row"]) == [5, 10]
    assert set(m.excluded["reason"]) == {"NaN in p_out_kPa"}
    assert "excluded 2 (NaN in p_out_kPa): rows 5, 10" in m.summary()


def test_negative_absolute_pressure(small):
    bad = small.copy()
    bad.loc[3, "p_in_kPa"] = -5.0
    with pytest.raises(DataError, match="negative absolute pressure in p_in_kPa: data row.*4"):
        load_measurements(bad)


def test_gauge_values_passed_as_absolute(small):
    bad = small.copy()
    for c in ("p_in_kPa", "p_out_kPa", "p_ctrl_kPa"):
        bad[c] = bad[c] - 96.0
    with pytest.raises(DataError, match="look like gauge") as err:
        load_measurements(bad)
    assert "--gauge" in err.value.hint
    with pytest.raises(DataError, match="ambient"):
        load_measurements(bad, gauge=True)
    ok = load_measurements(bad, gauge=True, ambient_kpa=96.0)
    np.testing.assert_allclose(ok.frame["p_in_kPa"], small["p_in_kPa"])


def test_p_in_not_above_p_out(small):
    bad = small.copy()
    bad.loc[7, "p_out_kPa"] = bad.loc[7, "p_in_kPa"] + 1
    with pytest.raises(DataError, match=r"p_in <= p_out.*data row\(s\) 8"):
        load_measurements(bad)
    m = load_measurements(bad, on_invalid="exclude")
    assert list(m.excluded["row"]) == [8] and len(m) == 199


def test_duplicate_rows(small):
    bad = pd.concat([small, small.iloc[[10, 11]]], ignore_index=True)
    with pytest.raises(DataError, match=r"duplicate.*data row\(s\) 201, 202"):
        load_measurements(bad)
    assert len(load_measurements(bad, on_invalid="exclude")) == 200


def test_text_in_numeric_column(small):
    bad = small.astype({"mdot_mg_s": object})
    bad.loc[2, "mdot_mg_s"] = "12,5"
    with pytest.raises(DataError, match=r"mdot_mg_s holds text.*row\(s\) 3"):
        load_measurements(bad)


def test_several_valves_need_a_choice(small):
    two = small.copy()
    two["valve"] = ["A"] * 100 + ["B"] * 100
    with pytest.raises(DataError, match="2 valves"):
        load_measurements(two)
    assert len(load_measurements(two, valve="B")) == 100


def test_unit_suffixed_columns_are_read_in_their_unit(tmp_path, small):
    raw = small.rename(columns={"p_in_kPa": "p_in_bar", "p_out_kPa": "p_out_kpa",
                                "mdot_mg_s": "mdot_g_s"})
    raw["p_in_bar"] = raw["p_in_bar"] / 100.0
    raw["mdot_g_s"] = raw["mdot_g_s"] / 1000.0
    m = load_measurements(write(tmp_path, raw))
    np.testing.assert_allclose(m.frame[CANON].to_numpy(), small[CANON].to_numpy(), rtol=1e-12)
    assert "column p_in_bar read as p_in_kPa (unit bar)" in m.notes
    assert "column p_out_kpa read as p_out_kPa (unit kPa)" in m.notes


def test_rows_in_reverse_time_order_are_reversed_with_a_notice(small):
    m = load_measurements(small.iloc[::-1])
    np.testing.assert_array_equal(m.frame["time_s"], small["time_s"])
    assert list(m.frame["row"][:2]) == [200, 199]  # still the rows of the source
    assert any("reverse time order" in n for n in m.notes)


def test_a_file_over_max_rows_is_thinned_evenly_with_a_notice(tmp_path, small):
    m = load_measurements(write(tmp_path, small), max_rows=60)
    assert list(m.frame["row"][:3]) == [1, 5, 9] and len(m) == 50  # every 4th row
    assert "holds 200 data rows, more than the limit of 60: every 4th row" in m.notes[0]
    np.testing.assert_allclose(m.frame["p_in_kPa"], small["p_in_kPa"][::4])
