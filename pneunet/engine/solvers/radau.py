"""Radau IIA (order 5) on many small DAE systems at once, each on its own steps.

A batch (:class:`~pneunet.engine.cells.CellBatch`) holds G independent systems
F_g(t_g, y_g, ẏ_g) = 0 of k unknowns.  Every pass of :func:`advance` lets each
system that has not reached its target take one step of its own size: arrays over
all G systems, one (3k, 3k) Newton matrix per system.

The method is the three-stage Radau IIA collocation method (Hairer & Wanner,
*Solving ODEs II*, IV.8): L-stable, stiffly accurate, order 5, for index-1 DAEs.
The stage increments Z_i = Y_i − y_n solve F(t_n + c_i·h, y_n + Z_i, Ẏ_i) = 0 with
Ẏ = A⁻¹Z/h, by simplified Newton with ∂F/∂y and ∂F/∂ẏ from the start of the step
(retaking an earlier sweep's steps: from the start of the recorded step, see
:class:`StepGuide`).
The local error is Hairer's embedded estimate (order 3)

    e = (γ₀⁻¹/h·M + J)⁻¹ · (M·ẏ_n + M·Σ d_i Z_i / h),   M = ∂F/∂ẏ, J = ∂F/∂y,

accepted when its weighted RMS norm with weights 1/(rtol·|y_n| + atol) — IDA's
norm — is at most 1, for each system on its own.  Being one-step, a system
restarts at a window boundary with only its state and step size, which waveform
relaxation (:mod:`pneunet.engine.multirate`) needs.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ...common.errors import SolverError

_S6 = np.sqrt(6.0)
C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
A = np.array([[(88 - 7 * _S6) / 360, (296 - 169 * _S6) / 1800, (-2 + 3 * _S6) / 225],
              [(296 + 169 * _S6) / 1800, (88 + 7 * _S6) / 360, (-2 - 3 * _S6) / 225],
              [(16 - _S6) / 36, (16 + _S6) / 36, 1.0 / 9.0]])
A_INV = np.linalg.inv(A)
B = A[2]                                     # stiffly accurate: y_n+1 = y_n + Z_3
_D = np.array([-(13 + 7 * _S6) / 3, (-13 + 7 * _S6) / 3, -1.0 / 3.0])



def _transformation():
    """T with T⁻¹·A⁻¹·T = [[γ, 0, 0], [0, α, β], [0, −β, α]]: the stage equations
    split into one real and one complex k×k system (Hairer & Wanner IV.8)."""
    values, vectors = np.linalg.eig(A_INV)
    real = int(np.argmin(np.abs(values.imag)))
    pair = [i for i in range(3) if i != real and values[i].imag > 0][0]
    T = np.column_stack([vectors[:, real].real, vectors[:, pair].real, vectors[:, pair].imag])
    blocks = np.linalg.inv(T) @ A_INV @ T
    return T, np.linalg.inv(T), blocks[0, 0], complex(blocks[1, 1], -blocks[1, 2])


T, T_INV, _GAMMA, _ALPHA_BETA = _transformation()   # γ = 1/γ₀ ≈ 3.6378, α − iβ
NEWTON_ITERATIONS = 2
NEWTON_TOL = 0.03     # estimated distance to the stage solution, in tolerance units
SAFETY, GROW, SHRINK = 0.9, 6.0, 0.2
SHRINK_RETRY = 0.01      # the most a step is cut after a second failure at the same time
NEWTON_CAP_GROWTH = 1.3  # growth per accepted step of the step bound after a Newton failure


@dataclass
class BatchState:
    """Per system: time t (s), next step h (s), state Y and rate Yd (G, k), its
    boundary outflows Q (G, nb, mg/s) and their integral M since the start (mg)."""

    t: np.ndarray
    h: np.ndarray
    Y: np.ndarray
    Yd: np.ndarray
    Q: np.ndarray
    M: np.ndarray
    Z: np.ndarray = None       # (3, G, k) stage increments of the last accepted step
    h_last: np.ndarray = None  # its length (s)
    err_last: np.ndarray = None  # its error norm (the predictive step control's memory)
    fresh: np.ndarray = None   # no usable last step (start, or after a jump)
    h_newton: np.ndarray = None  # the step (s) Newton is trusted to converge on (inf: any)
    h_failed: np.ndarray = None  # the last attempt's step (s) if it failed (nan: it passed)
    err_failed: np.ndarray = None  # that attempt's error norm

    def copy(self) -> "BatchState":
        return BatchState(*(getattr(self, f.name).copy() for f in fields(self)))

    def take(self, rows: np.ndarray) -> "BatchState":
        """The systems ``rows`` alone (copies)."""
        return BatchState(*(getattr(self, f.name)[:, rows] if f.name == "Z" else
                            getattr(self, f.name)[rows] for f in fields(self)))

    def put(self, rows: np.ndarray, part: "BatchState") -> None:
        """Write the systems ``rows`` back from ``part`` (a :meth:`take`)."""
        for f in fields(self):
            if f.name == "Z":
                self.Z[:, rows] = part.Z
            else:
                getattr(self, f.name)[rows] = getattr(part, f.name)


@dataclass
class Counters:
    steps: int = 0          # accepted steps, summed over systems
    rejected: int = 0
    passes: int = 0         # batched step attempts
    residuals: int = 0      # batched residual evaluations (one per stage)
    jacobians: int = 0      # batched Jacobian-block evaluations

    def add(self, other: "Counters") -> None:
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))


class Corners:
    """Each system's source corners: times (s) its steps must land on, and which of
    them are jumps of a value (the rate ẏ is recomputed after those)."""

    def __init__(self, times: list[np.ndarray], jumps: list[np.ndarray]):
        width = max([len(t) for t in times] + [1])
        self.times = np.full((len(times), width + 1), np.inf)
        self.jump = np.zeros_like(self.times, dtype=bool)
        for g, (ts, js) in enumerate(zip(times, jumps)):
            ts = np.asarray(ts, dtype=float)
            self.times[g, :ts.size] = ts
            self.jump[g, :ts.size] = np.isin(ts, js)
        self.next = np.zeros(len(times), dtype=int)

    def upcoming(self, t: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The next corner (s) after the times ``t`` of the systems ``rows`` (inf: none)."""
        return _upcoming(self.times, self.next, t, rows)

    def jumps_at(self, rows: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Those of ``rows`` whose next corner is a jump at their time ``t``."""
        k = self.next[rows]
        return rows[self.jump[rows, k] & (self.times[rows, k] == t)]


class StepGuide:
    """The steps each system accepted in an earlier integration from the same start (the
    previous waveform-relaxation sweep of a window), proposed again: a system on that
    grid retakes a step that passed there instead of the controller's guess, which the
    error test may reject again.  Every step still passes the error test; only the
    proposals change.  The Newton blocks each recorded step started from serve again
    (:meth:`blocks`): the state differs from the recorded one by the change of the
    coupling, which simplified Newton tolerates."""

    def __init__(self, G: int, start: float, rows: np.ndarray, ends: np.ndarray,
                 jac: np.ndarray, mass: np.ndarray):
        """``rows``, ``ends``, ``jac`` and ``mass``: the systems, step ends and Newton
        blocks ∂F/∂y, ∂F/∂ẏ (from the start of each step) of the accepted steps in the
        order they were taken (so each system's ends increase)."""
        # step j of system g: entry order[first[g] + j] of the arrays as given
        self.order = np.argsort(rows, kind="stable")  # by system, each in time order
        rows = rows[self.order]
        self.counts = np.bincount(rows, minlength=G)
        self.first = np.concatenate([[0], np.cumsum(self.counts)[:-1]])
        self.times = np.full((G, self.counts.max(initial=0) + 2), np.inf)
        self.times[:, 0] = start                  # every system starts on its grid
        self.times[rows, 1 + np.arange(rows.size) - self.first[rows]] = ends[self.order]
        self.jac, self.mass = jac, mass
        self.next = np.zeros(G, dtype=int)
        self.refused = np.zeros(G, dtype=bool)   # a proposal failed; not again until a step passes
        self.needs_own_blocks = np.zeros(G, dtype=bool)  # Newton failed: until a step passes
        self._following = None

    def propose(self, t, h_controller, h, limit, rows):
        """Step sizes (s) for the systems ``rows`` at times ``t``: to the next recorded
        end where that lies within ``limit`` (their next corner or target) and the
        system is on the recorded grid (or the end is within 0.5–1.5 of the
        controller's step ``h_controller``); else ``h`` (the controller's)."""
        ahead = _upcoming(self.times, self.next, t, rows) - t
        previous = self.times[rows, self.next[rows] - 1]
        on_grid = np.abs(t - previous) <= 1e-13 * np.maximum(1.0, np.abs(t))
        near = (ahead >= 0.5 * h_controller) & (ahead <= 1.5 * h_controller)
        follow = ((on_grid & (ahead <= 2.0 * h_controller)) | near) & (t + ahead <= limit) \
            & ~self.refused[rows]
        self._following = follow
        return np.where(follow, ahead, h)

    def blocks(self, rows, active):
        """After :meth:`propose`: for the systems ``rows``, the Newton blocks (jac, mass)
        of the recorded step each one's time lies in (the one starting there on the
        grid), or None when some ``active`` system has none or failed Newton since its
        last accepted step."""
        step, counts = self.next[rows] - 1, self.counts[rows]
        if np.any(active & ((step >= counts) | self.needs_own_blocks[rows])):
            return None
        at = self.order[self.first[rows] + np.minimum(step, counts - 1)]
        return self.jac[at], self.mass[at]

    def settle(self, rows, active, converged, accepted):
        """After the attempt: the systems ``rows`` whose proposal failed stop following
        until they pass a step of the controller's; those whose Newton iteration did not
        converge take no recorded blocks until they pass a step."""
        self.refused[rows[active & self._following & ~accepted]] = True
        self.refused[rows[accepted & ~self._following]] = False
        self.needs_own_blocks[rows[active & ~converged]] = True
        self.needs_own_blocks[rows[accepted]] = False


class StepRecorder:
    """The accepted steps of an integration from ``start`` (s) and the Newton blocks
    each started from, for the :class:`StepGuide` of the next integration from there."""

    def __init__(self, G: int, start: float):
        self.G, self.start = G, start
        self._parts = []

    def add(self, rows, ends, jac, mass):
        """The systems ``rows`` accepted steps ending at ``ends`` (s) from the blocks
        ``jac``, ``mass`` (len(rows), k, k)."""
        self._parts.append((rows, ends, jac, mass))

    def guide(self) -> StepGuide | None:
        """The guide for the next integration from ``start`` (None: no step taken)."""
        if not self._parts:
            return None
        return StepGuide(self.G, self.start, *map(np.concatenate, zip(*self._parts)))


def _upcoming(times, nxt, t, rows):
    """The next of each system's sorted ``times`` after its time ``t``, advancing its
    pointer ``nxt`` past those behind (inf: none left)."""
    while True:
        behind = times[rows, nxt[rows]] <= t * (1 + 1e-13) + 1e-13
        if not behind.any():
            return times[rows, nxt[rows]]
        nxt[rows[behind]] += 1


def wrms(x: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted RMS norm of each row (G,) (einsum: numpy's mean over a short last axis
    is 2× slower)."""
    scaled = x * weights
    return np.sqrt(np.einsum("gk,gk->g", scaled, scaled) / x.shape[-1])


def start(problem, t0: float, Y: np.ndarray, span: float, rtol: float, atol: float) -> BatchState:
    """The state at t0 with consistent rates and a cautious first step."""
    G = Y.shape[0]
    t = np.full(G, float(t0))
    Yd = problem.rates(t, Y, np.zeros_like(Y))
    _, Q = problem.evaluate(t, Y, Yd)
    speed = wrms(Yd, 1.0 / (rtol * np.abs(Y) + atol))  # tolerance units per second
    h = np.clip(10.0 / np.maximum(speed, 1e-300), 1e-9 * span, span)
    return BatchState(t, h, Y.copy(), Yd, Q, np.zeros_like(Q), np.zeros((3,) + Y.shape),
                      h.copy(), np.full(G, 1e-2), np.ones(G, dtype=bool), np.full(G, np.inf),
                      np.full(G, np.nan), np.full(G, np.nan))


def advance(problem, st: BatchState, t_end: float, rtol: float, atol: float,
            corners: Corners | None = None, on_step=None, count: Counters | None = None,
            guide: StepGuide | None = None, recorder: StepRecorder | None = None):
    """Step every system of ``st`` to ``t_end`` (s), landing on its corners, with the
    step proposals and Newton blocks of ``guide`` where given; ``recorder`` keeps the
    accepted steps.

    ``on_step(rows, before, after)`` is called after each pass with the systems that
    took a step and their (t, Y, Yd, Q, M) before and after it.  A problem with a
    ``rows(active)`` method (:class:`~pneunet.engine.cells.CellBatch`) may give an
    evaluator of the active systems alone; a pass then works on them only.  One with
    ``evaluate_stages`` evaluates a Newton iteration's three stages in one call.
    """
    count = count if count is not None else Counters()
    everyone = np.arange(st.Y.shape[0])
    tiny = 1e-12 * max(1.0, abs(t_end))
    subset = getattr(problem, "rows", None)
    while True:
        active = st.t < t_end - tiny
        if not active.any():
            return count
        count.passes += 1
        rows, view = subset(np.flatnonzero(active)) if subset is not None else (None, None)
        if rows is None:
            _pass(problem, st, everyone, active, t_end, tiny, rtol, atol, corners, on_step, count,
                  guide, recorder)
        else:
            part = st.take(rows)
            _pass(view, part, rows, active[rows], t_end, tiny, rtol, atol, corners, on_step,
                  count, guide, recorder)
            st.put(rows, part)


def _pass(problem, st, systems, active, t_end, tiny, rtol, atol, corners, on_step, count,
          guide=None, recorder=None):
    """One step attempt of the ``active`` systems of ``st``; ``systems`` are their
    indices in the whole batch (corners, callbacks and messages use those)."""
    G = st.Y.shape[0]
    target = np.full(G, t_end)
    if corners is not None:
        target = np.minimum(target, corners.upcoming(st.t, systems))
    room = target - st.t
    h = np.where(room <= st.h, room, np.where(room < 1.5 * st.h, 0.5 * room, st.h))
    if guide is not None:
        h = guide.propose(st.t, st.h, h, target + tiny, systems)
    h = np.where(active, h, 1.0)
    _check_step(problem, st, active, h, systems)
    weights = 1.0 / (rtol * np.abs(st.Y) + atol)
    blocks = guide.blocks(systems, active) if guide is not None else None
    if blocks is None:
        _, _, jac, mass = problem.evaluate(st.t, st.Y, st.Yd, jacobian=True)
        count.jacobians += 1
    else:
        jac, mass = blocks
    newton = _newton_matrices(jac, mass, h, active)
    Z, Yd_stages, Q_stages, ok, iterations = _solve_stages(problem, st, h, newton, weights,
                                                           active, count)
    error = _error_estimate(newton[0], mass, st.Yd, Z, h)
    err = _norm(error, weights, problem.differential)
    accepted = active & ok & (err <= 1.0)
    if guide is not None:
        guide.settle(systems, active, ok, accepted)
    new_h = _next_step(st, h, err, iterations, accepted)
    failed = active & ~accepted
    new_h = _after_repeated_failure(st, h, err, failed, new_h)
    st.h_failed = np.where(failed, h, np.where(accepted, np.nan, st.h_failed))
    st.err_failed = np.where(failed, err, st.err_failed)
    # Newton failed: at least halve, more when the (unconverged) error says so — a
    # step across a kink of the flow laws then takes fewer attempts
    new_h = np.where(ok, new_h, np.minimum(0.5 * h, new_h))
    # where Newton failed, the next steps stay below half that step, a bound that grows
    # by NEWTON_CAP_GROWTH per accepted step: the error test alone would grow the step
    # back onto the same failure (a valve settling onto its seat: fail, halve, grow 6×)
    st.h_newton = np.where(active & ~ok, 0.5 * h,
                           np.where(accepted, NEWTON_CAP_GROWTH * st.h_newton, st.h_newton))
    new_h = np.minimum(new_h, st.h_newton)
    clipped = h < st.h
    st.h = np.where(active, np.where(accepted & clipped, np.maximum(st.h, new_h), new_h), st.h)
    count.rejected += int(np.count_nonzero(active & ~accepted))
    rows = np.flatnonzero(accepted)
    if not rows.size:
        return
    count.steps += rows.size
    st.Z[:, rows], st.h_last[rows], st.fresh[rows] = Z[:, rows], h[rows], False
    st.err_last[rows] = np.maximum(err[rows], 1e-2)
    before = (st.t[rows], st.Y[rows], st.Yd[rows], st.Q[rows], st.M[rows])
    t_new = st.t[rows] + h[rows]
    st.t[rows] = np.where(np.abs(t_new - target[rows]) <= tiny, target[rows], t_new)
    if recorder is not None:
        recorder.add(systems[rows], st.t[rows], jac[rows], mass[rows])
    st.M[rows] += h[rows][:, None] * (B[0] * Q_stages[0, rows] + B[1] * Q_stages[1, rows]
                                       + B[2] * Q_stages[2, rows])
    st.Y[rows] += Z[2, rows]
    st.Yd[rows], st.Q[rows] = Yd_stages[2, rows], Q_stages[2, rows]
    if corners is not None:
        jumped = corners.jumps_at(systems[rows], st.t[rows])
        if jumped.size:
            _restart_rates(problem, st, np.searchsorted(systems, jumped))
    if on_step is not None:
        on_step(systems[rows], before, (st.t[rows], st.Y[rows], st.Yd[rows], st.Q[rows],
                                        st.M[rows]))


def _next_step(st, h, err, iterations, accepted):
    """Step sizes after a step of error ``err``: Hairer's rule with his safety factor
    for slow Newton convergence and, after an accepted step that followed an accepted
    one, Gustafsson's predictive control (radau5), within [SHRINK, GROW]·h.  After a
    rejection the predictive rule would compare the step with the last accepted one,
    taken before whatever made the attempts fail (a source corner), and cut it 5× again."""
    safety = SAFETY * (2 * NEWTON_ITERATIONS + 1) / (iterations + 2 * NEWTON_ITERATIONS)
    quot = np.clip(err ** 0.25 / safety, 1.0 / GROW, 1.0 / SHRINK)
    predictive = accepted & ~st.fresh & np.isnan(st.h_failed)
    gustafsson = np.clip(st.h_last / h * (err * err / st.err_last) ** 0.25 / safety,
                         1.0 / GROW, 1.0 / SHRINK)
    quot = np.where(predictive, np.maximum(quot, gustafsson), quot)
    return h / quot


def _after_repeated_failure(st, h, err, failed, new_h):
    """The next step of systems whose attempt ``failed`` again at the same time with a
    shorter step and a smaller error: the error's observed order in h over the two
    attempts (within [1, 4]; the controller assumes 4) sets it, by at most
    :data:`SHRINK_RETRY` at once.  Past a kink of an input or a flow law (a control
    source's ramp starting on a quadrature resistor at zero flow) the error falls about
    as h¹·²: the controller's h⁴ cut the step 5× per attempt, five attempts at each
    ramp corner of ``bench_scaling``'s cells, two with this rule."""
    again = failed & (st.h_failed > h) & (err < st.err_failed)
    if not again.any():
        return new_h
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.log(st.err_failed[again] / err[again]) / np.log(st.h_failed[again] / h[again])
    order = np.clip(np.where(np.isfinite(order), order, 4.0), 1.0, 4.0)
    factor = np.clip((SAFETY / err[again]) ** (1.0 / order), SHRINK_RETRY, 1.0)
    new_h = new_h.copy()
    new_h[again] = np.minimum(new_h[again], h[again] * factor)
    return new_h


def _check_step(problem, st, active, h, systems):
    small = active & (h < 1e-13 * np.maximum(1.0, np.abs(st.t)))
    if small.any():
        g = int(np.flatnonzero(small)[0])
        node = problem.names[systems[g]][0]
        raise SolverError(f"the step of the cell at node {node} collapsed at t = {st.t[g]:.6g} s",
                          time=float(st.t[g]), where=f"node {node}",
                          hint=".options method=single (one step for the whole circuit)")


def _newton_matrices(jac, mass, h, active):
    """Inverses of the real and complex iteration matrices γ/h·M + J and
    (α − iβ)/h·M + J per system, (G, k, k) each (identity for inactive systems)."""
    rows = np.flatnonzero(active)
    scale = 1.0 / h[rows, None, None]
    inverses = [_inverse(shift * scale * mass[rows] + jac[rows])
                for shift in (_GAMMA, _ALPHA_BETA)]
    if rows.size == h.size:
        return tuple(inverses)
    out = []
    for inv in inverses:  # identity for the inactive systems
        full = np.broadcast_to(np.eye(jac.shape[1], dtype=inv.dtype), jac.shape).copy()
        full[rows] = inv
        out.append(full)
    return tuple(out)


def _inverse(m):
    """Inverses of a stack of small matrices (G, k, k): by formula for k ≤ 2."""
    k = m.shape[-1]
    if k == 1:
        return 1.0 / m
    if k == 2:
        a, b, c, d = m[:, 0, 0], m[:, 0, 1], m[:, 1, 0], m[:, 1, 1]
        det = a * d - b * c
        if np.all(det != 0):
            out = np.empty_like(m)
            out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = d, -b, -c, a
            return out / det[:, None, None]
    try:
        return np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(m)


def _apply(inverse, v):
    """inverse (G, k, k) times v (G, k): for k ≤ 4 as k² multiply-adds of (G,) columns
    (at 1,500 cells 5× faster than a broadcast product summed over its last axis)."""
    k = v.shape[-1]
    if k > 4:
        return np.einsum("gab,gb->ga", inverse, v)
    out = np.empty(np.broadcast_shapes(inverse.shape[:-1], v.shape),
                   dtype=np.result_type(inverse, v))
    for a in range(k):
        row = inverse[:, a, 0] * v[:, 0]
        for b in range(1, k):
            row += inverse[:, a, b] * v[:, b]
        out[:, a] = row
    return out


def _mix(matrix, stages):
    """The 3×3 ``matrix`` applied along the stage axis of ``stages`` (3, G, ·)."""
    return (matrix @ stages.reshape(3, -1)).reshape(stages.shape)


def _solve_stages(problem, st, h, inverse, weights, active, count):
    """Stage increments Z (3, G, k), stage rates and boundary outflows (3, G, ·), and
    per system: convergence and the Newton iterations it took."""
    G, k = st.Y.shape
    Z = np.where(st.fresh[None, :, None], (C[:, None, None] * h[None, :, None]) * st.Yd[None],
                 _extrapolate(st.Z, h / st.h_last))
    ok = ~active
    iterations = np.zeros(G)
    previous = None
    stage_times = [st.t + c * h for c in C]
    for times in stage_times:  # read-only: the problem may keep its inputs at them
        times.flags.writeable = False
    stacked = getattr(problem, "evaluate_stages", None)
    for _ in range(NEWTON_ITERATIONS):
        rates = _mix(A_INV, Z) / h[None, :, None]
        if stacked is not None:
            residual, outflow = stacked(stage_times, st.Y[None] + Z, rates)
        else:
            stages = [problem.evaluate(stage_times[i], st.Y + Z[i], rates[i]) for i in range(3)]
            residual, outflow = (np.stack(parts) for parts in zip(*stages))
        count.residuals += 3
        delta = _newton_update(inverse, residual)
        scaled = delta * weights[None]
        size = np.sqrt(np.einsum("igk,igk->g", scaled, scaled) / (3 * k))
        Z = Z + np.where((active & ~ok)[None, :, None], delta, 0.0)
        if previous is not None:
            rate = size / np.maximum(previous, 1e-300)
            done = (rate < 1.0) & (rate / np.maximum(1.0 - rate, 1e-12) * size <= NEWTON_TOL)
        else:
            done = size <= NEWTON_TOL
        iterations += ~ok
        ok = ok | done
        if ok.all():
            break
        previous = size
    return Z, _mix(A_INV, Z) / h[None, :, None], outflow, ok, iterations


def _newton_update(inverse, residual):
    """−(∂F/∂Z)⁻¹·F for stage residuals F (3, G, k), in the transformed variables."""
    real_inv, pair_inv = inverse
    rhs = _mix(T_INV, residual)
    w0 = _apply(real_inv, rhs[0])
    u = _apply(pair_inv, rhs[1] + 1j * rhs[2])
    return -_mix(T, np.stack([w0, u.real, u.imag]))


_NODES = (0.0, C[0], C[1], C[2])      # the collocation polynomial's nodes, units of h
_LAGRANGE = [1.0 / np.prod([_NODES[j] - _NODES[m] for m in range(4) if m != j])
             for j in range(4)]         # 1 / Π_{m≠j}(x_j − x_m)


def _extrapolate(Z, ratio):
    """Stage increments for the next step (length ratio·h) from the collocation
    polynomial of the last one, u(0) = 0, u(c_i) = Z_i (3, G, k): Hairer's start."""
    s = 1.0 + C[:, None] * ratio[None, :]                     # (3, G) in units of h_last
    diff = [s - x for x in _NODES]
    # Lagrange basis of nodes 1–3 at the new stage times (node 0 carries u = 0)
    d0, d1, d2, d3 = diff
    weight = [(_LAGRANGE[1] * d0) * (d2 * d3), (_LAGRANGE[2] * d0) * (d1 * d3),
              (_LAGRANGE[3] * d0) * (d1 * d2)]
    if Z.shape[2] > 2:
        return np.einsum("jig,jgk->igk", np.array(weight), Z) - Z[2][None]
    out = np.empty_like(Z)
    for c in range(Z.shape[2]):  # column by column: numpy is slow on a last axis of 2
        out[:, :, c] = (weight[0] * Z[0][:, c] + weight[1] * Z[1][:, c]
                        + weight[2] * Z[2][:, c] - Z[2][:, c])
    return out


def _error_estimate(real_inv, mass, Yd, Z, h):
    """Hairer's embedded error estimate (G, k) of the step (see the module docstring);
    ``real_inv`` the inverse of γ/h·M + J."""
    combo = (_D[0] * Z[0] + _D[1] * Z[1] + _D[2] * Z[2]) / h[:, None]
    return _apply(real_inv, _apply(mass, Yd + combo))


def _norm(error, weights, differential):
    """Weighted RMS norm of the error over the differential unknowns, ≥ 1e-10."""
    if not differential.any():
        return np.full(error.shape[0], 1e-10)
    return np.maximum(wrms(error[:, differential], weights[:, differential]), 1e-10)


def _restart_rates(problem, st: BatchState, rows: np.ndarray) -> None:
    """After a source jump: rates consistent with the new source values."""
    full = problem.rates(st.t, st.Y, st.Yd)
    st.Yd[rows] = full[rows]
    st.fresh[rows] = True
    _, Q = problem.evaluate(st.t, st.Y, st.Yd)
    st.Q[rows] = Q[rows]
