"""Consistent initial states where the guessed branch does not exist.

The oscillator's valve output (no volume) at a tank pressure where its open branch has
folded away: the only root is the closed valve, the output at the tank's pressure, where
R_out's quadrature law makes the flow go as the square root of the pressure difference.
A Newton step there lands on the mirror point; every trial value of R_out must still
settle (a fit whose trial points fail at random R_out is trapped)."""
import numpy as np
import pytest

from pneunet.design.circuits import oscillator
from pneunet.engine.assembly import CircuitDAE
from pneunet.engine.single_rate import consistent_state

TANK_KPA = 315.388


def _start(Rout, out_guess=453.354):
    c = oscillator({"Rout": Rout, "Rvent": 2.93, "V": 41.09})
    c.initial["tank"], c.initial["out"] = TANK_KPA, out_guess
    dae = CircuitDAE(c)
    y, _ = consistent_state(dae, 0.0, dae.initial_state(0.0))
    return dict(zip(dae.node_names, y))


def _open_branch(Rout):
    """The valve output's pressure on the open branch from an independent root search:
    a sign change of the output node's flow balance between 350 kPa and the supply's
    496 (None when it has none: folded away)."""
    c = oscillator({"Rout": Rout, "Rvent": 2.93, "V": 41.09})
    dae = CircuitDAE(c)
    zeros = np.zeros(dae.n)
    i = dae.node_names.index("out")
    grid = np.linspace(350.0, 495.0, 581)
    f = []
    for p in grid:
        y = dae.initial_state(0.0)
        y[dae.node_names.index("tank")], y[i] = TANK_KPA, p
        f.append(dae.evaluate(0.0, y, zeros)[0][i])
    f = np.array(f)
    sign = np.nonzero(np.diff(np.sign(f)))[0]
    return None if not len(sign) else float(grid[sign[-1]])


@pytest.mark.parametrize("Rout", np.round(np.linspace(0.95, 1.05, 11), 3))
def test_a_folded_away_branch_settles_on_the_closed_valve(Rout):
    assert _open_branch(Rout) is None  # the premise: no open branch at this tank pressure
    y = _start(Rout)
    assert y["out"] == pytest.approx(TANK_KPA, abs=1e-3)


@pytest.mark.parametrize("Rout", [1.07, 1.132, 1.2])
def test_an_existing_branch_near_the_guess_is_kept(Rout):
    open_at = _open_branch(Rout)
    assert open_at is not None
    assert _start(Rout)["out"] == pytest.approx(open_at, abs=0.5)
