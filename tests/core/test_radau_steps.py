"""The batched Radau IIA integrator's step control where an input starts with an
infinite slope (a control ramp on a quadrature resistor at zero flow does that)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import quad

from pneunet.engine.solvers import radau

from .relaxation import ForcedRelaxation


class RootRamp(ForcedRelaxation):
    """G scalar systems ẏ = −λ_g·y + A·√max(t − t0, 0): the forcing starts at t0 with an
    infinite slope, so the error of a step from t0 falls about as h^1.5, not h^4."""

    def __init__(self, rates, t0=0.3, amplitude=50.0):
        super().__init__(rates, lambda t: amplitude * np.sqrt(np.maximum(t - t0, 0.0)))
        self.t0, self.amplitude = t0, amplitude

    def exact(self, g, t):
        """y_g(t) from y(0) = 0: A·∫ e^(−λ(t−s))·√(s − t0) ds over [t0, t]."""
        lam = self.lam[g]
        return quad(lambda s: self.amplitude * np.exp(-lam * (t - s)) * np.sqrt(s - self.t0),
                    self.t0, t, epsabs=1e-13, epsrel=1e-13)[0]


def test_after_a_root_kink_the_step_follows_the_observed_order_of_the_error():
    """Landing on t0, each system's first attempts fail; the retries take the error's
    observed order into account, so the three systems need 9 rejected attempts in all
    (25 with the h⁴ rule alone), and the end values match the exact solution to 1e-7."""
    problem = RootRamp([0.5, 3.0, 20.0])
    G = problem.lam.size
    st = radau.start(problem, 0.0, np.zeros((G, 1)), 1.0, 1e-6, 1e-6)
    corners = radau.Corners([np.array([problem.t0])] * G, [np.empty(0)] * G)
    count = radau.Counters()
    radau.advance(problem, st, 1.0, 1e-6, 1e-6, corners, count=count)
    assert count.rejected <= 12
    for g in range(G):
        exact = problem.exact(g, 1.0)
        assert abs(st.Y[g, 0] - exact) <= 1e-7 * abs(exact)
