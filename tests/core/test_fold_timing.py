"""Branch jumps at the fold's own time.

pneunet's valve output is an algebraic node: the oscillator's cycle ends each branch at
a fold and jumps to the other one.  The integrator stops where the fold indicator falls
to 1 % of its value; the jump must still happen at the fold, where a vanishing volume at
the output (the limit pneunet models) would make it.  Checked against the paper's
equations integrated with shrinking stubs by scipy (tests/reference_oscillator.py), and
against pneunet's own event put at the fold (indicator threshold 1e-5, where the time
left is ~10⁻⁹ s).
"""
import numpy as np
import pytest

from pneunet.design.circuits import oscillator


def _period(sol, settle):
    """Mean period of the tank's rising mid-level crossings after ``settle`` s."""
    t, p = np.asarray(sol.t), np.asarray(sol["p_tank"])
    late = t > settle
    mid = 0.5 * (p[late].min() + p[late].max())
    i = np.flatnonzero((p[:-1] < mid) & (p[1:] >= mid) & late[:-1])
    crossings = t[i] + (mid - p[i]) / (p[i + 1] - p[i]) * (t[i + 1] - t[i])
    return float(np.mean(np.diff(crossings)))


def test_paper_oscillator_period_is_the_vanishing_stub_limit():
    """The reference's period converges as its stub shrinks (1e-5 → 1e-6 mL moves it by
    7e-5 s); pneunet, with the same 1 kPa² flow band, lands within 5e-5 s of the 1e-6 mL
    value.  Jumps made 1 ms after the fold gave 4e-4 s."""
    from reference_oscillator import limit_cycle  # tests/ is on pytest's sys.path

    ref_5, ref_6 = limit_cycle(v_stub=1e-5)[0], limit_cycle(v_stub=1e-6)[0]
    assert abs(ref_5 - ref_6) < 1e-4  # the premise: the reference has converged
    circuit = oscillator()
    circuit.options = circuit.options.replace(rtol=1e-8, atol=1e-8, flow_band=1.0)
    period = _period(circuit.tran(24.0, t_step=1e-3), settle=8.0)
    assert period == pytest.approx(ref_6, abs=5e-5)


@pytest.mark.parametrize("params", [
    {"Rout": 1.008, "Rvent": 3.614, "V": 53.871},  # vent fold at a slow turning point
    {"Rout": 1.132, "Rvent": 3.0, "V": 50.0},
    {"Rout": 1.5, "Rvent": 2.2, "V": 120.0},
])
def test_jumps_land_where_the_event_at_the_fold_puts_them(params):
    """Each jump of a 10 s run moves by less than 1e-5 s against the one before it,
    compared with the run whose event is at the fold (errors add up from jump to jump:
    the old extrapolated push landed 7e-5 to 1e-3 s late each time; now 6e-6 s at the
    slow fold, 1e-7 s at the others)."""
    def jump_times(threshold):
        circuit = oscillator(params)
        circuit.options = circuit.options.replace(rtol=1e-10, atol=1e-10,
                                                  fold_threshold=threshold)
        return np.asarray(circuit.tran(10.0, t_step=0.01).jumps)

    default, at_fold = jump_times(1e-2), jump_times(1e-5)
    assert len(default) == len(at_fold) >= 4
    assert np.max(np.abs(np.diff(default - at_fold))) < 1e-5


def test_the_array_path_follows_the_branch_as_the_float_path_does(monkeypatch):
    """A block of several algebraic nodes follows the branch by dense (or sparse) Newton
    steps; on the oscillator's one node, forced onto that path, every jump lands where
    the float path puts it (within 1e-9 s: the same steps, other rounding)."""
    from pneunet.engine.solvers import folds

    params = {"Rout": 1.008, "Rvent": 3.614, "V": 53.871}

    def jump_times():
        circuit = oscillator(params)
        circuit.options = circuit.options.replace(rtol=1e-10, atol=1e-10)
        return np.asarray(circuit.tran(6.0, t_step=0.01).jumps)

    floats = jump_times()
    init = folds.FoldMonitor.__init__

    def arrays_only(self, dae, threshold):
        init(self, dae, threshold)
        self._one = None

    monkeypatch.setattr(folds.FoldMonitor, "__init__", arrays_only)
    arrays = jump_times()
    assert len(arrays) == len(floats) >= 6
    assert np.max(np.abs(arrays - floats)) < 1e-9



LINE_INTO_TANK = """* the paper's oscillator, its tank behind a line of {r} kPa*s/mg
.options ambient=96kPa rtol={rtol} atol={rtol}
PH supply 496kPa
X1 supply out line axi_0p6mm
Rout out line 1.132kPa*s/mg
Rline line tank {r}kPa*s/mg
Vtank tank 200mL
Rvent line atm 3kPa*s/mg
"""


def test_no_jump_lands_on_a_mirror_root_below_zero_pressure():
    """Behind a 2 kPa·s/mg line the vent branch cannot be left by any short push; the
    jump's pushes grew to 111 s and landed on the laws' mirror root, tank at −201 kPa,
    and the run 'succeeded' to 115 s of a 20 s request.  Now a located SolverError (or,
    should the jump learn to cross there, a run with positive pressures to its end)."""
    from pneunet import SolverError
    from pneunet.netlist import parse_netlist

    circuit = parse_netlist(LINE_INTO_TANK.format(r=2, rtol=1e-6)).circuit
    try:
        sol = circuit.tran(20.5, t_step=0.01)
    except SolverError as err:
        assert "jump" in str(err)
        return
    assert sol.t[-1] == pytest.approx(20.5) and min(np.min(sol[s]) for s in sol.signals
                                                     if s.startswith("p_")) > 0


@pytest.mark.parametrize("r_vent, oscillates", [(3.177, True), (3.193, False)])
def test_near_the_end_of_oscillation_the_branch_goes_on_as_the_equations_say(r_vent,
                                                                            oscillates):
    """The 44.2 mL oscillator stops oscillating between R_vent 3.177 and 3.185: its tank
    falls towards the valve's fold and, just short of it, settles at 178.8 kPa, with the
    fold indicator κ stalled at 0.3 % of its reference (a near-fold).  The jump used to
    push the state on linearly until it landed away from there, 0.5-1.1 s later on each
    cycle: it oscillated on past the end, skipping time.  The stand-alone equations
    (tests/traces/standalone.py: a 1e-4 mL stub at the output, scipy's Radau) decide."""
    from traces.standalone import oscillator_record

    values = {"Rout": 0.9081, "Rvent": r_vent, "V": 44.22}
    ref = oscillator_record(30.0, dt=0.05, noise=0.0, signals=("tank",), **values)
    late = ref["time_s"].to_numpy() >= 20.0
    swing = np.ptp(ref["p_tank_kPa"].to_numpy()[late])
    assert (swing > 50.0) == oscillates  # the premise: which side of the end it is
    circuit = oscillator(values)
    circuit.options = circuit.options.replace(flow_band=1.0)
    sol = circuit.tran(30.0, t_step=0.05)
    assert np.diff(sol.t).max() <= 0.05 + 1e-9  # no time skipped
    p = np.interp(ref["time_s"], sol.t, sol["p_tank"])
    if oscillates:
        assert np.ptp(p[late]) == pytest.approx(swing, rel=0.02)
    else:
        assert np.abs(p[late] - ref["p_tank_kPa"].to_numpy()[late]).max() < 0.2
