"""The multirate transient (issue 18): partition, batched Radau cells, hub coupling.

Every check compares with something computed independently of the multirate engine:
a hand-written cell ODE integrated by scipy's Radau, the single-rate IDA path at tight
tolerances, a mass balance, or single-oscillator runs.
"""
from __future__ import annotations

import functools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid, solve_ivp

from pneunet import Circuit
from pneunet.common.errors import NetlistError, ParameterError
from pneunet.netlist import parse_netlist
from pneunet.physics.waveforms import Pulse

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_scaling  # noqa: E402

AMB = 101.325


def at(sol, ref, node):
    """``ref``'s pressure of ``node`` on ``sol``'s time points (single-rate runs store
    the output grid and the source corners, so every grid point is one of theirs)."""
    return np.interp(sol.t, ref.t, ref.pressure(node))


def upward_crossings(t, x, level):
    i = np.flatnonzero((x[:-1] < level) & (x[1:] >= level))
    return t[i] + (level - x[i]) / (x[i + 1] - x[i]) * (t[i + 1] - t[i])


def periods(t, p, settle=10.0):
    late = t > settle
    level = 0.5 * (p[late].min() + p[late].max())
    return np.diff(upward_crossings(t[late], p[late], level))


# -- 1. batched Radau on independent cells against a hand-written reference ----------------
N_RC, T_RC, RTOL_RC = 20, 1.6, 1e-6
K = np.arange(N_RC)
DELAY, RISE, WIDTH, FALL = 0.1 + 0.037 * K, 0.02 + 0.001 * K, 0.5 - 0.01 * K, 0.03 + 0 * K
R_IN, R_OUT, VOL = 0.5 + 0.1 * K, 1.0 + 0.05 * K, 5.0 + K       # kPa·s/mg, kPa·s/mg, mL
P_HIGH = 400.0


def rc_circuit(method="multirate"):
    """N_RC cells on ideal sources: PULSE → resistor → volume → resistor → atm."""
    c = Circuit("rc cells", rtol=RTOL_RC, atol=RTOL_RC, ambient=AMB, method=method)
    for k in range(N_RC):
        c.pressure_source(f"PS{k}", f"s{k}", Pulse(AMB, P_HIGH, delay=DELAY[k], rise=RISE[k],
                                                 width=WIDTH[k], fall=FALL[k]))
        c.resistor(f"RA{k}", f"s{k}", f"n{k}", R=R_IN[k])
        c.volume(f"V{k}", f"n{k}", V=f"{VOL[k]}mL")
        c.resistor(f"RB{k}", f"n{k}", "atm", R=R_OUT[k])
    return c


def rc_corners():
    """Each cell's PULSE corners (s), (N_RC, 4)."""
    return np.column_stack([DELAY, DELAY + RISE, DELAY + RISE + WIDTH,
                            DELAY + RISE + WIDTH + FALL])


def rc_reference(times, options):
    """The cells' pressures on ``times``: C·ṗ = sr(ps² − p²)/R_in − sr(p² − p_amb²)/R_out,
    sr(d) = d/(d² + ε²)^¼ (docs/model.md), integrated by scipy's Radau at 1e-10,
    restarted at every corner of every cell."""
    eps = options.flow_band
    cap = options.gas_model.capacitance(VOL, options.temperature)       # mg/kPa

    def source(t):
        up = (t - DELAY) / RISE
        down = (DELAY + RISE + WIDTH + FALL - t) / FALL
        return AMB + (P_HIGH - AMB) * np.clip(np.minimum(up, down), 0.0, 1.0)

    def sr(d):
        return d / (d * d + eps * eps) ** 0.25

    def dsr(d):
        s = d * d + eps * eps
        return (0.5 * d * d + eps * eps) / (s * s ** 0.25)

    def f(t, p):
        ps = source(t)
        return (sr(ps * ps - p * p) / R_IN - sr(p * p - AMB * AMB) / R_OUT) / cap

    def jac(t, p):
        ps = source(t)
        return np.diag((-2 * p * dsr(ps * ps - p * p) / R_IN
                        - 2 * p * dsr(p * p - AMB * AMB) / R_OUT) / cap)

    stops = np.unique(np.concatenate([[times[0], times[-1]], rc_corners().ravel()]))
    out = np.empty((times.size, N_RC))
    out[0] = y = np.full(N_RC, AMB)
    for a, b in zip(stops[:-1], stops[1:]):
        r = solve_ivp(f, (a, b), y, method="Radau", rtol=1e-10, atol=1e-10, jac=jac,
                      dense_output=True)
        assert r.success
        y = r.y[:, -1]
        inside = (times > a) & (times <= b)
        out[inside] = r.sol(times[inside]).T
    return out


