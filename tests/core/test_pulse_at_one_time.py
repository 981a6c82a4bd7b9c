"""A PULSE at one time on Python floats (PulseTable.fraction_at, what a pressure source
gives IDA) is the vectorised PulseTable.fraction to the bit, and both are the SPICE
PULSE written out in the test."""
import numpy as np
import pytest

from pneunet.physics.elements.sources import _WaveformBank
from pneunet.physics.waveforms import Constant, Pulse, PulseTable

# (delay, rise, width, fall, period): ramps, steps (zero rise or fall), once or periodic
TIMINGS = [(0.5, 0.01, 4.99, 0.01, 10.0), (0.0, 0.0, 1.0, 0.2, 3.0), (1.0, 0.3, 0.7, 0.0, 0.0),
           (0.2, 0.0, 0.5, 0.0, 1.5)]


def spice_pulse(t, delay, rise, width, fall, period):
    """Fraction of the swing by the SPICE definition, one time and one pulse."""
    tau = t - delay
    if period and tau >= 0:
        tau %= period
    if tau < 0:
        return 0.0
    if tau < rise:
        return tau / rise
    if tau < rise + width:  # a step down (fall 0) is low at its instant
        return 1.0
    if tau < rise + width + fall:
        return 1.0 - (tau - rise - width) / fall
    return 0.0


def test_one_time_is_the_vectorised_pulse_to_the_bit():
    table = PulseTable(*np.array(TIMINGS).T)
    corners = [d + x for d, r, w, f, p in TIMINGS for x in (0, r, r + w, r + w + f)]
    grid = np.linspace(-1.0, 25.0, 4001)
    times = np.concatenate([grid, corners, np.nextafter(corners, 30.0),
                            np.nextafter(corners, -30.0)])
    many = table.fraction(times[:, None])
    for t, row in zip(times, many):
        assert table.fraction_at(float(t)) == row.tolist(), t
    for t in grid:  # (a step is one within 1e-300 s before its instant: not compared)
        assert table.fraction_at(float(t)) == pytest.approx(
            [spice_pulse(t, *timing) for timing in TIMINGS], abs=1e-9), t


def test_a_bank_of_sources_is_its_waveforms():
    waves = [Constant(101.3), Pulse(100.0, 300.0, 0.5, 0.01, 0.01, 4.99, 10.0),
             Pulse(96.0, 496.0, 0.2, 0.0, 0.0, 0.5, 1.5)]
    bank = _WaveformBank(waves)
    for t in (0.0, 0.505, 1.3, 5.51, 12.0):
        assert bank.value(t).tolist() == [w.value(t) for w in waves]


def test_a_source_follows_its_waveform_from_one_time_to_the_next():
    from pneunet.engine.options import SimulationOptions
    from pneunet.physics.elements.base import ElementSpec, FamilyContext
    from pneunet.physics.elements.sources import PressureSource

    for waves in ([Constant(101.3), Constant(250.0)],
                  [Constant(101.3), Pulse(100.0, 300.0, 0.5, 0.01, 0.01, 4.99, 10.0)]):
        specs = [ElementSpec("pressure_source", f"P{k}", (f"n{k}",), {"value": w})
                 for k, w in enumerate(waves)]
        source = PressureSource(specs, FamilyContext(SimulationOptions()))
        for t in (0.0, 0.0, 0.505, 0.505, 1.3, 12.0, 0.2):  # IDA repeats and steps back
            assert source.pinned_pressure(t)[:, 0].tolist() == [w.value(t) for w in waves]


def test_a_large_bank_at_one_time_is_its_waveforms_too():
    """Above FLOAT_PULSES pulses one time goes through numpy (the float loop cost a
    3,000-cell transient 8.1 → 12.8 s): the same values."""
    from pneunet.physics.elements.sources import FLOAT_PULSES

    waves = [Pulse(96.0, 400.0, 0.2 + 0.25 * k, 0.05, 0.05, 2.0, 4.0)
             for k in range(FLOAT_PULSES + 4)] + [Constant(101.3)]
    bank = _WaveformBank(waves)
    for t in (0.0, 0.23, 1.3, 2.31, 5.51, 12.0):
        assert bank.value(t).tolist() == pytest.approx([w.value(t) for w in waves],
                                                        rel=1e-15, abs=1e-12)


def test_a_small_bank_at_one_time_on_floats_is_its_vectorised_value():
    """value_at (what a pressure source gives IDA at a new time) on floats is value to
    the bit, constants and pulses interleaved, at corners and either side of them."""
    waves = [Pulse(96.0 + 10 * k, 496.0 - 7 * k, *timing[:2], timing[3], timing[2], timing[4])
             for k, timing in enumerate(TIMINGS)]
    waves[1:1] = [Constant(101.3)]
    waves.append(Constant(250.0))
    bank = _WaveformBank(waves)
    corners = [d + x for d, r, w, f, p in TIMINGS for x in (0, r, r + w, r + w + f)]
    for t in np.concatenate([np.linspace(-1.0, 25.0, 1001), corners,
                             np.nextafter(corners, 30.0), np.nextafter(corners, -30.0)]):
        assert bank.value_at(float(t)).tolist() == bank.value(float(t)).tolist(), t
