"""Signals of a simulated circuit: element flows computed on first read, exactly the flow laws."""
import numpy as np
import pytest

from pneunet import Circuit
from pneunet.physics.laws import quadrature_flow
from pneunet.engine.solution import LazySignals
from pneunet.physics.waveforms import Pulse


@pytest.fixture(scope="module")
def chain():
    """Pulsed source → R1 → volume → R2 → atm: every signal has a closed form."""
    c = Circuit("chain")
    c.pressure_source("PS", "src", Pulse(101.325, 300.0, delay=0.1, rise=0.05, fall=0.05,
                                         width=0.3, period=1.0))
    c.resistor("R1", "src", "tank", R=2.0)
    c.volume("V1", "tank", V="20mL")
    c.resistor("R2", "tank", "atm", R=4.0)
    return c.tran(2.0)


def test_element_flows_are_computed_when_first_read(chain):
    signals = chain.signals
    assert isinstance(signals, LazySignals)
    assert "mdot_R1" in signals and "mdot_R1" in list(signals)
    assert chain.units["mdot_R1"] == "mg/s"
    src, tank = chain.pressure("src"), chain.pressure("tank")
    expected, _, _ = quadrature_flow(src, tank, 2.0, band=10.0)
    np.testing.assert_allclose(chain.flow("R1"), expected, rtol=1e-12)
    with pytest.raises(ValueError):
        chain.flow("R1")[0] = 0.0


def test_source_flow_is_the_flow_into_the_element_it_drives(chain):
    np.testing.assert_allclose(chain.flow("PS"), chain.flow("R1"), rtol=1e-12, atol=1e-12)


def test_every_listed_signal_can_be_read_and_exported(chain):
    frame = chain.to_pandas()
    assert len(frame.columns) == len(chain.signals) + 1
    assert {"p_src_kPa", "p_tank_kPa", "mdot_PS_mg_s", "mdot_R1_mg_s", "mdot_R2_mg_s"} <= set(frame.columns)
    assert not frame.isna().any().any()
    final = chain.final()
    assert final["mdot_R2"] == pytest.approx(float(quadrature_flow(
        chain.pressure("tank")[-1], 101.325, 4.0, band=10.0)[0]), rel=1e-12)