@pytest.fixture(scope="module")
def rc_runs():
    circuit = rc_circuit()
    sol = circuit.tran(T_RC, t_step=1e-3)
    got = np.column_stack([sol.pressure(f"n{k}") for k in range(N_RC)])
    return sol, got, rc_reference(sol.t, circuit.options)


def tolerance_units(got, ref, rtol=RTOL_RC, atol=RTOL_RC):
    return np.abs(got - ref) / (rtol * np.abs(ref) + atol)


def test_batched_radau_cells_match_an_independent_reference(rc_runs):
    sol, got, ref = rc_runs
    assert sol.stats["method"] == "multirate"
    assert sol.stats["cells"] == N_RC and sol.stats["groups"] == 1
    assert sol.stats["hub_nodes"] == 0 and sol.stats["cells_alone"] == 0
    assert ref.max() > 300.0                           # every cell was charged
    # IDA's local error test in IDA's norm: the global error stays within a few tolerances
    # (single-rate IDA at the same rtol is off by 7–90 of them on this circuit)
    assert tolerance_units(got, ref).max() < 5.0


def test_every_cell_lands_on_its_own_source_corners(rc_runs):
    sol, got, ref = rc_runs
    corners = rc_corners()
    rows = np.array([[np.argmin(np.abs(sol.t - c)) for c in cell] for cell in corners])
    assert np.abs(sol.t[rows] - corners).max() < 1e-12   # the corners are output points
    at_corners = tolerance_units(got[rows, K[:, None]], ref[rows, K[:, None]])
    # a step across a corner (e.g. one cell's corners used for all, or none) is off by
    # thousands of tolerances there; landing on it keeps the kink exact
    assert at_corners.max() < 5.0


# -- 2. cells coupled through a hub, each with its own schedule ------------------------------
def independent_cells(n, rtol, method, seed=3):
    """bench_scaling.build(n) with every cell's PULSE delay drawn on its own."""
    delays = 0.2 + np.random.default_rng(seed).uniform(0.0, 3.0, n)
    return bench_scaling.build(n, rtol, rtol, delays=delays, method=method)


def test_cells_coupled_through_the_supply_line_match_single_rate():
    n = 20
    ref = independent_cells(n, 1e-8, "single").tran(4.0, t_step=0.01)
    sol = independent_cells(n, 1e-6, "multirate").tran(4.0, t_step=0.01)
    stats = sol.stats
    assert stats["method"] == "multirate" and stats["cells"] == n and stats["hub_nodes"] == 1
    assert stats["windows"] >= 1 and stats["sweeps"] >= stats["windows"]
    assert np.isfinite(stats["coupling_defect"])
    line = np.abs(sol.pressure("line") - at(sol, ref, "line")).max()
    acts = max(np.abs(sol.pressure(f"act{k}") - at(sol, ref, f"act{k}")).max() for k in range(n))
    assert line <= 0.1 and acts <= 0.1
    # the cells really switch and draw from the line
    assert max(np.ptp(ref.pressure(f"act{k}")) for k in range(n)) > 100.0
    assert np.ptp(ref.pressure("line")) > 1.0


# -- 3. mass through the hub ----------------------------------------------------------------
N_CLOSED = 20
V_HUB = 2000.0
V_ACT = 20.0 + 3.0 * np.arange(N_CLOSED)


def closed_network(method="multirate", rtol=1e-6, leak=True):
    """A charged hub volume feeding closed actuator volumes through valves (no supply,
    no vents); the valves' control lines are pinned PULSEs through RC filters.
    ``leak``: a 1e6 kPa·s/mg leak from the hub to atm (~1e-7 of the gas in 3 s)."""
    c = Circuit("closed hub", rtol=rtol, atol=rtol, ambient=AMB, method=method)
    c.volume("VH", "hub", V=f"{V_HUB}mL", p0=400.0)
    if leak:
        c.resistor("RL", "hub", "atm", R=1e6)
    for k in range(N_CLOSED):
        c.pressure_source(f"PC{k}", f"c{k}", Pulse(AMB, 400.0, delay=0.1 + 0.07 * k,
                                                  rise=0.05, fall=0.05, width=0.6))
        c.resistor(f"RC{k}", f"c{k}", f"ctl{k}", R=5.0)
        c.volume(f"VC{k}", f"ctl{k}", V="10mL")
        c.valve(f"X{k}", "hub", f"act{k}", f"ctl{k}", model="axi")
        c.volume(f"VA{k}", f"act{k}", V=f"{V_ACT[k]}mL")
    return c


def gas_ledger(circuit, sol):
    """Gas in the hub and actuators plus what leaked (mg), on sol.t."""
    o = circuit.options
    cap = lambda v: o.gas_model.capacitance(v, o.temperature)  # noqa: E731
    mass = cap(V_HUB) * sol.pressure("hub")
    mass = mass + sum(cap(V_ACT[k]) * sol.pressure(f"act{k}") for k in range(N_CLOSED))
    leaked = cumulative_trapezoid(sol.signals["mdot_RL"], sol.t, initial=0.0)
    return mass + leaked


