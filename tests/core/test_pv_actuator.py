"""The data-driven pressure–volume actuator (issue 12): a bellows' measured (p, V) points
read from CSV, filled through a resistor, against an integration of the stored mass
dm/dt = ṁ with m = ρ(p)·V(p) written here (p found from m at each step), and bad tables
named by file, line and element."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator
from scipy.optimize import brentq

from pneunet.common.errors import PneunetError
from pneunet.physics.gas import AIR, GAS_CONSTANT
from pneunet.netlist import parse_file

AMBIENT, SUPPLY, R, T = 100.0, 400.0, 1.0, 293.15   # kPa, kPa, kPa·s/mg, K
RHO_PER_P = AIR.molar_mass_g_mol / (GAS_CONSTANT * T)  # mg/mL per kPa
#: a bellows: unfolds at low pressure, stiffens as it reaches full stroke (kPa gauge, mL)
BELLOWS_KPAG = np.array([0, 10, 20, 40, 60, 100, 150, 200, 300, 400.0])
BELLOWS_ML = np.array([30, 45, 58, 74, 83, 91, 95, 97.5, 99.5, 100.5])


def _netlist(tmp_path, kind="free_actuator"):
    (tmp_path / "bellows.csv").write_text("p_kPag,V_mL\n" + "".join(
        f"{p:g},{v:g}\n" for p, v in zip(BELLOWS_KPAG, BELLOWS_ML)))
    (tmp_path / "fill.pn").write_text(
        f".options ambient={AMBIENT}kPa rtol=1e-8 atol=1e-8\nP1 s {SUPPLY}kPa\nR1 s b {R}\n"
        f"{kind} A1 b table=bellows.csv\n.tran 10ms 3s\n")
    return tmp_path / "fill.pn"


def reference_fill(times):
    """Pressure (kPa) in the bellows: the stored mass m (mg) integrated, ṁ = √(p_s² − p²)/R,
    and p the root of ρ(p)·V(p) = m (V: the monotone cubic through the points)."""
    volume = PchipInterpolator(BELLOWS_KPAG + AMBIENT, BELLOWS_ML)

    def pressure(m):
        return brentq(lambda p: RHO_PER_P * p * volume(p) - m, AMBIENT, AMBIENT + 400.0,
                      xtol=1e-13)

    def rate(t, m):
        return [np.sqrt(max(SUPPLY ** 2 - pressure(m[0]) ** 2, 0.0)) / R]

    m0 = RHO_PER_P * AMBIENT * volume(AMBIENT)
    out = solve_ivp(rate, (0.0, times[-1]), [m0], t_eval=times, rtol=1e-10, atol=1e-8)
    return np.array([pressure(m) for m in out.y[0]])


@pytest.mark.parametrize("kind", ["free_actuator", "pv_actuator", "pv_volume"])
def test_bellows_from_csv_fills_as_its_stored_mass_says(tmp_path, kind):
    deck = parse_file(_netlist(tmp_path, kind))
    assert deck.circuit.elements["A1"].kind == "pv_volume"
    sol = deck.circuit.tran(3.0, t_step=0.01)
    early = sol.pressure("b") < SUPPLY - 10.0  # away from the zero-flow band
    assert early.sum() > 20
    np.testing.assert_allclose(sol.pressure("b")[early], reference_fill(sol.t[early]),
                               rtol=1e-5)
    volume = PchipInterpolator(BELLOWS_KPAG + AMBIENT, BELLOWS_ML)
    np.testing.assert_allclose(sol.signals["volume_A1"], volume(sol.pressure("b")), rtol=1e-9)
    # it takes in the air of its growing volume: at the supply, (400·99.5 − 100·30)/(300·30)
    # = 4.09 × what a rigid tank of its relaxed volume would
    stored = RHO_PER_P * (sol.pressure("b")[-1] * sol.signals["volume_A1"][-1]
                          - AMBIENT * BELLOWS_ML[0])
    rigid = RHO_PER_P * (sol.pressure("b")[-1] - AMBIENT) * BELLOWS_ML[0]
    assert stored / rigid == pytest.approx(4.09, abs=0.02)


@pytest.mark.parametrize("text, message", [
    ("p,V_mL\n100,20\n200,30\n", r"bellows.csv: column p names no unit"),
    ("p_kPa,V_mL,x\n100,20,1\n200,30,1\n", r"bellows.csv: a table has two columns, found 3"),
    ("p_kPa,V_mL\n100,20\n200,abc\n", r"bellows.csv:3:5: column V_mL \(field 2\): 'abc' is not a number"),
    ("p_kPa,V_mL\n100,20\n", r"bellows.csv: a table needs at least two rows"),
    ("p_kPa,V_s\n100,20\n200,30\n", r"column V_s: .*a volume column in mL"),
    ("p_kPa,V_mL\n100,20\n200,nan\n", r"bellows.csv:3: column V_mL is not a finite number"),
    ("p_kPa,V_mL\n100,20\n90,19\n", r"bellows.csv:3: column p_kPa must increase from row to row \(or, for "
                                     r"a curve whose p_kPa is not monotone, column V_mL\)"),
    ("p_kPag,V_mL\n0,20\n100,30\n200,25\n", r"fill.pn:4:.*A1: .*volumes must not decrease"
                                             r".*point 3 \(25 mL at 300 kPa\)"),
])
def test_bad_csv_names_the_file_line_and_element(tmp_path, text, message):
    path = _netlist(tmp_path)
    (tmp_path / "bellows.csv").write_text(text)
    with pytest.raises(PneunetError, match=message) as err:
        parse_file(path)
    assert "fill.pn:4" in str(err.value) and "A1" in str(err.value)
