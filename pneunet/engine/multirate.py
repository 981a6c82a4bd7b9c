"""Multirate transient of a hub and many cells: each cell on its own steps.

The circuit is partitioned (:mod:`~pneunet.engine.partition`) into cells joined
only through hub nodes.  Cells of one structure are integrated together as arrays
by :mod:`~pneunet.engine.solvers.radau`, every cell with its own time step, error
test and source corners, so a cell switching at its own time costs steps in that
cell only.  Cells and hub are coupled by windowed waveform relaxation:

1. over a window [T, T + H] the hub pressures are given at sample times (at least
   :data:`SAMPLES`, one per step of the hub, and the output times), cubic Hermite
   between them (first sweep: extrapolated from T);
2. all cells are integrated across the window against them, and the mass each
   cell draws from each hub node is integrated with the method's own weights;
3. the hub is integrated across the window, its steps landing on the samples, with
   the draw the cubic through the drawn masses gives, plus the draw's sensitivity to
   the hub pressure times the difference from what the cells saw (Newton-type): the
   sensitivity the last window's last two sweeps showed (:func:`_secant_slope`), or, in
   the first window, the cells' instantaneous one at its start;
4. if the hub's new samples differ from those the cells saw by at most
   :data:`COUPLING_TOL` local tolerances (weighted norm, weights 1/(rtol·|p| + atol))
   and so does a rerun of the hub with the cells' draw alone (so that the hub loses
   exactly what the cells gain), the window is accepted; else steps 2–4 repeat with
   the new samples; after :data:`MAX_SWEEPS` the window is halved.  H grows while
   one or two sweeps suffice.  A sweep whose change is predicted acceptable (the last
   change times the ratio of the last two, :data:`FIRST_CONTRACTION` before there are
   two) runs that rerun's hub (without the slope) alone.

Every cell meets IDA's local error test in IDA's norm; the coupling error is
bounded by the same tolerance at every sample.  Cells with algebraic nodes and no
hub (cells driven by ideal sources only) are independent circuits: each runs
through the single-rate integrator of its own, with fold jumps.

From :data:`PARALLEL_MIN_BATCHED` batched cells on, the cells are split in two, each
half built and integrated in a worker process of its own (:class:`~pneunet.common.workers.Servant`)
with the outputs in shared memory; the hub stays in the calling process.
"""
from __future__ import annotations

import time as _time

import numpy as np

from .assembly import CircuitDAE
from .cells import CellBatch
from .partition import Cell, Partition
from .solution import Solution, build_solution
from .solvers import radau
from .solvers.interpolate import hermite_step
from ..common.errors import SolverError
from ..physics.waveforms import SampleTable
from ..common.workers import Servant, can_fork, process_pool

SAMPLES = 8                # hub sample intervals per window: at least,
MAX_SAMPLES = 64           # at most; else one per step of the hub (once it has taken one)
FIRST_WINDOW = 1 / 200     # of the span: the start is the least settled; windows grow from it
MAX_SWEEPS = 6             # waveform-relaxation sweeps before a window is halved
ANDERSON_DEPTH = 3         # earlier sweeps the next hub samples are mixed from
COUPLING_TOL = 30          # accepted hub-sample change between sweeps, in local tolerances
FIRST_CONTRACTION = 0.1    # change of the samples per sweep, until one has been measured
MIN_CONTRACTION = 1e-3     # the least that a measured one counts for
DEFAULT_OUTPUTS = 1000     # output points when the .tran gives no step
PARALLEL_WORKERS = 2
PARALLEL_MIN_CELLS = 8     # independent cells from which they run in worker processes
PARALLEL_MIN_BATCHED = 300   # batched cells from which they are split over worker processes