@pytest.fixture(scope="module")
def closed_run():
    circuit = closed_network()
    sol = circuit.tran(3.0, t_step=0.01)
    return sol, gas_ledger(circuit, sol), circuit.options


def test_the_hub_gives_the_cells_their_gas(closed_run):
    sol, ledger, o = closed_run
    assert sol.stats["method"] == "multirate" and sol.stats["hub_nodes"] == 1
    assert sol.stats["windows"] >= 1
    # the actuators took ~2 % of the hub's gas (~260 mg): a draw not applied to the hub,
    # or applied twice, breaks the balance by that much
    assert 400.0 - sol.pressure("hub")[-1] > 5.0
    gained = sum(o.gas_model.capacitance(V_ACT[k], o.temperature)
                 * (sol.pressure(f"act{k}")[-1] - AMB) for k in range(N_CLOSED))
    assert gained > 100.0
    assert abs(ledger[-1] - ledger[0]) <= 1e-5 * ledger[0]


# The hub integrates a piecewise cubic through the masses the cells drew, its steps landing
# on every knot (the samples, output times among them), so its integral of the draw is
# exact: the ledger balances to the tolerance (rtol 1e-6) at every output point, where a
# draw lost or counted twice would be off by ~2e-2 and a hub stepping across the knots by
# ~6e-6.
def test_mass_through_the_hub_is_conserved_to_the_tolerance_at_the_end(closed_run):
    _, ledger, _ = closed_run
    assert abs(ledger[-1] - ledger[0]) <= 1e-6 * ledger[0]


def test_mass_through_the_hub_is_conserved_at_every_output_point(closed_run):
    _, ledger, _ = closed_run
    assert np.abs(ledger - ledger[0]).max() <= 1e-6 * ledger[0]


def test_every_accepted_window_ends_with_a_hub_on_the_cells_draw_alone(monkeypatch):
    """Only a hub run without the draw's slope correction may be accepted (it loses what
    the cells drew); near convergence a sweep runs that one alone, so there are fewer hub
    runs than sweeps plus windows (the slope's run and a rerun for every window)."""
    from pneunet.engine import multirate

    runs = []  # (window start, window end, slope correction all zero)
    advance = multirate._Hub.advance

    def recorded(self, S, land, drawn, seen, slope, opts, count):
        runs.append((float(S[0]), float(S[-1]), not np.any(slope)))
        return advance(self, S, land, drawn, seen, slope, opts, count)

    monkeypatch.setattr(multirate._Hub, "advance", recorded)
    sol = closed_network().tran(3.0, t_step=0.01)
    starts = {start for start, _, _ in runs}
    accepted = [max(i for i, r in enumerate(runs) if r[:2] == (start, end))
                for start, end, _ in runs if end in starts or end == 3.0]
    assert len(set(accepted)) == sol.stats["windows"]
    assert all(runs[i][2] for i in accepted)
    assert any(not r[2] for r in runs)                  # the slope is used on the way
    assert len(runs) < sol.stats["sweeps"] + sol.stats["windows"]


def test_a_hub_that_is_only_a_volume_can_be_integrated():
    circuit = closed_network(leak=False)
    sol = circuit.tran(0.5, t_step=0.01)
    assert sol.stats["method"] == "multirate"


def stiff_hub(method, rtol=1e-5):
    """16 small cells tied tightly (R = 1) to a charged hub volume that one cell vents:
    the cells follow the hub within milliseconds, so their draw depends strongly on
    the hub pressure (draw slope ~4000 mg/(s·kPa) against a 12 mg/kPa hub)."""
    c = Circuit("stiff hub", rtol=rtol, atol=rtol, ambient=AMB, method=method)
    c.volume("VH", "hub", V="1000mL", p0=400.0)
    c.resistor("RL", "hub", "atm", R=1e6)
    for k in range(16):
        c.resistor(f"R{k}", "hub", f"a{k}", R=1.0)
        c.volume(f"V{k}", f"a{k}", V="10mL")
    c.resistor("RV", "a0", "atm", R=3.0)
    return c


def test_a_stiffly_coupled_hub_keeps_its_accuracy():
    ref = stiff_hub("single", 1e-9).tran(1.0, t_step=0.01)
    sol = stiff_hub("multirate").tran(1.0, t_step=0.01)
    assert sol.stats["method"] == "multirate" and sol.stats["hub_nodes"] == 1
    for node in ("hub", "a0", "a5"):
        assert np.abs(sol.pressure(node) - at(sol, ref, node)).max() <= 0.1


