"""The ``.model`` card of ``pneunet diagnose --model-out`` runs in a netlist: included with
``.include`` and used on an ``X`` line, the valve gives the flows of the fitted model, one
test per valve effect (each effect at a value where it changes the flow)."""
import numpy as np
import pytest

from pneunet.physics.valve_effects import ValveModel, get_effect
from pneunet.engine.simulate import operating_point
from pneunet.netlist import parse_file
from pneunet.physics.valve_params import PAPER_VALVES

#: (p_in, p_out, p_ctrl) kPa: open, near the threshold, closed, low ratio, low pressures
POINTS = [(396.0, 221.0, 96.0), (596.0, 346.0, 246.0), (296.0, 121.0, 171.0),
          (496.0, 130.0, 140.0), (496.0, 400.0, 260.0), (150.0, 100.0, 96.0),
          (296.0, 280.0, 120.0), (496.0, 200.0, 330.0)]

EFFECTS = {"choked": {"b": 0.45, "m": 0.6}, "leak": {"G": 0.02, "n": 0.8},
           "laminar": {"K": 40.0}, "hysteresis": {"h": 12.0},
           "pressure-offset": {"p0": 6.0}, "internal-drop": {"lam": 0.3}}


def circuit_flows(tmp_path, model, points):
    """The flow of one valve per point, each on its own three sources, in a netlist that
    includes the card (operating point)."""
    card = tmp_path / "valve.model"
    card.write_text("* fitted by pneunet diagnose from bench.csv\n"
                    + model.model_card("VDIAG") + "\n")   # what --model-out writes
    lines = ["* the diagnosed valve on three sources", '.include "valve.model"']
    for k, (p_in, p_out, p_ctrl) in enumerate(points):
        lines += [f"Pin{k} a{k} {p_in!r}kPa", f"Pout{k} b{k} {p_out!r}kPa",
                  f"Pctrl{k} c{k} {p_ctrl!r}kPa", f"X{k} a{k} b{k} c{k} VDIAG"]
    net = tmp_path / "valves.pn"
    net.write_text("\n".join(lines + [".op"]) + "\n")
    flows = operating_point(parse_file(net).circuit).flows
    return np.array([flows[f"X{k}"] for k in range(len(points))])


@pytest.mark.parametrize("effect", sorted(EFFECTS))
def test_card_in_a_netlist_gives_the_fitted_flows(tmp_path, effect):
    base = PAPER_VALVES["axi_0p6mm"]
    model = ValveModel(base, [get_effect(effect)(**EFFECTS[effect])])
    p = np.array(POINTS)
    fitted = model.flow(p[:, 0], p[:, 1], p[:, 2])       # a circuit has no sweep direction
    plain = ValveModel(base).flow(p[:, 0], p[:, 1], p[:, 2])
    got = circuit_flows(tmp_path, model, POINTS)
    # the card's 6 significant digits: within 1e-4 relative
    np.testing.assert_allclose(got, fitted, rtol=1e-4, atol=1e-6)
    if effect == "hysteresis":
        # the netlist valve has no sweep direction: it opens at the mean threshold
        # p_close (the rising and falling sweeps the diagnosis fitted differ from it)
        np.testing.assert_allclose(got, plain, rtol=1e-4, atol=1e-6)
        up = model.flow(p[:, 0], p[:, 1], p[:, 2], sweep=np.ones(len(p)))
        assert np.max(np.abs(up - got)) > 1.0
    else:
        assert np.max(np.abs(got - plain)) > 1.0, "the effect must change the flow here"
