"""Circuits that cannot be simulated, and bad values, give errors that name the culprit."""
import numpy as np
import pytest

from pneunet import Circuit, ParameterError, SolverError, TopologyError
from pneunet.design.paper_circuits import oscillator


def test_duplicate_element_name():
    c = Circuit()
    c.resistor("R1", "a", "atm", R=1)
    with pytest.raises(TopologyError, match="duplicate element name 'R1'"):
        c.resistor("R1", "a", "b", R=1)


def test_wrong_node_count_names_the_ports():
    with pytest.raises(TopologyError, match=r"valve needs 3 node\(s\) \(in out ctrl\)"):
        Circuit().add("valve", "X1", ("a", "b"), model="axi")


def test_no_defined_pressure():
    c = Circuit()
    c.resistor("R1", "a", "b", R=1)
    c.volume("V1", "a", V=10)
    with pytest.raises(TopologyError, match="no node has a defined pressure"):
        c.validate()


def test_floating_control_node_is_named():
    c = Circuit()
    c.pressure_source("P1", "s", 300)
    c.valve("X1", "s", "atm", "ctl", model="axi")
    with pytest.raises(TopologyError, match="node 'ctl' is floating.*X1"):
        c.validate()


def test_nodes_without_path_to_a_pressure_are_listed():
    c = Circuit()
    c.pressure_source("P1", "s", 300)
    c.resistor("R1", "s", "atm", R=1)
    c.resistor("R2", "x", "y", R=1)
    with pytest.raises(TopologyError, match="nodes x, y have no path to a defined pressure"):
        c.validate()


def test_two_sources_on_one_node():
    c = Circuit()
    c.pressure_source("P1", "s", 300)
    c.pressure_source("P2", "s", 200)
    c.resistor("R1", "s", "atm", R=1)
    with pytest.raises(TopologyError, match="pressure set twice"):
        c.validate()


def test_initial_condition_on_unknown_node_suggests_a_name():
    c = oscillator()
    c.set_initial("tnak", 200)
    with pytest.raises(TopologyError, match="did you mean 'tank'"):
        c.validate()


@pytest.mark.parametrize("call, message", [
    (lambda c: c.resistor("R9", "a", "b", R=-2), r"R=-2 kPa·s/mg is outside"),
    (lambda c: c.resistor("R9", "a", "b", R="2kPa"), r"R needs kPa·s/mg, got kPa"),
    (lambda c: c.volume("V9", "a", V="200mL", n=2), r"n=2 .*outside"),
    (lambda c: c.resistor("R9", "a", "b", R=1, Rx=2), r"unknown parameter 'Rx'.*did you mean 'R'"),
    (lambda c: c.valve("X9", "a", "b", "c", model={"Rf": 0.5, "pclose": 100, "ptrans": 90,
                                                   "e": 2, "ain": 0.3, "aout": 0.7}),
     r"ptrans .* must be greater than pclose"),
])
def test_bad_parameters_name_element_and_expected_unit(call, message):
    with pytest.raises(ParameterError, match=message) as err:
        call(Circuit())
    assert "9" in str(err.value)  # names the element


def test_gauge_pressure_strings_are_converted_with_the_ambient():
    c = Circuit(ambient=96.0)
    spec = c.pressure_source("P1", "s", "200kPag")
    assert spec.params["value"].level == pytest.approx(296.0)
    assert c.pressure_source("P2", "t", "4.96bar").params["value"].level == pytest.approx(496.0)


def test_solver_failure_reports_time_node_advice_and_keeps_partial_results():
    """A flow source draining a closed volume drives its pressure to zero at
    t = C·p0/ṁ ≈ 0.12 s, where no physical solution continues."""
    c = Circuit(ambient=100.0)
    c.flow_source("F1", "tank", "atm", 100.0)
    c.volume("V1", "tank", V=10.0, p0=100.0)
    with pytest.raises(SolverError) as err:
        c.tran(1.0)
    e = err.value
    assert e.time == pytest.approx(0.119, abs=0.01)
    assert "node tank" in str(e) and "vacuum" in str(e) and "try" in str(e)
    assert e.partial is not None and e.partial.t[-1] <= e.time + 1e-9


@pytest.mark.parametrize("band", [1.0, 100.0])
def test_zero_flow_regularisation_band_does_not_change_results(band, oscillator_run):
    """The band ε of sr(d) = d/(d²+ε²)^¼ moves the period by < 0.1 % over 1…100 kPa²."""
    from .conftest import cycle_periods

    reference = cycle_periods(oscillator_run).mean()
    other = cycle_periods(oscillator(flow_band=band).tran(30.0)).mean()
    assert other == pytest.approx(reference, rel=1e-3)


def test_solution_is_immutable_and_exports_unit_named_columns(oscillator_run, tmp_path):
    with pytest.raises(ValueError):
        oscillator_run.pressure("tank")[0] = 0.0
    frame = oscillator_run.to_pandas()
    assert {"time_s", "p_tank_kPa", "mdot_Rout_mg_s", "mdot_PH_mg_s"} <= set(frame.columns)
    path = tmp_path / "osc.csv"
    oscillator_run.to_csv(path)
    import pandas as pd

    back = pd.read_csv(path)
    np.testing.assert_allclose(back["p_tank_kPa"], frame["p_tank_kPa"], rtol=1e-8)


def test_mass_is_conserved_over_a_transient(oscillator_run):
    """Mass stored in the tank = ∫ (inflow through R_out − outflow through R_vent) dt."""
    from pneunet.physics.gas import AIR

    s = oscillator_run
    keep = np.concatenate([[True], np.diff(s.t) > 0])  # drop the duplicate time of each jump
    t = s.t[keep]
    net = (s.flow("Rout") - s.flow("Rvent"))[keep]
    stored = AIR.capacitance(200.0) * (s.pressure("tank")[-1] - s.pressure("tank")[0])
    assert np.trapezoid(net, t) == pytest.approx(stored, rel=2e-3)


def test_a_circuit_without_unknowns_is_its_sources():
    """Every node held by a source (a volume on a source's node included): no integrator
    (scikit-sundae cannot make a solver of size 0: it was a traceback), the pressures are
    the sources' and the flows the quadrature law's, at every output time."""
    import numpy as np

    from pneunet import Circuit
    from pneunet.physics.waveforms import Step

    c = Circuit("sources only", ambient=100.0)
    c.pressure_source("P1", "a", Step(200.0, 300.0, at=0.5))
    c.resistor("R1", "a", "atm", R=2.0)
    c.volume("V1", "a", V=10.0)
    sol = c.tran(1.0, t_step=0.1)
    # the grid's 11 times, t = 0.5 twice: both sides of the step (issue 32)
    assert sol.stats["unknowns"] == 0 and len(sol.t) == 12
    p = np.repeat([200.0, 300.0], 6)
    np.testing.assert_allclose(sol.pressure("a"), p)
    np.testing.assert_allclose(sol.flow("R1"), np.sqrt(p ** 2 - 100.0 ** 2) / 2.0, rtol=1e-3)
