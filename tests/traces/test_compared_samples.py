"""Which recorded samples a circuit fit compares (truth/circuits/fit.py:compared_masks):
a pressure at a node with a volume is compared at every sample, its fastest edges
included; around the jumps of a node without one (a valve output at a fold) and of a
flow a few samples are left out."""
import numpy as np

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits.data import JUMP_HALF_WIDTH
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
