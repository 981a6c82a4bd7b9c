"""Which recorded samples a circuit fit compares (truth/circuits/fit.py:compared_masks):
a pressure at a node with a volume is compared at every sample, its fastest edges
included; around the jumps of a node without one (a valve output at a fold) and of a
flow a few samples are left out."""
import numpy as np
import pytest

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits.data import JUMP_HALF_WIDTH, compared_samples
from pneunet.truth.circuits.fit import compared_masks
from pneunet.truth.circuits.model import TraceModel

STEP = np.r_[np.full(50, 96.0), np.full(50, 496.0)]  # a 400 kPa jump within one sample


def test_storage_node_edges_are_compared_algebraic_jumps_are_not():
    osc = TraceModel(NetlistBuilder("netlists/oscillator.pn"))
    masks = compared_masks(osc, {}, {"p_tank": STEP, "p_out": STEP, "mdot_X1": STEP})
    assert masks["p_tank"].all()  # Vtank: storage
    left_out = np.flatnonzero(~masks["p_out"])  # out: no volume, jumps at the fold
    np.testing.assert_array_equal(left_out, np.arange(50 - JUMP_HALF_WIDTH, 50 + JUMP_HALF_WIDTH))
    assert not masks["mdot_X1"].all()


def test_a_global_dead_volume_does_not_make_every_node_storage():
    """``.options dead_volume`` adds a tiny volume at every node for the solver's sake:
    the valve output still jumps within a sample, and is still left out there."""
    osc = TraceModel(NetlistBuilder("netlists/oscillator.pn"), options={"dead_volume": 1e-3})
    assert not compared_masks(osc, {}, {"p_out": STEP})["p_out"].all()


def test_inverter_outputs_with_their_volumes_are_compared_everywhere():
    inv = TraceModel(NetlistBuilder("netlists/inverter.pn"))
    masks = compared_masks(inv, {"Rpull": 23.0}, {"p_out1": STEP, "p_out2": STEP[::-1]})
    assert masks["p_out1"].all() and masks["p_out2"].all()


def test_the_screen_leaves_a_storage_nodes_edges_out_with_the_jacobians_rows():
    """The fit compares out1's edges, the screen does not (a grid point misses an edge's
    timing alike for every candidate); the Jacobian handed to the screen has exactly the
    rows of the samples it compares, in the same order."""
    from pneunet.truth.circuits import fit_trace
    from pneunet.truth.circuits.candidate_fits import screen_data
    from pneunet.truth.circuits.data import compared_samples, read_trace

    from .standalone_inverter import inverter_record

    rec = read_trace(inverter_record(0.5, 6.0, dt=0.02, noise=0.3, seed=1, Rpull=23.0))
    fit = fit_trace(NetlistBuilder("netlists/inverter.pn"), rec, {"Rpull": (23.0, 2.0, 200.0)},
                    node="out1", max_nfev=6)
    assert fit.extras["keep"]["p_out1"].all()  # the fit: every sample
    data, jac = screen_data(rec, (0.0, 6.0), fit)
    keep = data[3]
    y = rec["p_out1_kPa"].to_numpy()
    np.testing.assert_array_equal(keep["p_out1"], compared_samples(y))
    assert not keep["p_out1"].all()
    rows = np.concatenate([keep[s][fit.extras["keep"][s]] for s in data[1]])
    np.testing.assert_array_equal(jac, fit.extras["jacobian"][rows])
    assert jac.shape[0] == sum(int(k.sum()) for k in keep.values())


def _edges(rate_hz):
    """A valve output's two edges as loggers at ``rate_hz`` record them: a 360 kPa rise
    and a 125 kPa fall, each a logistic of 8 ms width (a dead volume behind the valve),
    the level drifting slowly between them."""
    t = np.arange(0.0, 4.0, 1.0 / rate_hz)
    rise = 360.0 / (1.0 + np.exp(-(t - 1.0) / 0.008))
    fall = -125.0 / (1.0 + np.exp(-(t - 3.0) / 0.008))
    return t, 96.0 + rise + fall + 3.0 * np.sin(t)