def transient(circuit, dae: CircuitDAE, part: Partition, t_stop: float, t_step: float | None,
              t_start: float, y0: np.ndarray, algebraic: set[str], single_rate) -> Solution:
    """Multirate transient of ``circuit`` (its DAE ``dae``) from the full state ``y0``
    (kPa, in the DAE's order).
    Cells with ``algebraic`` nodes (no volume; folds possible) and no hub run each on
    its own through ``single_rate(circuit, t_stop, t_step, t_start)``."""
    wall = _time.perf_counter()
    opts = circuit.options
    times = (np.append(np.arange(t_start, t_stop, t_step)[1:], t_stop) if t_step else
             np.linspace(t_start, t_stop, DEFAULT_OUTPUTS + 1)[1:])
    jumps = dae.jumps(t_start, t_stop)  # each twice: both sides (solution.left_limits)
    times = np.sort(np.concatenate([[t_start], times[~np.isin(times, jumps)], jumps, jumps]))
    alone = [c for c in part.cells if any(n in algebraic for n in c.nodes)]
    batched = [ids for ids in part.groups
               if not any(n in algebraic for n in part.cells[ids[0]].nodes)]
    split = can_fork() and sum(map(len, batched)) >= PARALLEL_MIN_BATCHED
    out = _shared((times.size, dae.n)) if split else np.empty((times.size, dae.n))
    out[0] = y0
    corners = dae.instance_corners(t_start, t_stop)
    chunks = [chunk for ids in batched for chunk in
              np.array_split(ids, PARALLEL_WORKERS if split else 1)]
    # with split: each part of the cells built and integrated in a worker process of its
    # own, the outputs in shared memory
    groups = [(_GroupProcess if split else _Group)(circuit, part, chunk, dae, corners, y0,
                                                   times, out, t_start, t_stop)
              for chunk in chunks]
    stats = dict(method="multirate", cells=len(part.cells), groups=len(batched),
                 processes=len(groups) if split else 1,
                 hub_nodes=len(part.hub_nodes), cells_alone=len(alone))
    count = radau.Counters()
    if alone:
        alone_steps, jumps = _run_independently(circuit, alone, single_rate, (t_stop, t_step, t_start),
                                                times, out, dae)
        count.steps += alone_steps
        stats["branch_jumps"] = jumps
    done = [t_start]  # the time up to which every output row is final
    try:
        if part.hub_nodes:
            hub = _Hub(circuit, part, dae, corners, y0, times, out, t_start)
            stats.update(_relax(groups, hub, t_start, t_stop, opts, count, done))
        elif groups:
            _advance_all(groups, count, "advance", t_stop, None, opts)
    except SolverError as err:
        if not part.hub_nodes:  # each cell recorded its outputs up to where it got
            done[0] = min((g.earliest() for g in groups), default=t_start)
        rows = int(np.searchsorted(times, done[0], side="right"))
        partial = build_solution(dae, times[:rows], np.array(out[:rows]),
                                 dict(stats, failed=True), ())
        raise SolverError(err.message, time=err.time, where=err.where, hint=err.hint,
                          partial=partial) from None
    finally:
        for group in groups:
            group.close()
    stats.update(steps=count.steps, rejected=count.rejected, passes=count.passes,
                 residual_calls=count.residuals, jacobian_calls=count.jacobians,
                 output_points=int(times.size), unknowns=dae.n,
                 algebraic=len(algebraic), backend="radau5 (multirate)",
                 wall_time_s=_time.perf_counter() - wall)
    return build_solution(dae, times, np.array(out), stats, ())


