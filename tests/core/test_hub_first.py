"""Cells that only read the hub (valve control lines): the hub is integrated first and
pins the hub nodes of the cells, which then run as independent cells.

References are computed independently of that path: the single-rate IDA transient of
the whole circuit at tight tolerances, and exact polynomials for the sample tables.
"""
from __future__ import annotations

import numpy as np
import pytest

from pneunet.physics.elements.sources import _WaveformBank
from pneunet.engine.partition import partition
from pneunet.netlist import parse_netlist
from pneunet.physics.waveforms import Pulse, SampleTable, Sampled

CELLS = 20


def address_network(method="multirate", rtol=1e-6, algebraic=False, cells=CELLS):
    """An inverter drives the control line h of one valve in every cell (the hub: read
    only); a second valve per cell opens on its own staggered control pulse.  The
    inverter's address line steps (zero rise), so the hub's rate jumps.  ``algebraic``:
    instead of the second valve, a resistor from a node without volume."""
    last = cells - 1
    if algebraic:
        cell = "X1 data n1 h mirror backward=mirror_backward\nRser n1 act 2kPa*s/mg"
        controls = ""
    else:
        cell = ("X1 data n1 h mirror backward=mirror_backward\nVn1 n1 0.5mL\n"
                "X2 n1 act c mirror backward=mirror_backward")
        controls = (f"PC[0:{last}] c[0:{last}] PULSE(96kPa 496kPa {{0.1+0.09*index}} "
                    "10ms 10ms 0.6 1.6)")
    text = f"""* read-only hub
.options ambient=96kPa rtol={rtol} atol={rtol} method={method}
PD data 496kPa
PA a PULSE(96kPa 496kPa 0.5 0 0 1.0 2.0)
Xinv data h a mirror backward=mirror_backward
Rpull h atm 20kPa*s/mg
Vh h 2mL
{controls}
.subckt CELL data h c act
{cell}
.ends
Xcell[0:{last}] data h c[0:{last}] act[0:{last}] CELL
Aact[0:{last}] act[0:{last}] V=20mL
Rleak[0:{last}] act[0:{last}] atm 5kPa*s/mg
"""
    return parse_netlist(text).circuit


@pytest.fixture(scope="module")
def reference():
    return address_network("single", rtol=1e-9).tran(3.0, t_step=0.01)


def test_a_hub_read_through_control_ports_only_is_read_only():
    part = partition(address_network())
    assert part.hub_nodes == ["h"] and part.read_only_hub
    assert len(part.groups) == 1  # the cells' pinned and hub nodes number alike
    # a cell that draws from h (a resistor into it) makes the hub two-way
    c = address_network()
    c.add("resistor", "Rdraw", ("Xcell[0].n1", "h"), R=10.0)
    assert not partition(c).read_only_hub


def test_hub_first_matches_single_rate_ida(reference):
    sol = address_network().tran(3.0, t_step=0.01)
    assert sol.stats["method"] == "multirate (hub first)"
    assert sol.stats["hub_steps"] > 0 and "sweeps" not in sol.stats
    assert np.array_equal(sol.t, np.round(np.arange(301) * 0.01, 12)) or \
        np.allclose(sol.t, np.arange(301) * 0.01, atol=1e-12)
    for node in ["h"] + [f"act[{k}]" for k in range(CELLS)] + ["Xcell[7].n1"]:
        expected = np.interp(sol.t, reference.t, reference.pressure(node))
        assert np.abs(sol.pressure(node) - expected).max() < 0.05, node  # kPa, at rtol 1e-6
    # the cells really switched: every actuator filled and drained
    peaks = [sol.pressure(f"act[{k}]").max() for k in range(CELLS)]
    assert min(peaks) > 150.0


def test_cells_with_nodes_without_volume_run_alone_against_a_read_only_hub():
    sol = address_network(algebraic=True).tran(3.0, t_step=0.01)
    assert sol.stats["method"] == "multirate (hub first)" and sol.stats["cells_alone"] == CELLS
    ref = address_network("single", rtol=1e-9, algebraic=True).tran(3.0, t_step=0.01)
    for node in ["h", "act[3]", "Xcell[17].n1"]:
        expected = np.interp(sol.t, ref.t, ref.pressure(node))
        assert np.abs(sol.pressure(node) - expected).max() < 0.05, node


