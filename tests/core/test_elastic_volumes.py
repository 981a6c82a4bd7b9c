"""Elastic volumes: an accumulator filled through a resistor against scipy's solve_ivp of
C(p)·ṗ = √(p_s² − p²)/R with C = (M/(R·T))·(V + p·dV/dp) written out here (issue 14)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pneunet import Circuit, ParameterError
from pneunet.common.errors import PneunetError
from pneunet.physics.gas import AIR, GAS_CONSTANT
from pneunet.netlist import parse_file

AMBIENT, SUPPLY, R, V0, K, PREF, T = 100.0, 300.0, 2.0, 20.0, 0.08, 100.0, 293.15
RHO_PER_P = AIR.molar_mass_g_mol / (GAS_CONSTANT * T)  # kg/m³ per kPa = mg/mL per kPa


def reference_fill(times, volume_and_slope):
    """Pressure (kPa) of a volume V(p) filled from ambient through R, isothermal gas."""
    def rate(t, p):
        v, dv = volume_and_slope(p[0])
        return [np.sqrt(max(SUPPLY ** 2 - p[0] ** 2, 0.0)) / R / (RHO_PER_P * (v + p[0] * dv))]

    out = solve_ivp(rate, (0.0, times[-1]), [AMBIENT], t_eval=times, rtol=1e-11, atol=1e-11,
                    method="LSODA")
    return out.y[0]


def _fill(add_volume):
    c = Circuit("fill", ambient=AMBIENT, temperature=T, rtol=1e-8, atol=1e-8)
    c.pressure_source("P1", "s", SUPPLY)
    c.resistor("R1", "s", "b", R=R)
    add_volume(c)
    return c.tran(1.5, t_step=0.01)


def _compare(sol, volume_and_slope):
    early = sol.pressure("b") < SUPPLY - 10.0  # away from the zero-flow band
    assert early.sum() > 20
    ref = reference_fill(sol.t[early], volume_and_slope)
    np.testing.assert_allclose(sol.pressure("b")[early], ref, rtol=1e-5)


def test_accumulator_fill_matches_the_integrated_capacitance():
    sol = _fill(lambda c: c.accumulator("A1", "b", V0=V0, k=K, pref=PREF))
    _compare(sol, lambda p: (V0 + K * (p - PREF), K))
    np.testing.assert_allclose(sol.signals["volume_A1"], V0 + K * (sol.pressure("b") - PREF))
    # the compliance matters: the same volume held rigid fills visibly faster
    rigid = reference_fill(sol.t[1:30], lambda p: (V0 + K * (p - PREF), 0.0))
    assert np.max(np.abs(rigid - sol.pressure("b")[1:30])) > 1.0


def test_table_volume_from_csv_follows_its_monotone_cubic(tmp_path):
    """A table in bar gauge and litres, read from CSV, interpolated by PCHIP (scipy) and
    continued linearly with its end slope below the first point."""
    from scipy.interpolate import PchipInterpolator

    p_g = np.array([0.2, 0.5, 1.0, 1.5, 2.5])  # bar gauge
    v_l = np.array([0.021, 0.024, 0.032, 0.034, 0.035])
    (tmp_path / "curve.csv").write_text("p_barg,V_L\n" + "".join(
        f"{a},{b}\n" for a, b in zip(p_g, v_l)))
    curve = PchipInterpolator(p_g * 100 + AMBIENT, v_l * 1e3)
    lo = p_g[0] * 100 + AMBIENT

    def volume_and_slope(p):
        if p < lo:
            return float(curve(lo) + curve(lo, 1) * (p - lo)), float(curve(lo, 1))
        return float(curve(p)), float(curve(p, 1))

    sol = _fill(lambda c: c.pv_volume("A1", "b", table=tmp_path / "curve.csv"))
    _compare(sol, volume_and_slope)
    (tmp_path / "fill.pn").write_text("P1 s 300kPa\nR1 s b 2\npv_volume A1 b table=curve.csv\n"
                                      ".options ambient=100kPa\n.tran 1.5\n")
    deck = parse_file(tmp_path / "fill.pn")
    assert deck.circuit.elements["A1"].params["table"][1] == pytest.approx(v_l * 1e3)


def test_bad_tables_and_compliance_are_named_errors(tmp_path):
    with pytest.raises(ParameterError, match="A2.*must not decrease"):
        Circuit().pv_volume("A2", "b", table=([100, 200], [30, 20]))
    with pytest.raises(ParameterError, match="A3.*k=-0.1 mL/kPa is outside its valid range"):
        Circuit().accumulator("A3", "b", V0=10, k=-0.1)
    c = Circuit(ambient=100.0)
    c.accumulator("A5", "b", V0=1.0, k=0.1, pref=200.0)
    c.resistor("R1", "b", "atm", R=1.0)
    with pytest.raises(ParameterError, match="A5.*is -9 mL at the initial pressure 100 kPa"):
        c.tran(1.0)
    (tmp_path / "c.csv").write_text("p_kPa,V_mL\n100,20\n90,19\n")  # neither increases
    (tmp_path / "n.pn").write_text("pv_volume A4 b table=c.csv\nR1 b atm 1\n")
    with pytest.raises(PneunetError, match=r"n.pn:1.*A4: table: .*c.csv:3: column p_kPa must "
                                           r"increase"):
        parse_file(tmp_path / "n.pn")
    (tmp_path / "n.pn").write_text("pv_volume A4 b table=../c.csv\nR1 b atm 1\n")
    with pytest.raises(PneunetError, match="outside the allowed folders"):
        parse_file(tmp_path / "n.pn")


def test_inline_table_and_printed_netlist_parse_back():
    from pneunet.netlist import parse_netlist, print_circuit

    text = ("P1 s 3bar\nD1 s b 0.5 pcrack=20kPa\naccumulator A1 b 20mL 10mL/bar\n"
            "pv_volume A2 b table=TABLE(1bar 20mL 2bar 0.03L 3bar 35mL)\n")
    circuit = parse_netlist(text).circuit
    assert circuit.elements["A1"].params["k"] == pytest.approx(0.1)
    np.testing.assert_allclose(circuit.elements["A2"].params["table"], [[100, 200, 300],
                                                                         [20, 30, 35]])
    again = parse_netlist(print_circuit(circuit)).circuit
    for name, spec in circuit.elements.items():
        for key, value in spec.params.items():
            np.testing.assert_array_equal(again.elements[name].params[key], value)