class _Group:
    """The cells of one structure: batch, state, corners and output recorder."""

    def __init__(self, circuit, part, ids, dae, corners, y0, times, out, t_start, t_stop):
        cells = [part.cells[i] for i in ids]
        self.cells = cells
        self.batch = CellBatch(circuit, cells)
        self.cols = np.array([[dae.node_index(n) for n in c.nodes] for c in cells], dtype=int)
        # (G, nb): the hub node (its index in part.hub_nodes) of each cell's boundary nodes
        self.hub_cols = np.array([[part.hub_nodes.index(h) for h in c.hub_nodes]
                                  for c in cells], dtype=int).reshape(len(cells), -1)
        self.batch.boundary_cols = self.hub_cols
        self.n_hub = len(part.hub_nodes)
        self.corners = radau.Corners(*_cell_corners(corners, cells))
        self.times, self.out = times, out
        self.next_out = np.ones(len(cells), dtype=int)
        self.t_start, self.span = t_start, t_stop - t_start
        self.y0 = y0[self.cols]
        self.state = None
        self._saved = self._guide = self._recorded = None

    def begin(self, opts):
        if self.state is None:
            self.state = radau.start(self.batch, self.t_start, self.y0, self.span,
                                     opts.rtol, opts.atol)

    def set_hub(self, S, value, slope):
        """The hub pressures the cells see: the cubic Hermite through ``value`` and
        ``slope`` (S.size, n_hub) at the times S."""
        self.batch.boundary = SampleTable(S, value, slope).value

    def draw_now(self):
        """The cells' draw from each hub node now (n_hub,), mg/s."""
        return self._per_hub(self.state.Q)

    def earliest(self) -> float:
        """The time (s) every cell has reached."""
        return float(self.state.t.min()) if self.state is not None else self.t_start

    def later(self, name, *args):
        """Method ``name`` called with ``args``, its result given by the returned function."""
        result = getattr(self, name)(*args)
        return lambda: result

    def start_window(self):
        """:meth:`save` the state at the start of a window; return :meth:`draw_slope`."""
        self.save()
        return self.draw_slope()

    def sweep(self, S, value, slope, t_end, opts):
        """Back to the start of the window, the hub given by ``value`` and ``slope`` at the
        times S (:meth:`set_hub`), integrate to ``t_end``: :meth:`advance`."""
        self.restore()
        self.set_hub(S, value, slope)
        return self.advance(t_end, S, opts)

    def close(self):
        pass

    def advance(self, t_end, S, opts):
        """Integrate to ``t_end``; return the counters and, with sample times ``S``,
        the mass (mg) the cells have drawn from each hub node and its rate (mg/s) there,
        (S.size, n_hub) each."""
        count = radau.Counters()
        self.begin(opts)
        cols = self.hub_cols
        if S is not None:
            mass, rate = np.zeros((S.size, self.n_hub)), np.zeros((S.size, self.n_hub))
            mass[0], rate[0] = self._per_hub(self.state.M), self._per_hub(self.state.Q)
            next_sample = np.ones(self.batch.G, dtype=int)

        def on_step(rows, before, after):
            _record(self.times, self.next_out, rows, before, after, self._write, slopes=False)
            if S is not None:
                _record(S, next_sample, rows, before, after, lambda r, k, m, q: (
                    np.add.at(mass, (k[:, None], cols[r]), m),
                    np.add.at(rate, (k[:, None], cols[r]), q)), mass=True)
        # in a sweep, the accepted steps: the next sweep's guide
        recorder = radau.StepRecorder(self.batch.G, self.state.t.min()) if S is not None else None
        radau.advance(self.batch, self.state, t_end, opts.rtol, opts.atol, self.corners,
                      on_step, count, self._guide, recorder)
        if recorder is not None:
            self._recorded = recorder.guide()
        return count, ((mass, rate) if S is not None else None)

    def _per_hub(self, per_cell):
        """Per hub node (n_hub,): the sum of the cells' ``per_cell`` (G, nb) drawn from it."""
        total = np.zeros(self.n_hub)
        np.add.at(total, self.hub_cols, per_cell)
        return total

    def draw_slope(self, dp=1e-3):
        """How much more the cells draw from each hub node per kPa of its pressure, now
        (a difference quotient of every cell's boundary outflow), (n_hub,) mg/(s·kPa)."""
        st, batch = self.state, self.batch
        slope = np.zeros(self.n_hub)
        restore = batch.boundary
        seen = restore(st.t)
        batch.boundary = lambda t: seen
        _, base = batch.evaluate(st.t, st.Y, st.Yd)
        cells = np.arange(batch.G)
        for j, col in enumerate(self.hub_cols.T):  # each cell's j-th boundary node
            shifted = seen.copy()
            shifted[cells, col] += dp
            batch.boundary = lambda t, b=shifted: b
            _, q = batch.evaluate(st.t, st.Y, st.Yd)
            np.add.at(slope, col, (q[:, j] - base[:, j]) / dp)
        batch.boundary = restore
        return slope

    def _write(self, rows, k, y, _):
        self.out[k[:, None], self.cols[rows]] = y

    def save(self):
        """Keep the state, to :meth:`restore` it (the start of a window)."""
        self._saved = self.state.copy(), self.corners.next.copy(), self.next_out.copy()
        self._recorded = self._guide = None

    def restore(self):
        """Back to the start of the window, to step as the last sweep did (its steps
        proposed again: :class:`~pneunet.engine.solvers.radau.StepGuide`)."""
        state, corners, next_out = self._saved
        self.state = state.copy()
        self.corners.next[:] = corners
        self.next_out[:] = next_out
        self._guide, self._recorded = self._recorded, None


