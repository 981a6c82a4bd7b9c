"""The batched Radau IIA integrator retaking the steps of an earlier sweep."""
from __future__ import annotations

import numpy as np

from pneunet.engine.solvers import radau

from .relaxation import ForcedRelaxation


class KinkedRelaxation(ForcedRelaxation):
    """G scalar systems ẏ = −λ_g·(y − |sin(3t)|): each follows a rectified sine with its
    own rate, so the step-size controller meets a kink every π/3 s and rejects steps."""

    def __init__(self, rates):
        super().__init__(rates, lambda t: self.lam * np.abs(np.sin(3.0 * t)))


class StiffeningRelaxation(KinkedRelaxation):
    """ẏ = −λ_g·(1 + y²)·(y − a·|sin(3t)|): the Jacobian depends on the state, and a
    changes the forcing a little, as a new coupling waveform does between sweeps."""

    def __init__(self, rates, a=1.0):
        super().__init__(rates)
        self.a = a

    def evaluate(self, t, Y, Yd, jacobian=False):
        target = self.a * np.abs(np.sin(3.0 * t))[:, None]
        res = Yd + self.lam[:, None] * (1.0 + Y * Y) * (Y - target)
        out = np.zeros((Y.shape[0], 0))
        if not jacobian:
            return res, out
        G = Y.shape[0]
        dres = self.lam[:, None] * (2.0 * Y * (Y - target) + 1.0 + Y * Y)
        return res, out, dres.reshape(G, 1, 1), np.ones((G, 1, 1))

    def rates(self, t, Y, Yd_guess):
        return Yd_guess - self.evaluate(t, Y, Yd_guess)[0]


def run(problem, guide=None):
    """Integrate to 3 s; return the final state, the accepted steps' systems and ends,
    the counters and the guide recorded on the way."""
    st = radau.start(problem, 0.0, np.zeros((problem.lam.size, 1)), 3.0, 1e-6, 1e-6)
    ends, count = ([], []), radau.Counters()
    recorder = radau.StepRecorder(problem.lam.size, 0.0)

    def on_step(rows, before, after):
        ends[0].append(rows)
        ends[1].append(after[0])
    radau.advance(problem, st, 3.0, 1e-6, 1e-6, on_step=on_step, count=count, guide=guide,
                  recorder=recorder)
    return st, np.concatenate(ends[0]), np.concatenate(ends[1]), count, recorder.guide()


def test_a_guided_sweep_retakes_the_accepted_steps_without_the_rejected_attempts():
    problem = KinkedRelaxation([5.0, 40.0, 300.0])
    first, rows, ends, count, guide = run(problem)
    assert count.rejected >= 10                     # the kinks cost attempts the first time
    second, rows2, ends2, count2, _ = run(problem, guide)
    assert count2.rejected == 0
    for g in range(problem.lam.size):               # the same grid, system by system
        assert np.array_equal(np.sort(ends2[rows2 == g]), np.sort(ends[rows == g]))
    assert np.allclose(second.Y, first.Y, rtol=1e-9, atol=0)


def test_a_guided_sweep_takes_the_recorded_newton_blocks_and_keeps_its_accuracy():
    """The second sweep sees a slightly different forcing (a = 1.001): it evaluates no
    Jacobian, and its end state matches an unguided run of that problem within the
    tolerance."""
    _, _, _, count, guide = run(StiffeningRelaxation([5.0, 40.0, 300.0]))
    assert count.jacobians == count.passes
    changed = StiffeningRelaxation([5.0, 40.0, 300.0], a=1.001)
    guided, _, _, guided_count, _ = run(changed, guide)
    unguided, *_ = run(changed)
    assert guided_count.jacobians == 0
    assert np.allclose(guided.Y, unguided.Y, rtol=2e-5, atol=2e-6)


def test_a_guide_is_only_a_proposal_the_error_test_still_decides():
    """A guide recorded for a slow system, given to a fast one: its long steps fail the
    error test and its Newton blocks (λ = 2, not 2000) fail the iteration, and the
    controller and fresh blocks take over (the solution matches an unguided run)."""
    slow, fast = KinkedRelaxation([2.0]), KinkedRelaxation([2000.0])
    *_, guide = run(slow)
    unguided, *_ = run(fast)
    guided, _, _, count, _ = run(fast, guide)
    assert count.rejected >= 1 and count.jacobians >= 1
    exact_tail = np.abs(np.sin(3.0 * 3.0))          # λ = 2000 follows the sine within 1e-3
    assert abs(guided.Y[0, 0] - unguided.Y[0, 0]) <= 1e-5 * exact_tail + 1e-5
