"""The user's own fluids (issue 34): ``.fluid`` cards and Gas/Liquid objects, checked against
Hagen–Poiseuille, the stored mass of a volume (ρV/K for a liquid, MV/(RT) for a gas) and
Sutherland's law, all written here; bad cards are located errors (exit code 2)."""
import math
import subprocess
import sys

import numpy as np
import pytest

from pneunet import Circuit, Gas, Liquid, ParameterError
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_netlist, print_circuit
from pneunet.physics.waveforms import Step

GLYCERIN = ".fluid glycerol rho=1260kg/m3 mu=1.41Pa*s K=4.35GPa\n"
R_GAS = 8.314462618  # J/(mol·K)


def test_user_liquid_tube_is_hagen_poiseuille():
    deck = parse_netlist(GLYCERIN + ".options fluid=glycerol ambient=100kPa\nP1 a 300kPa\n"
                         "tube T1 a atm length=1m diameter=4mm\n"
                         "laminar_tube T2 a atm length=1m diameter=4mm\n.op\n")
    flows = deck.circuit.op(stability=False).flows
    rho, mu, d, length, dp = 1260.0, 1.41, 4e-3, 1.0, 200e3
    expected = rho * math.pi * d ** 4 * dp / (128 * mu * length) * 1e6  # mg/s
    assert 4 * expected * 1e-6 / (math.pi * d * mu) < 1  # Re ≪ 1: creeping flow
    assert flows["T2"] == pytest.approx(expected, rel=1e-9)
    assert flows["T1.s1"] == pytest.approx(expected, rel=1e-6)


def test_user_liquid_volume_stores_rho_v_over_k():
    oil = Liquid("my_oil", density=870.0, viscosity=0.046, bulk_modulus=1.7e6)
    c = Circuit("closed", ambient=100.0, fluid=oil, rtol=1e-8, atol=1e-8)
    c.flow_source("F1", "atm", "a", Step(2.0, 0.0, at=1.0))  # 2 mg in all
    c.volume("V1", "a", V=50.0)
    rise = c.tran(2.0, t_step=0.01).pressure("a")[-1] - 100.0
    assert rise == pytest.approx(2.0 * 1.7e6 / (870.0 * 50.0), rel=1e-6)


def test_user_gas_stores_its_molar_mass_and_flows_by_sutherland():
    helium = Gas("helium", 4.0026, mu0=1.87e-5, t0=273.15, sutherland=79.4)
    c = Circuit("helium", ambient=100.0, gas=helium, rtol=1e-8, atol=1e-8)
    c.flow_source("F1", "atm", "a", Step(1.0, 0.0, at=1.0))  # 1 mg
    c.volume("V1", "a", V=100.0)
    rise = c.tran(2.0, t_step=0.01).pressure("a")[-1] - 100.0
    t = 293.15
    assert rise == pytest.approx(1e-6 * R_GAS * t / (4.0026e-3 * 100e-6) / 1e3, rel=1e-6)
    # laminar line: ṁ = π·D⁴·(p_a² − p_b²)/(256·μ·R_s·T·L), μ by Sutherland at 20 °C
    c = Circuit("line", ambient=100.0, gas=helium)
    c.pressure_source("P1", "a", 100.5)
    c.tube("T1", "a", "atm", length=2000.0, diameter=0.5)
    mu = 1.87e-5 * (t / 273.15) ** 1.5 * (273.15 + 79.4) / (t + 79.4)
    expected = (math.pi * 0.5e-3 ** 4 * (100.5e3 ** 2 - 100e3 ** 2)
                / (256 * mu * R_GAS / 4.0026e-3 * t * 2.0)) * 1e6
    assert c.op(stability=False).flows["T1.s1"] == pytest.approx(expected, rel=2e-3)


