"""A pressure–volume table whose pressure is not monotone (issue 34): a balloon whose
pressure rises to a peak, falls and rises again, so that under one supply pressure it has
two stable volumes. The table here has the shape of a 60 mm latex balloon (peak 87 kPa
gauge at 6 mL, valley 58 kPa at 22 mL); the references are written here: the roots of
p(V) = p_s on its rising branches, and the stored mass m = ρ1·p·V integrated by scipy with
V as the state (dV/dt = ṁ/(ρ1·(P + V·P'))), P the monotone cubic through the points."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

from pneunet import Circuit, ParameterError
from pneunet.common.errors import NetlistError
from pneunet.physics.gas import AIR, GAS_CONSTANT
from pneunet.netlist import parse_netlist
from pneunet.physics.waveforms import PiecewiseLinear

AMB, T, R = 101.325, 293.15, 0.5  # kPa, K, kPa·s/mg
RHO1 = AIR.molar_mass_g_mol / (GAS_CONSTANT * T)  # mg/(mL·kPa)
V = np.array([1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30, 32, 34, 36,
              38, 40.0])  # mL
P_G = np.array([2, 28, 55, 74, 85, 87, 83, 77.5, 70, 66, 62.7, 60.5, 59, 58.5, 58, 58.3, 59.2,
                60.2, 61.5, 63.2, 65.5, 68, 71, 74.5])  # kPa gauge
#: the supply: 65 kPa gauge, a pulse to 89 kPa (above the 87 kPa peak) from 3 to 4.2 s
TIMES = [0.0, 0.5, 3.0, 3.2, 4.0, 4.2, 8.0]
LEVELS = [AMB, AMB + 65, AMB + 65, AMB + 89, AMB + 89, AMB + 65, AMB + 65]


def _balloon(**options):
    c = Circuit("balloon", ambient=AMB, **options)
    c.pressure_source("P1", "s", PiecewiseLinear(TIMES, LEVELS))
    c.resistor("R1", "s", "b", R=R)
    c.pv_volume("B1", "b", table=(P_G + AMB, V))
    return c


def test_the_balloon_rests_on_either_rising_branch():
    """Before the pulse it sits on the first rising branch, after it on the last: the
    smallest and the largest root of P(V) = 65 kPa gauge."""
    sol = _balloon(rtol=1e-8, atol=1e-8).tran(8.0, t_step=0.01)
    roots = PchipInterpolator(V, P_G).solve(65.0, extrapolate=False)
    assert roots.size == 3 and roots[0] < 6 < 22 < roots[2]  # rising, falling, rising
    volume = sol.signals["volume_B1"]
    assert volume[sol.t.searchsorted(2.9)] == pytest.approx(roots[0], rel=1e-6)
    assert volume[-1] == pytest.approx(roots[2], rel=1e-6)
    assert sol.pressure("b")[-1] - AMB == pytest.approx(65.0, abs=1e-6)


@pytest.mark.filterwarnings("ignore:divide by zero:RuntimeWarning")  # scipy's Radau at rest
def test_snap_through_follows_the_stored_mass():
    """The whole run against scipy's integration of the stored mass with V as the state;
    the flow √(p_s² − p²)/R regularised as pneunet documents, d/(d² + ε²)^¼ with the band
    ε = 1e-3 kPa² (the exact root's infinite slope at rest stalls the integrator)."""
    sol = _balloon(rtol=1e-8, atol=1e-8, flow_band=1e-3).tran(8.0, t_step=0.01)
    pchip = PchipInterpolator(V, P_G + AMB)
    end_slopes = pchip.derivative()(V[[0, -1]])

    def curve(v):  # the monotone cubic, continued linearly with its end slopes (documented)
        v = np.asarray(v, dtype=float)
        inside = np.clip(v, V[0], V[-1])
        return pchip(inside) + np.where(v < V[0], end_slopes[0], end_slopes[1]) * (v - inside)

    def slope(v):
        return pchip.derivative()(np.clip(v, V[0], V[-1]))

    def rate(t, y):
        p_s, p = np.interp(t, TIMES, LEVELS), curve(y[0])
        d = p_s * p_s - p * p
        mdot = d / (d * d + 1e-6) ** 0.25 / R
        return [mdot / (RHO1 * (p + y[0] * slope(y[0])))]

    start = V[0] - P_G[0] / end_slopes[0]  # at ambient: below the table, on its end slope
    ref = solve_ivp(rate, (0.0, 8.0), [start], method="Radau", rtol=1e-8, atol=1e-8,
                    max_step=0.02, dense_output=True)
    volume = ref.sol(sol.t)[0]
    assert np.max(np.abs(sol.signals["volume_B1"] - volume)) < 3e-4  # mL, of a 34 mL swing
    assert np.max(np.abs(sol.pressure("b") - curve(volume))) < 1e-3  # kPa


def test_volume_is_saved_and_measured_from_a_netlist():
    points = " ".join(f"{p:g}kPag {v:g}mL" for p, v in zip(P_G, V))
    deck = parse_netlist(
        f".options ambient={AMB}kPa\nP1 s PWL(0 {AMB}kPa 0.5 166.325kPa)\nR1 s b {R}\n"
        f"free_actuator B1 b table=TABLE({points})\n.tran 10ms 3s\n.save volume(B1) p(b)\n"
        ".meas tran vrest FIND volume(B1) AT=2.9s\n")
    from pneunet.netlist.runner import run_deck

    result = run_deck(deck)
    roots = PchipInterpolator(V, P_G).solve(65.0, extrapolate=False)
    assert result.measures["vrest"] == pytest.approx(roots[0], rel=1e-4)


def test_bad_balloon_tables_and_starts_are_named():
    with pytest.raises(NetlistError, match=r"<netlist>:3:.*B1.*pressures or volumes must "
                                           r"increase.*point 3"):
        parse_netlist("P1 s 1bar\nR1 s b 1\n"
                      "pv_volume B1 b table=TABLE(150kPa 1mL 140kPa 3mL 145kPa 2mL)\n")
    with pytest.raises(ParameterError, match="never reaches p0 = 300 kPa"):
        c = Circuit("b", ambient=AMB)
        c.pressure_source("P1", "s", 200.0)
        c.resistor("R1", "s", "b", R=1.0)
        c.pv_volume("B1", "b", table=(P_G + AMB, V), p0=300.0)
        c.tran(1.0)
    with pytest.raises(ParameterError, match="V0 chooses the branch"):
        Circuit("b").pv_volume("B1", "b", table=([100.0, 200.0], [1.0, 2.0]), V0=1.5)


def test_v0_starts_the_balloon_on_its_far_branch():
    c = _balloon()
    c.elements.pop("B1")
    c.pv_volume("B1", "b", table=(P_G + AMB, V), V0=36.0)
    c.elements["P1"].params["value"] = PiecewiseLinear([0.0, 1.0], [AMB + 68.0, AMB + 65.0])
    sol = c.tran(3.0)
    roots = PchipInterpolator(V, P_G).solve(65.0, extrapolate=False)
    assert sol.signals["volume_B1"][0] == pytest.approx(36.0, abs=1e-9)
    assert sol.signals["volume_B1"][-1] == pytest.approx(roots[2], rel=1e-4)


def test_balloon_from_a_csv_file(tmp_path):
    """A CSV whose pressures are not monotone but whose volumes increase is a p(V) curve."""
    from pneunet.netlist import parse_file

    (tmp_path / "balloon.csv").write_text("p_kPag,V_mL\n" + "".join(
        f"{p:g},{v:g}\n" for p, v in zip(P_G, V)))
    (tmp_path / "b.pn").write_text(f".options ambient={AMB}kPa\nP1 s 160kPa\nR1 s b {R}\n"
                                   "free_actuator B1 b table=balloon.csv\n")
    circuit = parse_file(tmp_path / "b.pn").circuit
    assert circuit.elements["B1"].kind == "pv_volume_state"
    p, v = circuit.elements["B1"].params["table"]
    np.testing.assert_allclose(p, P_G + AMB) and np.testing.assert_allclose(v, V)


def test_printed_balloon_parses_back_to_the_same_run():
    from pneunet.netlist import print_circuit

    c = _balloon()
    again = parse_netlist(print_circuit(c)).circuit
    assert again.elements["B1"].kind == "pv_volume_state"
    first, second = c.tran(5.0, t_step=0.05), again.tran(5.0, t_step=0.05)
    np.testing.assert_allclose(second.signals["volume_B1"], first.signals["volume_B1"],
                               rtol=1e-9)


def test_operating_point_reports_the_balloons_own_mode():
    """At rest on the first branch, the slowest mode is the fill through R1: λ = −G/C with
    G = dṁ/dp of the regularised root at zero flow, 2p/(R·√ε), and C = ρ1·(V + p/P'(V))."""
    c = _balloon()
    op = c.op(t=2.9)
    p = AMB + 65.0
    v = PchipInterpolator(V, P_G).solve(65.0, extrapolate=False)[0]
    slope = PchipInterpolator(V, P_G).derivative()(v)
    rate = -(2 * p / (R * np.sqrt(10.0))) / (RHO1 * (v + p / slope))
    assert op.pressures["b"] == pytest.approx(p, abs=1e-6)
    assert op.stability.slowest.real == pytest.approx(rate, rel=1e-3)