def test_anderson_mixing_solves_a_linear_coupling_with_a_low_rank_error_in_few_sweeps():
    """A hub map g(x) = x* + E·(x − x*) whose error operator E has rank 2 and eigenvalues 0.9 and 0.6:
    plain iteration gains 10 % per sweep; Anderson mixing of 3 earlier sweeps (GMRES
    on the residuals) reaches x* to round-off by the fourth sweep."""
    from types import SimpleNamespace

    from pneunet.engine.multirate import _Anderson

    rng = np.random.default_rng(5)
    m = 17                                    # samples of one hub node: values and slopes
    fixed = np.concatenate([400 + rng.normal(0, 5, m), rng.normal(0, 20, m)])
    u = np.linalg.qr(rng.normal(size=(2 * m, 2)))[0].T    # eigenvalues 0.9 and 0.6
    error_map = 0.9 * np.outer(u[0], u[0]) + 0.6 * np.outer(u[1], u[1])

    def hub(x):
        return fixed + error_map @ (x - fixed)

    mixer = _Anderson(SimpleNamespace(rtol=1e-5, atol=1e-5))
    x = fixed + rng.normal(0, 50, 2 * m)
    plain = x.copy()
    for _ in range(4):
        g = hub(x)
        value, slope = mixer.next((x[:m], x[m:]), (g[:m], g[m:]))
        x = np.concatenate([value, slope])
        plain = hub(plain)
    assert np.abs(x - fixed).max() <= 1e-8 * np.abs(fixed).max()
    assert np.abs(plain - fixed).max() > 1.0     # what the sweeps would be without it


def test_the_secant_slope_is_the_least_squares_ratio_of_draw_to_pressure_changes():
    """Two sweeps of a window on three hub nodes: the cells' draw grows by 40 and by
    7 mg/(s·kPa) (plus a pressure-independent part and noise) where the hub pressure
    changed, and not at all on a node whose pressure did not change; a draw that falls
    with the pressure is no sensitivity to correct with."""
    from pneunet.engine.multirate import _secant_slope

    rng = np.random.default_rng(3)
    seen = 480 + rng.normal(0, 2, (33, 3))
    moved = seen + np.column_stack([rng.normal(0, 0.5, 33), rng.normal(0, 0.5, 33), np.zeros(33)])
    base = rng.uniform(100, 200, (33, 3))
    noise = rng.normal(0, 1e-3, (33, 3))
    drawn = base + np.array([40.0, -7.0, 3.0]) * (seen - 480)
    drawn_moved = base + np.array([40.0, -7.0, 3.0]) * (moved - 480) + noise
    slope = _secant_slope((seen, drawn), (moved, drawn_moved))
    dp = moved[:, 0] - seen[:, 0]
    expected = np.sum((drawn_moved[:, 0] - drawn[:, 0]) * dp) / np.sum(dp * dp)
    assert slope[0] == pytest.approx(expected, rel=1e-12)
    assert slope[0] == pytest.approx(40.0, rel=1e-3)
    assert np.isnan(slope[1]) and np.isnan(slope[2])


# -- 4. independent oscillators: folds inside cells -----------------------------------------
OSC_VOLUMES = [100 + 20 * i for i in range(6)]   # periods 3.0–5.9 s
OSCILLATORS = """* six oscillators of different tanks on one ideal supply
.options ambient=96kPa method=multirate
.param Rf=0.566 Rout={2*Rf} Rvent=3
.subckt OSC supply tank V=200
X1 supply out tank axi_0p6mm
Rout out tank {Rout}kPa*s/mg
Vtank tank {V}mL
Rvent tank atm {Rvent}kPa*s/mg
.ends OSC
PH supply 496kPa
Xosc[0:5] supply tank[0:5] OSC V={100 + 20*index}
.tran 10ms 30s
"""


def test_independent_oscillators_keep_the_periods_of_single_runs(monkeypatch):
    from pneunet.engine import multirate

    monkeypatch.setattr(multirate, "PARALLEL_MIN_CELLS", 2)   # the two-process path
    sol = parse_netlist(OSCILLATORS).circuit.tran(30.0, t_step=0.01)
    assert sol.stats["method"] == "multirate"
    assert sol.stats["cells"] == 6 and sol.stats["cells_alone"] == 6
    assert sol.stats["branch_jumps"] > 6 * 5                # fold jumps inside the cells
    single = (ROOT / "netlists" / "oscillator.pn").read_text()
    assert "Vtank tank 200mL" in single
    means = []
    for i, volume in enumerate(OSC_VOLUMES):
        circuit = parse_netlist(single.replace("Vtank tank 200mL", f"Vtank tank {volume}mL")).circuit
        circuit.options = circuit.options.replace(method="single")
        ref = circuit.tran(30.0, t_step=0.01)
        expected = periods(ref.t, ref.pressure("tank"), settle=8.0)
        got = periods(sol.t, sol.pressure(f"tank[{i}]"), settle=8.0)
        assert got.size == expected.size >= 2
        assert abs(got.mean() / expected.mean() - 1.0) <= 1e-3
        means.append(got.mean())
    assert np.all(np.diff(means) > 0.3)     # each tank's own period, in the netlist's order