def test_fluid_cards_print_and_parse_back():
    text = (GLYCERIN + ".options fluid=glycerol ambient=100kPa\nP1 a 300kPa\n"
            "tube T1 a atm length=1m diameter=4mm segments=2\n")
    circuit = parse_netlist(text).circuit
    again = parse_netlist(print_circuit(circuit)).circuit
    assert again.options == circuit.options
    gas = parse_netlist(".fluid he M=4.0026g/mol mu=1.87e-5Pa*s S=79.4K\n.options gas=he\n"
                        "P1 a 300kPa\nV1 a 1mL\nR1 a atm 1\n").circuit
    assert gas.options.gas_model == Gas("he", 4.0026, 1.87e-5, 273.15, 79.4)
    assert parse_netlist(print_circuit(gas)).circuit.options == gas.options


@pytest.mark.parametrize("card, where, message", [
    (".fluid glycerol rho=1260kg/m3 mu=1.41Pa*s", ":1:1:", "a liquid needs K"),
    (".fluid glycerol rho=1260kg/m3 mu=1.41Pa*s K=4GPa cp=2", ":1:", "unknown key 'cp'"),
    (".fluid glycerol rho=1260kPa mu=1.41Pa*s K=4GPa", ":1:", "rho needs kg/m^3"),
    (".fluid glycerol rho=-1 mu=1.41Pa*s K=4GPa", ":1:8:", "rho must be a finite number > 0"),
    (".fluid water rho=999 mu=1mPa*s K=2GPa", ":1:8:", "fluid 'water' is built in"),
    (".fluid he S=79K M=4g/mol", ":1:8:", "Sutherland's S needs the viscosity"),
    (".fluid", ":1:1:", ".fluid needs a name"),
])
def test_bad_fluid_card_is_located(card, where, message):
    with pytest.raises(NetlistError) as err:
        parse_netlist(card + "\nP1 a 300kPa\nR1 a atm 1\n")
    assert f"<netlist>{where}" in str(err.value) and message in str(err.value)


def test_unknown_fluid_names_the_way_to_define_one(tmp_path):
    bad = tmp_path / "bad.pn"
    bad.write_text(GLYCERIN + ".options fluid=glycerin\nP1 a 300kPa\n"
                   "orifice O1 a atm 1mm\n")
    run = subprocess.run([sys.executable, "-m", "pneunet", "check", str(bad)],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert "bad.pn:2:" in run.stderr and "unknown fluid 'glycerin'" in run.stderr
    assert "glycerol" in run.stderr and "Traceback" not in run.stderr
    with pytest.raises(NetlistError, match="defined twice"):
        parse_netlist(GLYCERIN * 2 + "P1 a 300kPa\nR1 a atm 1\n")
    with pytest.raises(NetlistError, match="not allowed inside .subckt"):
        parse_netlist(".subckt s a\n" + GLYCERIN + "R1 a atm 1\n.ends\nP1 a 1bar\nX1 a s\n")
    with pytest.raises(ParameterError, match="fluid 'water' is built in"):
        Circuit(fluid=Liquid("water", 999.0, 1e-3, 2.2e6))
    with pytest.raises(ParameterError, match="viscosity must be|mu must be"):
        Liquid("thin", 999.0, 0.0, 2.2e6)


def test_a_user_gas_gives_the_thermal_volumes_its_gamma():
    """Helium (γ = 5/3) from a .fluid card: a thermal volume without gamma= takes the gas's;
    the same run with gamma=1.667 given agrees, and air's 1.4 differs."""
    def run(gamma, gas=".fluid he M=4.0026g/mol gamma=1.6666\n.options gas=he\n"):
        text = (gas + "P1 s PWL(0 100kPa 0.1s 300kPa)\nR1 s b 0.02\n"
                f"thermal_volume VT1 b bT V=50mL tau=2s {gamma}\n")
        return parse_netlist(text).circuit.tran(0.5, t_step=0.01).pressure("bT")

    default, given = run(""), run("gamma=1.6666")
    np.testing.assert_allclose(default, given, rtol=1e-9)
    assert np.max(np.abs(default - run("gamma=1.4"))) > 1.0  # kPa: γ matters here
    with pytest.raises(NetlistError, match=r"<netlist>:1:8:.*gamma = c_p/c_v must lie in"):
        parse_netlist(".fluid he M=4g/mol gamma=2\nP1 a 1bar\nR1 a atm 1\n")
