import pytest

#: the paper's oscillator with a short transient (a design test simulates it ~30 times)
SHORT_OSCILLATOR = """\
* oscillator, short transient for design tests
.options ambient=96kPa
.param Rout=1.132 Rvent=3
PH supply 496kPa
X1 supply out tank axi_0p6mm
Rout out tank {Rout}kPa*s/mg
Vtank tank 100mL
Rvent tank atm {Rvent}kPa*s/mg
.tran 10ms 14s
.meas tran period PERIOD p(tank) FROM=7s
.meas tran swing PP p(tank) FROM=7s
"""


@pytest.fixture
def short_oscillator(tmp_path):
    path = tmp_path / "osc.pn"
    path.write_text(SHORT_OSCILLATOR)
    return path
