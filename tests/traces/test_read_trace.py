"""read_trace: columns in other units converted with a notice (never dropped), a record
starting late shifted to 0 with a notice, unknown columns refused, thinning."""
import numpy as np
import pytest

from pneunet.common.errors import DataError
from pneunet.truth.circuits import read_trace

from .standalone import oscillator_record


@pytest.fixture(scope="module")
def record():
    return oscillator_record(4.0, noise=0.4, seed=3)


def test_pressure_in_bar_and_lower_case_kpa_are_converted_not_dropped(tmp_path, record):
    raw = record.rename(columns={"p_tank_kPa": "p_tank_bar", "p_out_kPa": "p_out_kpa"})
    raw["p_tank_bar"] = raw["p_tank_bar"] / 100.0
    path = tmp_path / "rec.csv"
    raw.to_csv(path, index=False)
    df = read_trace(path)
    assert list(df.columns) == ["time_s", "p_tank_kPa", "p_out_kPa"]
    np.testing.assert_allclose(df["p_tank_kPa"], record["p_tank_kPa"], rtol=1e-12)
    assert "column p_tank_bar read as p_tank_kPa (unit bar)" in df.attrs["notes"]


def test_gauge_columns_need_the_barometric_pressure_and_are_made_absolute_with_it(
        tmp_path, record):
    """A logger's gauge readings in kPa and psi: refused without the barometric
    pressure (a located error naming --ambient), absolute with it."""
    raw = record.rename(columns={"p_tank_kPa": "p_tank_kPag", "p_out_kPa": "p_out_psig"})
    raw["p_tank_kPag"] = raw["p_tank_kPag"] - 101.2
    raw["p_out_psig"] = (raw["p_out_psig"] - 101.2) / 6.894757293168361
    path = tmp_path / "rec.csv"
    raw.to_csv(path, index=False)
    with pytest.raises(DataError, match="gauge") as err:
        read_trace(path)
    assert "--ambient" in err.value.hint and "rec.csv" in str(err.value)
    df = read_trace(path, ambient_kpa=101.2)
    np.testing.assert_allclose(df["p_tank_kPa"], record["p_tank_kPa"], rtol=1e-12)
    np.testing.assert_allclose(df["p_out_kPa"], record["p_out_kPa"], rtol=1e-12)
    assert any("p_out_psig made absolute with the barometric pressure 101.2 kPa" in n
               for n in df.attrs["notes"])


def test_a_record_starting_at_1000_s_is_shifted_to_0(tmp_path, record):
    path = tmp_path / "rec.csv"
    record.assign(time_s=record.time_s + 1000.0).to_csv(path, index=False)
    df = read_trace(path)
    np.testing.assert_allclose(df["time_s"], record["time_s"], atol=1e-9)
    assert "time_s starts at 1000 s: counted from the first sample" in df.attrs["notes"][0]
    assert df.attrs["time_origin"] == pytest.approx(1000.0)  # a driven circuit's clock
    # read again (a frame already read): the clock is kept, not shifted twice
    assert read_trace(df).attrs["time_origin"] == pytest.approx(1000.0)


def test_unknown_columns_are_refused_unless_signals_are_chosen(tmp_path, record):
    path = tmp_path / "rec.csv"
    record.assign(comment="x").to_csv(path, index=False)
    with pytest.raises(DataError, match="column comment is not a signal") as err:
        read_trace(path)
    assert err.value.where == str(path)
    assert list(read_trace(path, ["p_tank_kPa"]).columns) == ["time_s", "p_tank_kPa"]


def test_a_long_record_is_thinned_with_a_notice(tmp_path, record):
    path = tmp_path / "rec.csv"
    record.to_csv(path, index=False)
    df = read_trace(path, max_rows=30)
    assert len(df) == (len(record) + 3) // 4
    np.testing.assert_allclose(df["p_tank_kPa"], record["p_tank_kPa"][::4])
    assert "every 4th row is used" in df.attrs["notes"][0]
