"""A third circuit for the trace diagnosis: the two-inverter chain of netlists/inverter.pn.

Its stand-alone generator (:mod:`.standalone_inverter`, no pneunet code) and pneunet agree
on the clean chain and with each library effect the study hides in it; and a circuit with
several volumes is offered heat exchange in each volume on its own (the chain's hidden
heat exchange is in out1's volume only: one τ for both volumes cannot fit it).
"""
import numpy as np
import pytest

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import candidates_for
from pneunet.truth.circuits.effects import VolumeHeatTransfer

from .standalone_inverter import inverter_record

NETLIST = "netlists/inverter.pn"


def chain(**options):
    return NetlistBuilder(NETLIST, **options)({"Rpull": 23.0})


def test_a_circuit_with_several_volumes_is_offered_each_volume_on_its_own():
    names = {e.name for e in candidates_for(chain())}
    assert {"volume_heat_transfer", "volume_heat_transfer@X1.Vout",
            "volume_heat_transfer@X2.Vout", "polytropic_volume"} <= names
    assert not any(n.startswith("polytropic_volume@") for n in names)  # absorbed a leak
    one = {e.name for e in candidates_for(NetlistBuilder("netlists/oscillator.pn")({}))}
    assert not any(n.startswith(("volume_heat_transfer@", "polytropic_volume@")) for n in one)


def test_heat_exchange_in_one_volume_leaves_the_other_isothermal():
    effects = {e.name: e for e in candidates_for(chain())}
    one, two = effects["volume_heat_transfer@X1.Vout"], effects["volume_heat_transfer@X2.Vout"]
    assert list(one.params) == ["tau@X1.Vout"]
    c = chain()
    one.apply(c, {"tau@X1.Vout": 0.3})
    kinds = {s.name: s.kind for s in c.elements.values()}
    assert kinds["X1.Vout"] == "thermal_chamber" and kinds["X2.Vout"] == "volume"
    assert c.elements["X1.Vout"].params["tau"] == 0.3
    c = chain()  # the two as a pair, each with its own τ
    one.apply(c, {"tau@X1.Vout": 0.3})
    two.apply(c, {"tau@X2.Vout": 2.0})
    assert [c.elements[v].params["tau"] for v in ("X1.Vout", "X2.Vout")] == [0.3, 2.0]


@pytest.mark.parametrize("hidden, effect, values", [
    ({}, None, {}),
    ({"heat_tau": 0.5}, VolumeHeatTransfer(("X1.Vout",), site=True), {"tau@X1.Vout": 0.5}),
    ({"tube_ctrl": (20.0, 1.0)}, "tube@X2.Xv.ctrl",
     {"R_tube@X2.Xv.ctrl": 20.0, "V_tube@X2.Xv.ctrl": 1.0}),
], ids=["clean", "heat@X1.Vout", "tube@X2.Xv.ctrl"])
def test_the_stand_alone_chain_agrees_with_pneunet(hidden, effect, values):
    """Within 0.01 kPa at every sample (the edges of out1 and out2, 400 kPa in ~10 ms,
    included; measured 2e-3): both integrated tightly, pneunet's zero-flow band set to the
    generator's 1 kPa², its output on the samples' grid."""
    rec = inverter_record(0.0, 4.5, dt=0.01, noise=0.0, Rpull=23.0, **hidden)
    c = chain(rtol=1e-8, atol=1e-8, flow_band=1.0)
    if effect is not None:
        bound = candidates_for(c, [effect])
        assert len(bound) == 1
        bound[0].apply(c, values)
    sol = c.tran(4.5, t_step=0.01)
    for node in ("out1", "out2"):
        model = np.interp(rec["time_s"], sol.t, sol[f"p_{node}"])
        assert np.max(np.abs(model - rec[f"p_{node}_kPa"])) < 0.01, node