@pytest.mark.parametrize("rate_hz", [20, 50, 100, 200, 1000])
def test_an_algebraic_nodes_edge_is_left_out_whole_at_any_logger_rate(rate_hz):
    """Where a valve output's recorded edge spans several samples (a fast logger), none
    of its samples between 5 % and 95 % of the way is compared, the smaller fall too
    (no single step of it is a quarter of the range); away from the edges (more than
    four samples and 0.1 s) every sample is."""
    t, y = _edges(rate_hz)
    osc = TraceModel(NetlistBuilder("netlists/oscillator.pn"))
    keep = compared_masks(osc, {}, {"p_out": y})["p_out"]
    for t0 in (1.0, 3.0):
        s = 1.0 / (1.0 + np.exp(-(t - t0) / 0.008))
        assert not keep[(s > 0.05) & (s < 0.95)].any()
    far = np.min(np.abs(t[:, None] - np.array([1.0, 3.0])), axis=1) > max(0.1, 4.0 / rate_hz)
    assert keep[far].all()


def test_the_filling_behind_a_junctions_jump_stays_compared():
    """The edge rule of an autonomous circuit on a junction like the amplifier's at
    100 Hz: each switching moves it by a step (45 kPa up, 19 down), then it follows the
    actuator filling or venting through the line, 10 kPa a sample at first.  The up-step
    is a jump and is left out (four samples), the small down-step with the venting
    behind it is none; the filling and the venting are compared."""
    from .standalone_driven import amplifier_record

    rec = amplifier_record(0.0, 30.0, dt=0.01, noise=0.3, seed=1)
    y = rec["p_act_kPa"].to_numpy()
    amp = TraceModel(NetlistBuilder("netlists/amplifier.pn"))
    keep = compared_masks(amp, {}, {"p_act": y}, autonomous=True)["p_act"]
    ups, downs = np.flatnonzero(np.diff(y) > 30.0), np.flatnonzero(np.diff(y) < -15.0)
    assert len(ups) == 3 and len(downs) == 2
    runs = np.flatnonzero(np.diff(np.r_[1, keep.astype(int), 1]) != 0).reshape(-1, 2)
    np.testing.assert_array_equal(runs, np.column_stack([ups - 1, ups + 3]))
    for i in np.r_[ups, downs]:
        assert keep[i + 3:i + 60].all()


def test_a_driven_circuits_edges_spread_over_samples_are_compared():
    """In a circuit driven by its sources the sources decide when a valve switches: the
    fit compares the amplifier's junction on every sample but those around a jump within
    one sample.  With a 6 mL dead volume between the valves its 50 kPa jump spreads over
    two samples at 100 Hz (32 and 16 kPa) and is compared: that is where the volume
    shows.  The oscillator's valve output, whose switching its own state decides, is
    left out over its whole edges (the same fit's rule)."""
    from pneunet.truth.circuits import fit_trace

    from .standalone import oscillator_record
    from .standalone_driven import amplifier_record

    rec = amplifier_record(3.0, 12.0, dt=0.01, noise=0.3, seed=1, V_act=6.0, R_line=0.24,
                           V=30.0)
    fit = fit_trace(NetlistBuilder("netlists/amplifier.pn"), rec,
                    {"Rtube.R": (0.24, 0.02, 2.0), "Amck.V": (30.0, 5.0, 200.0)},
                    node="muscle", max_nfev=2)
    y = rec["p_act_kPa"].to_numpy()
    assert not compared_samples(y, whole_edges=True).all()  # an autonomous one's rule
    assert fit.start_state.driven and fit.extras["keep"]["p_act"].all()
    osc = oscillator_record(12.0, dt=0.02, noise=0.3, seed=1, V_out=3.0)
    fit = fit_trace(NetlistBuilder("netlists/oscillator.pn"), osc,
                    {"Rvent": (3.0, 0.5, 20.0)}, node="tank", max_nfev=2)
    y = osc["p_out_kPa"].to_numpy()
    assert not fit.start_state.driven
    np.testing.assert_array_equal(fit.extras["keep"]["p_out"],
                                  compared_masks(TraceModel(NetlistBuilder(
                                      "netlists/oscillator.pn")), {}, {"p_out": y})["p_out"])
    assert (~fit.extras["keep"]["p_out"]).sum() > (~compared_samples(y)).sum()