class _GroupProcess:
    """A :class:`_Group` built and kept in a worker process of its own (its outputs in
    shared memory): the same methods, and :meth:`later` runs one while the caller goes
    on."""

    def __init__(self, *args):
        self._servant = Servant(_Group, *args)

    def __getattr__(self, name):
        if name in ("begin", "set_hub", "draw_now", "earliest", "restore"):
            return lambda *args: self._servant.call(name, *args)
        raise AttributeError(name)

    def later(self, name, *args):
        self._servant.send(name, *args)
        return self._servant.receive

    def close(self):
        self._servant.close()


class _Hub:
    """The hub nodes as one system, with the cells' draw injected."""

    def __init__(self, circuit, part, dae, corners, y0, times, out, t_start):
        cell = Cell(part.hub_elements, list(part.hub_nodes), [], list(part.hub_sources))
        self.batch = CellBatch(circuit, [cell], hub_nodes=part.hub_nodes, title="hub")
        self.cols = np.array([dae.node_index(n) for n in cell.nodes])
        own, jumps = _cell_corners(corners, [cell])
        self.own_corners, self.own_jumps = own[0], jumps[0]
        self.times, self.out = times, out
        self.next_out = np.ones(1, dtype=int)
        self.y0, self.t_start = y0[self.cols][None, :], t_start
        self.batch.injection = self._injection
        self._draw = self._seen = None
        self._inputs = {}  # (first time (s), count) → (draw, seen pressures) at those times
        self.slope = None  # (1, n_hub) mg/(s·kPa); None: the draw alone
        self.state = None

    def begin(self, draw, opts):
        """The hub's state at the start, the cells drawing ``draw`` (n_hub,) mg/s."""
        self._draw = lambda t: np.broadcast_to(draw, (len(t), draw.size))
        self._inputs.clear()
        self.state = radau.start(self.batch, self.t_start, self.y0, self.times[-1] - self.t_start,
                                 opts.rtol, opts.atol)

    def _injection(self, t, Y):
        """The cells' draw at times t (one, or a pass's three stage times), corrected by
        its slope for the difference between the hub's pressure and the one the cells
        saw."""
        key = (float(t[0]), t.size)  # a pass evaluates its stage times several times
        if key not in self._inputs:
            if len(self._inputs) > 16:
                self._inputs.clear()
            self._inputs[key] = (self._draw(t), None if self._seen is None else self._seen(t))
        rate, seen = self._inputs[key]
        if seen is None:
            return rate, None
        return rate + self.slope * (Y - seen), self.slope

    def advance(self, S, land, drawn, seen, slope, opts, count):
        """Integrate across the window ``S`` with the cells' draw ``drawn`` (mass and
        rate at S) by cells that saw hub pressures ``seen`` (value and slope at S) and
        whose draw grows by ``slope`` (n_hub,) mg/(s·kPa) per kPa of hub pressure,
        landing on the times ``land``; return the hub's pressures and their rates at S
        (M + 1, n_hub) each."""
        corrected = bool(np.any(slope))
        self._draw = SampleTable(S, *drawn).slope
        self._seen = SampleTable(S, *seen).value if corrected else None
        self.slope = np.asarray(slope, dtype=float)[None, :] if corrected else None
        self._inputs.clear()
        values, rates = np.empty((S.size, self.batch.k)), np.empty((S.size, self.batch.k))
        values[0], rates[0] = self.state.Y[0], self.state.Yd[0]
        next_sample = np.ones(1, dtype=int)
        inside = (self.own_corners > S[0]) & (self.own_corners < S[-1])
        corners = radau.Corners([np.union1d(land, self.own_corners[inside])], [self.own_jumps])

        def on_step(rows, before, after):
            _record(self.times, self.next_out, rows, before, after, self._write, slopes=False)
            _record(S, next_sample, rows, before, after,
                    lambda r, k, y, d: (values.__setitem__(k, y), rates.__setitem__(k, d)))
        radau.advance(self.batch, self.state, S[-1], opts.rtol, opts.atol, corners,
                      on_step, count)
        return values, rates

    def _write(self, rows, k, y, _):
        self.out[k[:, None], self.cols[None, :]] = y

    def snapshot(self):
        return self.state.copy(), self.next_out.copy()

    def restore(self, saved):
        self.state, self.next_out = saved[0].copy(), saved[1].copy()