# -- 5. method selection and errors ---------------------------------------------------------
def test_an_unknown_method_is_an_error_naming_the_option():
    with pytest.raises(ParameterError, match=r"method.*'bogus'"):
        Circuit("t", method="bogus")
    with pytest.raises(NetlistError, match=r":2:1: unknown method 'bogus'"):
        parse_netlist("* t\n.options method=bogus\nPS s 200kPa\nR1 s a 1kPa*s/mg\nV1 a 10mL\n")


def line_without_volume(method="multirate"):
    lines = ["* cells on a line without a volume", f".options method={method}",
             "PS sup 496kPa", "RS sup line 0.01kPa*s/mg"]
    for k in range(20):
        lines += [f"R{k} line a{k} 1kPa*s/mg", f"V{k} a{k} 10mL", f"RV{k} a{k} atm 3kPa*s/mg"]
    return "\n".join(lines + [".tran 10ms 1s"]) + "\n"


def cells_without_volume():
    lines = ["* cells without a volume on a line", ".options method=multirate",
             "PS sup 496kPa", "RS sup line 0.01kPa*s/mg", "VL line 100mL"]
    for k in range(20):
        lines += [f"R{k} line a{k} 1kPa*s/mg", f"RV{k} a{k} atm 3kPa*s/mg"]
    return "\n".join(lines + [".tran 10ms 1s"]) + "\n"


def test_multirate_on_a_circuit_it_cannot_split_is_a_parameter_error():
    with pytest.raises(ParameterError, match="cannot split this circuit: hub node line has no volume"):
        parse_netlist(line_without_volume()).circuit.tran(0.1)
    with pytest.raises(ParameterError, match="node a0 has no volume"):
        parse_netlist(cells_without_volume()).circuit.tran(0.1)
    # the same circuit runs single-rate
    sol = parse_netlist(line_without_volume("single")).circuit.tran(0.1)
    assert "windows" not in sol.stats and np.isfinite(sol.pressure("line")).all()


