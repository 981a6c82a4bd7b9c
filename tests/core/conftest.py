import numpy as np
import pytest


def upward_crossings(t, x, level):
    """Times where x crosses ``level`` upwards (linear interpolation)."""
    i = np.flatnonzero((x[:-1] < level) & (x[1:] >= level))
    return t[i] + (level - x[i]) / (x[i + 1] - x[i]) * (t[i + 1] - t[i])


def cycle_periods(solution, node="tank", settle=10.0):
    t, p = solution.t, solution.pressure(node)
    late = t > settle
    level = 0.5 * (p[late].min() + p[late].max())
    return np.diff(upward_crossings(t, p, level))


@pytest.fixture(scope="session")
def oscillator_run():
    """The R_out = 2 R_f oscillator simulated once for 30 s (explicit jumps)."""
    from pneunet.design.paper_circuits import oscillator

    return oscillator().tran(30.0)