def _on_all(groups, name, *args):
    """Call method ``name`` of every group (those in worker processes at the same time);
    return the results in order."""
    waiting = [g.later(name, *args) for g in groups]
    results, failure = [], None
    for wait in waiting:  # every reply is collected, so the workers are idle after
        try:
            results.append(wait())
        except SolverError as err:
            failure = failure or err
    if failure is not None:
        raise failure
    return results


def _advance_all(groups, count, name, *args):
    """Integrate every group by its method ``name`` (:meth:`_Group.advance` or
    :meth:`_Group.sweep`) with ``args``; add up their counters; return what each drew."""
    results = _on_all(groups, name, *args)
    for counted, _ in results:
        count.add(counted)
    return [drawn for _, drawn in results]


def _relax(groups, hub, t_start, t_stop, opts, count, done) -> dict:
    """Windowed waveform relaxation of ``groups`` and ``hub`` to ``t_stop``; ``done[0]``
    follows the end of the last accepted window (s)."""
    draw = np.zeros(len(hub.cols))
    flat = np.repeat(hub.y0, 2, axis=0)
    for group in groups:
        group.set_hub(np.array([t_start, t_stop]), flat, np.zeros_like(flat))
        group.begin(opts)
        draw += group.draw_now()
    hub.begin(draw, opts)
    T, H = t_start, FIRST_WINDOW * (t_stop - t_start)
    windows = sweeps = halvings = 0
    secant = None  # the draw's sensitivity to the hub pressure the last two sweeps showed
    contraction = FIRST_CONTRACTION  # the change's ratio over the last two sweeps
    worst = 0.0
    while T < t_stop - 1e-12 * max(1.0, abs(t_stop)):
        H = min(H, t_stop - T)
        if t_stop - T - H < 0.2 * H:
            H = t_stop - T
        m = SAMPLES if hub.state.fresh[0] else int(np.clip(np.ceil(H / hub.state.h[0]),
                                                            SAMPLES, MAX_SAMPLES))
        S = _samples(T, H, m, hub.times)
        # the hub's steps land on every sample (the knots of its piecewise-cubic draw):
        # its integral of the draw is exact, so it loses what the cells drew
        land = S[1:-1]
        p = (hub.state.Y[0] + (S - T)[:, None] * hub.state.Yd[0],
             np.repeat(hub.state.Yd, S.size, axis=0))
        instantaneous = sum(_on_all(groups, "start_window"))
        slope = instantaneous if secant is None else \
            np.where(np.isnan(secant), instantaneous, secant)
        saved_hub = hub.snapshot()
        no_slope = np.zeros_like(slope)  # the hub drawing exactly what the cells drew
        history = _Anderson(opts)
        change, last = np.inf, None
        for sweep in range(1, MAX_SWEEPS + 1):
            sweeps += 1
            mass, rate = np.zeros_like(p[0]), np.zeros_like(p[0])
            for group_mass, group_rate in _advance_all(groups, count, "sweep", S, p[0], p[1],
                                                       T + H, opts):
                mass += group_mass
                rate += group_rate
            if last is not None:
                secant = _secant_slope(last, (p[0], rate))
            last = p[0], rate
            # when the last change times the last measured contraction is acceptable, this
            # sweep is likely accepted: run the only hub that may be (on the cells' draw
            # alone, no slope) instead of the slope's, which would be run again
            exact = change * contraction <= COUPLING_TOL
            hub.restore(saved_hub)
            new = hub.advance(S, land, (mass, rate), p, no_slope if exact else slope, opts,
                              count)
            previous, change = change, _change(new, p, opts)
            if np.isfinite(previous):
                contraction = max(change / previous, MIN_CONTRACTION)
            if change <= COUPLING_TOL and not exact:
                hub.restore(saved_hub)
                new = hub.advance(S, land, (mass, rate), p, no_slope, opts, count)
                change = _change(new, p, opts)
            if change <= COUPLING_TOL:
                break
            p = history.next(p, new)
        else:
            for group in groups:
                group.restore()
            hub.restore(saved_hub)
            H *= 0.5
            halvings += 1
            continue
        worst = max(worst, change)
        windows += 1
        T = done[0] = float(S[-1])
        H *= 2.0 if sweep <= 2 else 1.3 if sweep == 3 else 1.0 if sweep == 4 else 0.7
    return dict(windows=windows, sweeps=sweeps, window_halvings=halvings,
                coupling_defect=worst)


