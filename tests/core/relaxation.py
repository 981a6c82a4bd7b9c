"""Scalar test systems for the batched Radau integrator: G systems ẏ = −λ_g·y + u(t)."""
from __future__ import annotations

import numpy as np


class ForcedRelaxation:
    """G scalar systems ẏ_g = −λ_g·y_g + u(t_g)_g, each at its own time; ``drive(t)``
    gives u (G,) at the systems' times t (G,)."""

    def __init__(self, rates, drive):
        self.lam = np.asarray(rates, dtype=float)
        self.drive = drive
        self.differential = np.array([True])
        self.names = [[f"y{g}"] for g in range(self.lam.size)]

    def evaluate(self, t, Y, Yd, jacobian=False):
        res = Yd + self.lam[:, None] * Y - self.drive(t)[:, None]
        out = np.zeros((Y.shape[0], 0))
        if not jacobian:
            return res, out
        G = Y.shape[0]
        return res, out, self.lam.reshape(G, 1, 1).copy(), np.ones((G, 1, 1))

    def rates(self, t, Y, Yd_guess):
        return -self.lam[:, None] * Y + self.drive(t)[:, None]
