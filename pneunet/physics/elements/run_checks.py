"""Warnings about a whole run, once per element: a law used outside the range it holds in
(a laminar tube at Re > 2000) or an element that never did its job (a check valve held shut
by a reverse pressure all run).  Like the muscle's "cannot lift" warning they are
``warning:`` lines of the CLI (``-q`` silences them), naming the element's line, the time
and the quantity; the engine reads the signals of every family with ``checks_run`` at the
end of each transient (:func:`pneunet.engine.solution.build_solution`)."""
from __future__ import annotations

import warnings

import numpy as np

from ...common.solver_messages import SolverWarning

#: a laminar law holds below this Reynolds number
RE_LAMINAR = 2000.0
#: a check valve opened less than this fraction all run "never opened"
NEVER_OPEN = 1e-3


class RangeWarning(SolverWarning):
    """An element that ran outside its law's range, or never did its job, in a run."""


def laminar_reynolds(specs, t, re) -> None:
    """Warn for each instance whose Reynolds number ``re`` (n_t, n) exceeded RE_LAMINAR."""
    for k in np.flatnonzero(re.max(axis=0) > RE_LAMINAR):
        i = int(np.argmax(re[:, k] > RE_LAMINAR))
        warnings.warn(RangeWarning(
            f"{specs[k].where}: Reynolds number {re[i, k]:.4g} at t = {t[i]:.4g} s (up to "
            f"{re[:, k].max():.4g}): the flow is not laminar (Re < {RE_LAMINAR:g}), so the "
            "laminar law gives too much flow from then on; a tube (Darcy–Weisbach, any Re) "
            "holds there, and a turbulent loss is an orifice with Cd = 1/√K"), stacklevel=3)


def check_valve_shut(specs, t, dp, opening, pcrack) -> None:
    """Warn for each check valve that never opened while its outlet stood above its inlet
    (``dp`` = p_a − p_b (n_t, n), kPa): it may be wired backwards."""
    for k in np.flatnonzero(opening.max(axis=0) < NEVER_OPEN):
        i = int(np.argmin(dp[:, k]))
        if dp[i, k] >= 0.0:
            continue  # forward-biased below its cracking pressure: a relief that had no need
        warnings.warn(RangeWarning(
            f"{specs[k].where}: the check valve never opened (p_a − p_b at most "
            f"{dp[:, k].max():.4g} kPa, below its cracking pressure {pcrack[k]:.4g} kPa) and was "
            f"reverse-biased by {-dp[i, k]:.4g} kPa at t = {t[i]:.4g} s: it passes flow from "
            f"its first node {specs[k].nodes[0]!r} to {specs[k].nodes[1]!r}; if flow should "
            "pass the other way, swap its nodes"), stacklevel=3)