class _Anderson:
    """Anderson acceleration of the hub's waveform iteration: the next samples the cells
    see are the combination of the last :data:`ANDERSON_DEPTH` hub results whose
    residuals (result − what the cells saw, values and slopes, each in its own local
    tolerances) combine to the smallest in the least-squares sense."""

    def __init__(self, opts):
        self.opts = opts
        self.seen, self.results = [], []

    def next(self, seen, result):
        """The hub samples (value, slope) for the next sweep, after the cells saw
        ``seen`` and the hub came out as ``result``."""
        self.seen.append(np.concatenate([a.ravel() for a in seen]))
        self.results.append(np.concatenate([a.ravel() for a in result]))
        del self.seen[:-ANDERSON_DEPTH - 1], self.results[:-ANDERSON_DEPTH - 1]
        if len(self.seen) < 2:
            return result
        x, g = np.array(self.seen), np.array(self.results)
        r = (g - x) / (self.opts.rtol * np.abs(g[-1]) + self.opts.atol)
        gamma = np.linalg.lstsq(np.diff(r, axis=0).T, r[-1], rcond=1e-10)[0]
        mixed = g[-1] - gamma @ np.diff(g, axis=0)
        if not np.all(np.isfinite(mixed)):
            return result
        n = result[0].size
        return mixed[:n].reshape(result[0].shape), mixed[n:].reshape(result[1].shape)


def _secant_slope(before, after):
    """How much more the cells drew from each hub node per kPa more hub pressure between
    two sweeps of a window, each given as (pressures seen, rates drawn) at the samples
    (S.size, n_hub): the least-squares ratio of the changes over the samples, (n_hub,)
    mg/(s·kPa); NaN where the pressure did not change or the ratio is not positive.

    Over a window the cells' volumes follow the hub, and their draw settles back: on
    ``bench_scaling``'s network this ratio is 5–9× below the instantaneous sensitivity
    at the start of a window of 1–5 s, whose correction overshoots."""
    dp, dq = after[0] - before[0], after[1] - before[1]
    power = np.einsum("sj,sj->j", dp, dp)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.einsum("sj,sj->j", dq, dp) / power
    return np.where((power > 0) & np.isfinite(ratio) & (ratio > 0), ratio, np.nan)


def _samples(T, H, m, outputs):
    """The sample times (s) of the window [T, T + H]: its ends, the ``outputs`` inside
    (the draw is known there exactly) and, between consecutive ones further apart than
    H/m, evenly spaced points at most H/m apart."""
    inside = np.unique(outputs[(outputs > T + 1e-9 * H) & (outputs < T + H - 1e-9 * H)])
    knots = np.concatenate([[T], inside, [T + H]])
    gaps = np.diff(knots)
    pieces = np.maximum(np.ceil(gaps * (m / H) - 1e-9), 1).astype(int)
    first = np.repeat(knots[:-1], pieces)
    step = np.repeat(gaps / pieces, pieces)
    within = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    return np.append(first + within * step, T + H)


