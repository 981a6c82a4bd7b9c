"""Linear stability of a steady state: will the circuit settle there?

Around a steady state y* (ẏ = 0) the DAE F(t, y, ẏ) = 0 linearises to
J·δy + M·δẏ = 0 with J = ∂F/∂y (mg/(s·kPa)) and M = ∂F/∂ẏ (mg/kPa, the
capacitances; zero rows at nodes without volume).  Its modes δy = v·e^{λt} solve
the generalised eigenproblem J·v = λ·(−M)·v: algebraic nodes give infinite
eigenvalues, which are dropped; the finite ones are the decay (Re λ < 0) or growth
(Re λ > 0) rates, 1/s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.reprs import Summarized

#: unknowns above which no eigenvalues are computed (dense QZ costs ~n³: ~0.1 s at 200)
EIGEN_LIMIT = 200


@dataclass(frozen=True, repr=False)
class Stability(Summarized):
    """Eigenvalues (1/s, sorted by decreasing real part) of a linearised steady state.

    ``stable``: every mode decays; None when not computed (``reason`` says why);
    ``marginal``: the slowest mode neither grows nor decays (a closed volume).
    """

    eigenvalues: tuple = ()
    stable: bool | None = None
    marginal: bool = False
    reason: str = ""

    def _summary(self):
        verdict = ("not computed" if self.stable is None else "stable" if self.stable else
                   "marginal" if self.marginal else "UNSTABLE")
        rows = [("modes", str(len(self.eigenvalues)))]
        if self.slowest is not None:
            rows.append(("slowest eigenvalue", f"{_format(self.slowest)} 1/s"))
        return verdict, rows, ".describe(), .eigenvalues, .slowest"

    @property
    def slowest(self) -> complex | None:
        """The eigenvalue of largest real part (the mode that decides), 1/s."""
        return self.eigenvalues[0] if self.eigenvalues else None

    def describe(self) -> str:
        """One sentence: stable or not, the deciding eigenvalue, what it means."""
        if self.stable is None:
            return f"stability not computed ({self.reason})"
        if not self.eigenvalues:
            return "stable (no storage: the circuit is at this state instantly)"
        lam = self.slowest
        value = _format(lam)
        if self.stable:
            return (f"stable: the slowest mode decays at {value} 1/s (time constant "
                    f"{-1 / lam.real:.3g} s)")
        if self.marginal:
            return (f"marginal: a mode neither decays nor grows ({value} 1/s); the state "
                    "depends on where the circuit starts (a closed volume?)")
        how = ("it oscillates around it with a growing amplitude" if abs(lam.imag) > 0 else
               "it moves away from it (a relaxation oscillator or a switch)")
        return (f"UNSTABLE: a mode grows at {value} 1/s; the circuit will not settle at this "
                f"operating point: {how} (run a transient)")


def _format(lam: complex) -> str:
    if abs(lam.imag) <= 1e-12 * max(abs(lam.real), 1.0):
        return f"{lam.real:+.3g}"
    return f"{lam.real:+.3g} ± {abs(lam.imag):.3g}j"


def linear_stability(dae, t: float, y: np.ndarray) -> Stability:
    """:class:`Stability` of the steady state ``y`` (kPa) of ``dae`` at time ``t`` (s)."""
    from scipy.linalg import eig

    if dae.n > EIGEN_LIMIT:
        return Stability(reason=f"{dae.n} unknowns, over EIGEN_LIMIT = {EIGEN_LIMIT}")
    zeros = np.zeros(dae.n)
    stiffness = dae.jacobian(t, y, zeros, 0.0).toarray()
    mass = dae.mass_matrix(t, y).toarray()
    alpha, beta = eig(stiffness, -mass, right=False, homogeneous_eigvals=True)
    finite = np.abs(beta) > 1e-12 * np.maximum(np.abs(alpha), 1.0)
    lam = alpha[finite] / beta[finite]
    lam = tuple(complex(v) for v in lam[np.argsort(-lam.real)])
    scale = max((abs(v) for v in lam), default=1.0)
    tol = 1e-9 * scale
    stable = all(v.real < -tol for v in lam)
    return Stability(lam, stable, marginal=not stable and lam[0].real <= tol)