def test_sample_table_is_the_cubic_hermite_through_values_and_slopes():
    def f(t):
        return 2 + t - 0.5 * t ** 2 + 0.1 * t ** 3

    def df(t):
        return 1 - t + 0.3 * t ** 2
    knots = np.array([0.0, 0.4, 1.5, 3.0])
    table = SampleTable(knots, np.column_stack([f(knots), -3 * f(knots)]),
                        np.column_stack([df(knots), -3 * df(knots)]))
    t = np.linspace(0.0, 3.0, 31)
    values, slopes = table.value(t), table.slope(t)
    assert np.allclose(values[:, 0], f(t), atol=1e-13) and np.allclose(slopes[:, 1], -3 * df(t))
    assert np.allclose(table.at(t, np.arange(31) % 2), np.where(np.arange(31) % 2, -3, 1) * f(t))
    # a repeated time is a corner: |t − 1| from its one-sided slopes, exact on both sides
    kink = SampleTable([0.0, 1.0, 1.0, 2.0], [1.0, 0.0, 0.0, 1.0], [-1.0, -1.0, 1.0, 1.0])
    s = np.array([0.0, 0.25, 0.999, 1.0, 1.5, 2.0])
    assert np.allclose(kink.at(s, np.zeros(6, dtype=int)), np.abs(s - 1.0), atol=1e-12)


def test_sampled_sources_of_one_table_evaluate_together_as_one_by_one():
    knots = np.linspace(0.0, 1.0, 6)
    table = SampleTable(knots, np.column_stack([knots ** 2, np.cos(knots)]),
                        np.column_stack([2 * knots, -np.sin(knots)]))
    waves = [Sampled(table, 1, corners=[0.5]), Pulse(1.0, 2.0, 0.2, 0.1, 0.1, 0.3),
             Sampled(table, 0), Sampled(table, 1)]
    bank = _WaveformBank(waves)
    t_each = np.array([0.13, 0.5, 0.77, 0.91])
    assert np.allclose(bank.value_each(t_each), [w.value(ti) for w, ti in zip(waves, t_each)])
    grid = np.array([[0.1, 0.35], [0.6, 0.95]])
    assert np.allclose(bank.value(grid), np.stack([w.value(grid) for w in waves], axis=-1))
    assert list(waves[0].breakpoints(0.0, 1.0)) == [0.5]


def test_auto_runs_hub_first_when_the_cells_are_driven_in_many_ways():
    from pneunet.engine.simulate import transient_method

    staggered = address_network("auto", cells=64)       # 64 different control schedules
    assert "read only by the cells" in transient_method(staggered, (0.0, 3.0))
    same = address_network("auto", cells=64)
    for k in range(64):  # every cell on the first cell's control pulse
        same.elements[f"PC[{k}]"].params["value"] = same.elements["PC[0]"].params["value"]
    assert transient_method(same, (0.0, 3.0)).startswith("single-rate IDA")
    assert transient_method(address_network("auto", cells=20), (0.0, 3.0)).startswith(
        "single-rate IDA")  # fewer than 64 cells


def test_a_failing_cell_keeps_every_row_all_cells_reached(monkeypatch):
    """A solver failure mid-run returns the rows up to where every cell got, hub
    columns included, equal to those of a run that does not fail."""
    from pneunet.engine.solvers import radau
    from pneunet.common.errors import SolverError

    full = address_network().tran(3.0, t_step=0.01)
    check, passes = radau._check_step, [0]

    def collapse_late(problem, st, active, h, systems):
        passes[0] += 1
        if passes[0] > 400:
            raise SolverError("forced collapse", time=float(st.t.min()))
        return check(problem, st, active, h, systems)
    monkeypatch.setattr(radau, "_check_step", collapse_late)
    with pytest.raises(SolverError) as caught:
        address_network().tran(3.0, t_step=0.01)
    partial = caught.value.partial
    assert 0.5 < partial.t[-1] < 3.0 and partial.t.size > 50
    for node in ["h", "act[0]", "act[19]"]:
        np.testing.assert_array_equal(partial.pressure(node), full.pressure(node)[:partial.t.size])