def _change(new, seen, opts) -> float:
    """Largest change of the hub samples, in local tolerances (IDA's weights)."""
    return float(np.max(np.abs(new[0] - seen[0]) / (opts.rtol * np.abs(new[0]) + opts.atol)))


def _record(times, nxt, rows, before, after, write, mass=False, slopes=True):
    """For each step that passed one of ``times`` (shared, increasing), write the
    cubic Hermite interpolant's value and slope (None without ``slopes``) there; ``nxt``
    is each system's next time index.  ``mass``: interpolate the drawn mass M (rate Q),
    not the state."""
    t0, Y0, Yd0, Q0, M0 = before
    t1, Y1, Yd1, Q1, M1 = after
    y0, d0, y1, d1 = (M0, Q0, M1, Q1) if mass else (Y0, Yd0, Y1, Yd1)
    k = nxt[rows]
    passed = np.searchsorted(times, t1 * (1 + 1e-14), side="right")  # times ≤ t1
    hit = np.flatnonzero(passed > k)
    if not hit.size:
        return
    count = passed[hit] - k[hit]        # the times each step passed, in one go
    at = np.repeat(hit, count)
    first = np.cumsum(count) - count
    k = k[at] + np.arange(at.size) - np.repeat(first, count)
    h = (t1[at] - t0[at])[:, None]
    s = np.clip((times[k] - t0[at])[:, None] / h, 0.0, 1.0)
    write(rows[at], k, *hermite_step(s, h, y0[at], d0[at], y1[at], d1[at], slopes))
    nxt[rows[hit]] = passed[hit]


def _shared(shape):
    """A float array in memory shared with processes forked after it (zeros)."""
    import mmap

    size = int(np.prod(shape))
    return np.frombuffer(mmap.mmap(-1, max(8 * size, 8)), dtype=float, count=size).reshape(shape)


def _cell_corners(corners, cells):
    """Per cell: the corners and jumps (s) of its elements' inputs, from ``corners``
    (:meth:`CircuitDAE.instance_corners`)."""
    times, jumps = [], []
    for cell in cells:
        own = [corners[name] for name in cell.sources + cell.elements if name in corners]
        times.append(np.unique(np.concatenate([c[0] for c in own])) if own else np.empty(0))
        jumps.append(np.unique(np.concatenate([c[1] for c in own])) if own else np.empty(0))
    return times, jumps


def _run_independently(circuit, cells, single_rate, span, times, out, dae):
    """Cells without a hub, as circuits of their own (on both cores when there are
    many); their pressures go into ``out`` on the output ``times``.  Returns the
    integrator steps and branch jumps, summed."""
    global _ALONE
    _ALONE = (circuit, cells, single_rate, span, times)
    chunks = np.array_split(np.arange(len(cells)), min(len(cells), 2 * PARALLEL_WORKERS))
    pool = process_pool(PARALLEL_WORKERS) if len(cells) >= PARALLEL_MIN_CELLS else None
    try:
        results = list(pool.map(_run_cells, chunks)) if pool else [_run_cells(c) for c in chunks]
    finally:
        if pool is not None:
            pool.shutdown()
        _ALONE = None
    steps = jumps = 0
    for block in results:
        for nodes, values, cell_steps, cell_jumps in block:
            out[:, [dae.node_index(n) for n in nodes]] = values
            steps, jumps = steps + cell_steps, jumps + cell_jumps
    return steps, jumps


_ALONE = None  # what the forked workers of _run_independently read


def _run_cells(indices):
    """Run the cells ``indices`` of ``_ALONE``: (nodes, pressures on the output times,
    steps, jumps) for each."""
    circuit, cells, single_rate, (t_stop, t_step, t_start), times = _ALONE
    results = []
    for cell in (cells[i] for i in indices):
        sub = circuit.subcircuit(cell.sources + cell.elements, cell.nodes)
        sol = single_rate(sub, t_stop, t_step, t_start)
        values = np.column_stack([np.interp(times, sol.t, sol.pressure(n)) for n in cell.nodes])
        results.append((cell.nodes, values, int(sol.stats.get("steps", 0)),
                        int(sol.stats.get("branch_jumps", 0))))
    return results
