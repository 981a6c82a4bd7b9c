"""Circuit effects: every registered kind offers its sites on the oscillator, each bound
effect changes the simulated circuit and keeps it simulatable, its screening grid lies
inside its bounds, and an effect without ``apply`` cannot be made."""
import numpy as np
import pytest

from pneunet.design.circuits import oscillator
from pneunet.truth.circuits import CircuitEffect, candidates_for

BASE = oscillator({"V": 50.0}).tran(3.0, t_step=0.05)


@pytest.mark.parametrize("effect", candidates_for(oscillator()), ids=lambda e: e.name)
def test_effect_changes_the_circuit_and_its_grid_is_inside_its_bounds(effect):
    grid = effect.grid()
    assert grid
    for point in grid:
        for k, v in point.items():
            _, lo, hi = effect.params[k]
            assert lo < v < hi
    c = oscillator({"V": 50.0})
    effect.apply(c, grid[len(grid) // 2])
    sol = c.tran(3.0, t_step=0.05)
    tank = np.interp(BASE.t, sol.t, sol["p_tank"])
    assert np.max(np.abs(tank - BASE["p_tank"])) > 1.0  # kPa: the effect is visible


def test_sites_cover_the_lines_where_a_tube_is_not_a_dead_volume():
    names = {e.name for e in candidates_for(oscillator())}
    assert {"polytropic_volume", "volume_heat_transfer", "dead_volume@out", "tube@X1.in",
            "tube@X1.ctrl", "tube@V1.node"} <= names
    assert "tube@X1.out" not in names and "tube@Rout.a" not in names


def test_after_heat_exchange_no_dead_volume_is_offered_at_its_links():
    """The tank with its energy balance gets a thermal_inlet per line: the link nodes sit
    at the tank's pressure, so a dead volume there is more tank, not a new site."""
    c = oscillator({"V": 50.0})
    heat = next(e for e in candidates_for(c) if e.name == "volume_heat_transfer")
    heat.apply(c, {"tau": 0.3})
    links = {s.nodes[0] for s in c.elements.values() if s.kind == "thermal_inlet"}
    assert len(links) == 2
    sites = {e.name for e in candidates_for(c) if e.family == "dead volume"}
    assert "dead_volume@out" in sites
    assert not {f"dead_volume@{n}" for n in links} & sites


def test_an_effect_without_apply_cannot_be_made():
    class Nothing(CircuitEffect):
        name = "nothing"

    with pytest.raises(TypeError):
        Nothing()


def test_heat_exchange_changes_only_the_volumes_the_circuit_had():
    """Bound by ``candidates`` to the netlist's volumes: a tube's volume added by another
    effect, before or after, stays isothermal (a thin tube's gas is at wall temperature;
    one shared τ with a 200 mL tank would make its 5 mL adiabatic)."""
    base = oscillator({})
    effects = {e.name: e for e in candidates_for(base)}
    heat, tube = effects["volume_heat_transfer"], effects["tube@X1.ctrl"]
    values = {"tau": 0.5, "R_tube@X1.ctrl": 1.0, "V_tube@X1.ctrl": 5.0}
    for order in ((tube, heat), (heat, tube)):
        c = oscillator({})
        for e in order:
            e.apply(c, values)
        kinds = {s.name: s.kind for s in c.elements.values()}
        assert kinds["Vtube_X1_ctrl"] == "volume"
        assert [n for n, k in kinds.items() if k in ("thermal_volume", "thermal_chamber")] \
            == ["V1"]


def test_a_tube_with_its_volume_has_the_dead_volume_at_its_node_as_its_limit():
    """R → 0: the tube's volume at the node it joins (the amplifier's Xin.out and
    Xout.in are both at ``act``); a tube without a volume of its own has no such limit."""
    from pneunet.netlist.builder import NetlistBuilder
    from pneunet.truth.circuits.effects import Tube

    circuit = NetlistBuilder("netlists/amplifier.pn")({})
    for port, element in (("out", "Xin"), ("in", "Xout")):
        site = f"{element}.{port}"
        tube = Tube(element, port)
        assert tube.limits(circuit, {f"R_tube@{site}": 0.007, f"V_tube@{site}": 3.9}) == \
            [("dead_volume@act", {"V_dead@act": 3.9})]
        assert {name for name, _ in tube.limits(circuit, {f"V_tube@{site}": 1.0})} <= \
            {e.name for e in candidates_for(circuit)}
    assert Tube("Xin", "out", with_volume=False).limits(circuit, {}) == []