@pytest.mark.parametrize("netlist, message", [
    (line_without_volume(), "hub node line has no volume"),
    (cells_without_volume(), "node a0 has no volume"),
], ids=["hub-without-volume", "cell-without-volume"])
def test_cli_says_once_why_multirate_cannot_split_and_exits_2(tmp_path, netlist, message):
    deck = tmp_path / "deck.pn"
    deck.write_text(netlist)
    out = subprocess.run([sys.executable, "-m", "pneunet", "run", "--no-progress",
                          "-o", str(tmp_path / "out"), str(deck)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2
    text = out.stdout + out.stderr
    assert "Traceback" not in text
    assert text.count(message) == 1 and text.count("error:") == 1
    assert "method=multirate cannot split this circuit" in out.stderr
    assert "method=single" in out.stderr                     # the hint


def test_auto_keeps_small_circuits_single_rate():
    sol = rc_circuit(method="auto").tran(0.3, t_step=0.01)
    assert sol.stats.get("method") != "multirate" and "windows" not in sol.stats
    sol = rc_circuit(method="multirate").tran(0.3, t_step=0.01)
    assert sol.stats["method"] == "multirate"


def test_auto_partitions_many_cells_on_many_schedules():
    from pneunet.engine.simulate import transient_method
    from scaling_schedules import build

    def method(n, schedule):
        return transient_method(build(n, schedule, "auto", 1e-5), (0.0, 10.0))
    # cells switching each at its own time: multirate from 400 unknowns
    assert method(200, "independent").startswith(
        "multirate: 200 cells in 1 group(s), hub nodes line")
    assert method(199, "independent").startswith("single-rate IDA (399 unknowns")
    # cells switching together in 8 phase groups: one global step serves them all
    assert method(1000, "groups").startswith("single-rate IDA (2001 unknowns")
    forced = bench_scaling.build(40)
    forced.options = forced.options.replace(method="multirate")
    assert transient_method(forced).startswith("multirate: 40 cells")


# -- 6. partition ---------------------------------------------------------------------------
def test_partition_of_the_scaling_network():
    from pneunet.engine.partition import partition

    part = partition(bench_scaling.build(40))
    assert part.hub_nodes == ["line"]
    assert part.hub_elements == ["RS", "VL"] and part.hub_sources == ["PS"]
    assert len(part.cells) == 40 and part.groups == [list(range(40))]
    for k, cell in enumerate(part.cells):
        assert cell.nodes == [f"ctl{k}", f"act{k}"]
        assert cell.elements == [f"RC{k}", f"VC{k}", f"X{k}", f"VA{k}", f"RV{k}"]
        assert cell.hub_nodes == ["line"] and cell.sources == [f"PC{k}"]
    assert part.largest_cell == 2


def _cell_batch(monkeypatch, n):
    """The CellBatch of ``independent_cells(n)``'s cells, subsets evaluated from 1 cell."""
    from pneunet.engine import cells
    from pneunet.engine.cells import CellBatch
    from pneunet.engine.partition import partition

    monkeypatch.setattr(cells, "SUBSET_MIN_CELLS", 1)
    circuit = independent_cells(n, 1e-6, "multirate")
    part = partition(circuit)
    return CellBatch(circuit, [part.cells[i] for i in part.groups[0]])


def test_a_pass_over_some_cells_evaluates_them_as_the_whole_batch_does(monkeypatch):
    """The evaluator of a subset of cells (CellBatch.rows) gives, for those cells, the
    residuals, boundary outflows and Newton blocks the whole batch gives, at cell times
    that differ (each cell's own PULSE phase), with the boundary given by the driver."""
    n = 40
    batch = _cell_batch(monkeypatch, n)
    rng = np.random.default_rng(5)
    t = rng.uniform(0.0, 4.0, n)
    Y = rng.uniform(100.0, 480.0, (n, batch.k))
    Yd = rng.normal(0.0, 50.0, (n, batch.k))
    batch.boundary = lambda times: (470.0 + 5.0 * np.sin(times))[:, None]
    full = batch.evaluate(t, Y, Yd, jacobian=True)
    for rows in (np.array([0, 3, 17, 39]), np.arange(5, 25), np.array([11])):
        got, view = batch.rows(rows)
        assert np.array_equal(got, rows)
        part_eval = view.evaluate(t[rows], Y[rows], Yd[rows], jacobian=True)
        for whole, some in zip(full, part_eval):
            np.testing.assert_allclose(some, whole[rows], rtol=1e-13, atol=1e-12)
        res, out = view.evaluate(t[rows], Y[rows], Yd[rows])
        np.testing.assert_allclose(res, full[0][rows], rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(out, full[1][rows], rtol=1e-13, atol=1e-12)
    assert np.ptp(full[1]) > 0  # the cells really draw different flows from the line
    # most cells active: the whole batch is as cheap
    assert batch.rows(np.arange(n - 2)) == (None, None)


def test_three_stages_evaluated_at_once_equal_three_evaluations(monkeypatch):
    """CellBatch.evaluate_stages (every family once for a Radau pass's three stages)
    gives the residuals and boundary outflows of three evaluations, for the whole batch
    and for a subset, at stage times that differ per cell and stage (each cell's own
    PULSE phase and boundary pressure)."""
    n = 40
    batch = _cell_batch(monkeypatch, n)
    rng = np.random.default_rng(7)
    times = [rng.uniform(0.0, 4.0, n) for _ in range(3)]
    for t in times:
        t.flags.writeable = False
    Y = rng.uniform(100.0, 480.0, (3, n, batch.k))
    Yd = rng.normal(0.0, 50.0, (3, n, batch.k))
    batch.boundary = lambda t: (470.0 + 5.0 * np.sin(t))[:, None]
    one_by_one = [batch.evaluate(t, y, d) for t, y, d in zip(times, Y, Yd)]
    for _ in range(2):  # the second time from the inputs kept for these stage times
        res, out = batch.evaluate_stages(times, Y, Yd)
        for stage, (r, o) in enumerate(one_by_one):
            np.testing.assert_allclose(res[stage], r, rtol=1e-13, atol=1e-12)
            np.testing.assert_allclose(out[stage], o, rtol=1e-13, atol=1e-12)
    assert np.ptp(res[:, :, 0]) > 1.0 and np.ptp(out) > 0  # really different per stage
    later = [t + 0.37 for t in times]  # new stage times: nothing kept may be reused
    for t in later:
        t.flags.writeable = False
    res, out = batch.evaluate_stages(later, Y, Yd)
    for stage, t in enumerate(later):
        r, o = batch.evaluate(t, Y[stage], Yd[stage])
        np.testing.assert_allclose(res[stage], r, rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(out[stage], o, rtol=1e-13, atol=1e-12)
    rows = np.array([1, 4, 18, 30])
    _, view = batch.rows(rows)
    res, out = view.evaluate_stages([t[rows] for t in times], Y[:, rows], Yd[:, rows])
    for stage, (r, o) in enumerate(one_by_one):
        np.testing.assert_allclose(res[stage], r[rows], rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(out[stage], o[rows], rtol=1e-13, atol=1e-12)


def test_the_multirate_result_does_not_depend_on_passes_over_active_cells(monkeypatch):
    """Passes over the active cells alone give the result of passes over all cells."""
    from pneunet.engine import cells

    monkeypatch.setattr(cells, "SUBSET_MIN_CELLS", 1)
    subsets = []
    whole_batch_rows = cells.CellBatch.rows

    def counted(batch, active):
        rows, view = whole_batch_rows(batch, active)
        subsets.append(view is not None)
        return rows, view
    monkeypatch.setattr(cells.CellBatch, "rows", counted)
    sol = independent_cells(30, 1e-6, "multirate").tran(3.0, t_step=0.05)
    assert sum(subsets) > 100  # many passes really worked on a subset
    monkeypatch.setattr(cells, "SUBSET_FRACTION", 0.0)
    whole = independent_cells(30, 1e-6, "multirate").tran(3.0, t_step=0.05)
    # the same numbers up to the order of summation, whose round-off can tip a Newton
    # convergence test (a few steps of ~11,600): within the run's rtol (a wrong cell
    # mapping is off by far more)
    assert abs(sol.stats["steps"] - whole.stats["steps"]) <= 1e-3 * whole.stats["steps"]
    for node in ["line"] + [f"act{k}" for k in range(30)]:
        np.testing.assert_allclose(sol.pressure(node), whole.pressure(node), rtol=1e-6)


@functools.lru_cache(maxsize=1)
def manifolds_reference():
    """Single-rate IDA at rtol 1e-8 of the 40-cell manifolds, 3 s (shared by two tests)."""
    return two_by_two_manifolds("single", 1e-8, 40).tran(3.0, t_step=0.01)


def two_by_two_manifolds(method, rtol, n=40):
    """bench_scaling's cells on two supply lines and two exhaust lines of different
    resistances: cell k draws from supply k % 2 and vents into exhaust (k // 2) % 2
    (each exhaust vents to atm)."""
    from bench_scaling import AMBIENT, P_CTRL_HIGH, P_SUPPLY

    c = Circuit("manifolds", rtol=rtol, atol=rtol, ambient=AMBIENT, method=method)
    c.pressure_source("PS", "sup", P_SUPPLY)
    for m in range(2):
        c.resistor(f"RS{m}", "sup", f"line{m}", R=(0.6, 3.0)[m] / n)
        c.volume(f"VL{m}", f"line{m}", V=f"{10 * n}mL", p0=P_SUPPLY)
        c.resistor(f"RE{m}", f"exh{m}", "atm", R=(0.2, 2.0)[m] / n)
        c.volume(f"VE{m}", f"exh{m}", V=f"{5 * n}mL")
    delays = 0.2 + np.random.default_rng(7).uniform(0.0, 2.5, n)
    for k in range(n):
        c.pressure_source(f"PC{k}", f"c{k}", Pulse(AMBIENT, P_CTRL_HIGH, delay=delays[k],
                                                 rise=0.05, fall=0.05, width=1.0, period=2.0))
        c.resistor(f"RC{k}", f"c{k}", f"ctl{k}", R=5.0)
        c.volume(f"VC{k}", f"ctl{k}", V="10mL")
        c.valve(f"X{k}", f"line{k % 2}", f"act{k}", f"ctl{k}", model="axi")
        c.volume(f"VA{k}", f"act{k}", V="50mL")
        c.resistor(f"RV{k}", f"act{k}", f"exh{(k // 2) % 2}", R=3.0)
    return c


def test_cells_on_different_hub_nodes_are_one_group_and_match_single_rate():
    """Cells of one structure on different supply and exhaust lines are integrated as
    one batch (each cell reading its own lines), and agree with single-rate IDA."""
    from pneunet.engine.partition import partition

    n = 40
    part = partition(two_by_two_manifolds("multirate", 1e-6, n))
    assert sorted(part.hub_nodes) == ["exh0", "exh1", "line0", "line1"]
    assert part.groups == [list(range(n))]
    assert {tuple(c.hub_nodes) for c in part.cells} == {
        ("line0", "exh0"), ("line1", "exh0"), ("line0", "exh1"), ("line1", "exh1")}
    ref = manifolds_reference()
    sol = two_by_two_manifolds("multirate", 1e-6, n).tran(3.0, t_step=0.01)
    assert sol.stats["method"] == "multirate" and sol.stats["groups"] == 1
    nodes = ["line0", "line1", "exh0", "exh1"] + [f"act{k}" for k in range(n)]
    worst = max(np.abs(sol.pressure(x) - at(sol, ref, x)).max() for x in nodes)
    assert worst <= 0.1
    # the lines really differ: each cell must read its own
    assert np.abs(ref.pressure("exh0") - ref.pressure("exh1")).max() > 1.0
    assert np.abs(ref.pressure("line0") - ref.pressure("line1")).max() > 1.0


def test_cells_split_over_two_processes_give_the_one_process_result(monkeypatch):
    """Two worker processes, each integrating half of the cells (outputs in shared
    memory, the hub in the parent), give what one process gives, within the coupling
    tolerance: the hub sums the two halves' draws in another order, and an adaptive
    solver turns such round-off into tolerance-sized differences wherever a decision
    sits on its threshold (a 1e-13 relative change of the supply pressure alone moves
    this run by 1.7e-6; a window accepted one sweep later, by 7e-6).  The budget is
    written here (30 local tolerances, docs/numerics.md), not read from the constant
    under test, and the two-process run also agrees with single-rate IDA at rtol 1e-8."""
    from pneunet.engine import multirate

    one = two_by_two_manifolds("multirate", 1e-6).tran(3.0, t_step=0.01)
    assert one.stats["processes"] == 1
    monkeypatch.setattr(multirate, "PARALLEL_MIN_BATCHED", 10)
    two = two_by_two_manifolds("multirate", 1e-6).tran(3.0, t_step=0.01)
    assert two.stats["processes"] == 2 and two.stats["cells"] == 40
    for node in ["line0", "line1", "exh0", "exh1"] + [f"act{k}" for k in range(40)]:
        local = 1e-6 * np.abs(one.pressure(node)) + 1e-6    # rtol = atol = 1e-6
        assert np.all(np.abs(two.pressure(node) - one.pressure(node)) <= 30 * local)
    ref = manifolds_reference()
    nodes = ["line0", "line1", "exh0", "exh1"] + [f"act{k}" for k in range(40)]
    assert max(np.abs(two.pressure(x) - at(two, ref, x)).max() for x in nodes) <= 0.1
    assert abs(two.stats["sweeps"] - one.stats["sweeps"]) <= 2
    assert two.stats["steps"] == pytest.approx(one.stats["steps"], rel=0.05)


def _multirate_in_a_worker(n):
    sol = two_by_two_manifolds("multirate", 1e-6, n).tran(1.0, t_step=0.05)
    return sol.stats["processes"], float(sol.pressure("act0")[-1])


def test_multirate_inside_a_daemonic_worker_stays_in_its_process(monkeypatch):
    """A daemonic process (a multiprocessing pool's, a dask worker) may not fork: the
    multirate run then keeps its cells in that process, with the same result."""
    import multiprocessing

    from pneunet.engine import multirate

    monkeypatch.setattr(multirate, "PARALLEL_MIN_BATCHED", 10)
    here = _multirate_in_a_worker(40)
    assert here[0] == 2
    with multiprocessing.get_context("fork").Pool(1) as pool:
        there = pool.apply(_multirate_in_a_worker, (40,))
    assert there[0] == 1
    assert there[1] == pytest.approx(here[1], rel=1e-6)


def test_cells_of_another_structure_form_another_group():
    from pneunet.engine.partition import partition

    c = bench_scaling.build(20)
    for k in range(5):                                  # five cells without a vent
        del c.elements[f"RV{k}"]
    part = partition(c)
    assert len(part.cells) == 20
    assert sorted(map(sorted, part.groups)) == [list(range(5)), list(range(5, 20))]


def test_worth_partitioning_says_why_not():
    from pneunet.engine.partition import partition, worth_partitioning

    small = bench_scaling.build(10)          # the line has 12 ports: no hub, one cell
    part = partition(small)
    assert part.hub_nodes == [] and len(part.cells) == 1
    assert worth_partitioning(part, set()) == "1 cell(s), fewer than 64"
    part = partition(small, hub_degree=8)
    assert part.hub_nodes == ["line"] and len(part.cells) == 10
    assert worth_partitioning(part, set()) == "10 cell(s), fewer than 64"
    assert worth_partitioning(partition(bench_scaling.build(64)), set()) == ""
    assert "hub node line has no volume" in worth_partitioning(partition(bench_scaling.build(64)),
                                                               {"line"})


@pytest.mark.parametrize("processes", [1, 2])
def test_a_failure_keeps_the_finished_windows(monkeypatch, processes):
    """A cell whose steps collapse mid-run: SolverError with the solution up to the last
    accepted window (finite, ending before the failure), as single-rate failures keep theirs."""
    from pneunet.engine.solvers import radau
    from pneunet.common.errors import SolverError

    real, calls = radau._check_step, {"n": 0}

    def collapse_late(problem, st, active, h, systems):
        calls["n"] += 1
        if st.t[active].max(initial=0.0) > 2.0 and problem.G > 1:
            raise SolverError("the step of the cell at node act0 collapsed", time=2.0,
                              where="node act0")
        real(problem, st, active, h, systems)
    monkeypatch.setattr(radau, "_check_step", collapse_late)
    if processes == 2:  # the failure happens in a worker process
        from pneunet.engine import multirate

        monkeypatch.setattr(multirate, "PARALLEL_MIN_BATCHED", 10)
    with pytest.raises(SolverError) as caught:
        independent_cells(20, 1e-5, "multirate").tran(4.0, t_step=0.01)
    partial = caught.value.partial
    assert partial is not None and partial.stats["failed"]
    assert partial.stats["processes"] == processes
    assert 0.0 < partial.t[-1] <= 2.0 + 1e-9 and partial.t[0] == 0.0
    assert np.all(np.isfinite(partial.pressure("act0"))) and np.all(np.isfinite(partial.pressure("line")))
