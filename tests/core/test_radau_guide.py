"""The batched Radau IIA integrator retaking the steps of an earlier sweep."""
from __future__ import annotations

import numpy as np

from pneunet.engine.solvers import radau


class KinkedRelaxation:
    """G scalar systems ẏ = −λ_g·(y − |sin(3t)|): each follows a rectified sine with its
    own rate, so the step-size controller meets a kink every π/3 s and rejects steps."""

    def __init__(self, rates):
        self.lam = np.asarray(rates, dtype=float)
        self.differential = np.array([True])
        self.names = [[f"y{g}"] for g in range(self.lam.size)]

    def evaluate(self, t, Y, Yd, jacobian=False):
        res = Yd + self.lam[:, None] * (Y - np.abs(np.sin(3.0 * t))[:, None])
        out = np.zeros((Y.shape[0], 0))
        if not jacobian:
            return res, out
        G = Y.shape[0]
        return res, out, self.lam.reshape(G, 1, 1).copy(), np.ones((G, 1, 1))

    def rates(self, t, Y, Yd_guess):
        return -self.lam[:, None] * (Y - np.abs(np.sin(3.0 * t))[:, None])


def run(problem, guide=None):
    st = radau.start(problem, 0.0, np.zeros((problem.lam.size, 1)), 3.0, 1e-6, 1e-6)
    ends, count = ([], []), radau.Counters()

    def on_step(rows, before, after):
        ends[0].append(rows)
        ends[1].append(after[0])
    radau.advance(problem, st, 3.0, 1e-6, 1e-6, on_step=on_step, count=count, guide=guide)
    return st, np.concatenate(ends[0]), np.concatenate(ends[1]), count


def test_a_guided_sweep_retakes_the_accepted_steps_without_the_rejected_attempts():
    problem = KinkedRelaxation([5.0, 40.0, 300.0])
    first, rows, ends, count = run(problem)
    assert count.rejected >= 10                     # the kinks cost attempts the first time
    guide = radau.StepGuide(problem.lam.size, 0.0, rows, ends)
    second, rows2, ends2, count2 = run(problem, guide)
    assert count2.rejected == 0
    for g in range(problem.lam.size):               # the same grid, system by system
        assert np.array_equal(np.sort(ends2[rows2 == g]), np.sort(ends[rows == g]))
    assert np.allclose(second.Y, first.Y, rtol=1e-9, atol=0)


def test_a_guide_is_only_a_proposal_the_error_test_still_decides():
    """A guide recorded for a slow system, given to a fast one: its long steps fail the
    error test, and the controller takes over (the solution matches an unguided run)."""
    slow, fast = KinkedRelaxation([2.0]), KinkedRelaxation([2000.0])
    _, rows, ends, _ = run(slow)
    unguided, *_ = run(fast)
    guided, _, _, count = run(fast, radau.StepGuide(1, 0.0, rows, ends))
    assert count.rejected >= 1
    exact_tail = np.abs(np.sin(3.0 * 3.0))          # λ = 2000 follows the sine within 1e-3
    assert abs(guided.Y[0, 0] - unguided.Y[0, 0]) <= 1e-5 * exact_tail + 1e-5
