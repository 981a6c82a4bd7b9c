"""Regime maps: equilibrium vs oscillation over (R_out, R_vent) or (R_out, V).

Every grid point is classified twice: by a transient (:class:`RegimeMeasure`, which
runs :func:`~pneunet.engine.oscillation.oscillator_period` until the cycle converges)
and by the stationary branches of eqs. 27–29
(:func:`~pneunet.physics.oscillator_branches.stationary_branches`, no simulation).  The table
holds both, the period and the predicted p_c,min/max; :func:`plot_regime_map` colours
the transient result by period and draws the boundary predicted by the branches.
"""
from __future__ import annotations

import numpy as np

from .sweep import OscillationMeasure, grid, lin, run_sweep


class RegimeMeasure(OscillationMeasure):
    """:class:`OscillationMeasure` plus the branch prediction for the same circuit."""

    def __call__(self, circuit):
        from ..physics.oscillator_branches import spec_from_circuit, stationary_branches

        out, sol = super().__call__(circuit)
        try:
            b = stationary_branches(spec_from_circuit(circuit, self.node))
            out.update(regime_branches=b.regime, p_c_min_branches=b.p_c_min,
                       p_c_max_branches=b.p_c_max)
        except Exception as exc:  # noqa: BLE001 - recorded, the transient result stands
            out.update(regime_branches="error", branches_error=str(exc))
        return out, sol


def regime_map(build, x, y, *, node: str = "tank", workers=None, executor=None, store=None,
               progress=True, t_max: float = 320.0, rtol: float = 1e-4):
    """Sweep the grid of axes ``x`` × ``y`` (:func:`~pneunet.design.sweep.lin` etc.).

    Returns a :class:`~pneunet.design.sweep.SweepResult` whose table has the columns
    ``regime`` (transient), ``regime_branches``, ``period_s``, ``p_min``/``p_max`` and the
    branch predictions ``p_c_min_branches``/``p_c_max_branches``.
    """
    points = grid(x, y)
    return run_sweep(build, points, RegimeMeasure(node=node, rtol=rtol, t_max=t_max),
                     workers=workers, executor=executor, store=store, progress=progress)


def oscillator_map(n: int = 20, rout=(0.2, 3.0), rvent=(1.0, 6.0), **kw):
    """The paper's oscillator over an n × n (R_out, R_vent) grid."""
    from .circuits import oscillator

    return regime_map(oscillator, lin("Rout", *rout, n), lin("Rvent", *rvent, n), **kw)


def agreement(table) -> dict:
    """How often the branch prediction agrees with the transient classification."""
    ok = table[table["regime"].isin(["oscillation", "equilibrium"])
               & table["regime_branches"].isin(["oscillation", "equilibrium"])]
    same = ok["regime"] == ok["regime_branches"]
    return {"points": int(len(table)), "compared": int(len(ok)), "agree": int(same.sum()),
            "fraction": float(same.mean()) if len(ok) else float("nan"),
            "disagree_at": ok.loc[~same, [c for c in ok.columns if c not in (
                "key", "elapsed_s")]].iloc[:, :2].to_dict(orient="records")}


def plot_regime_map(table, x: str, y: str, path=None, title=None):
    """Period (colour) where the transient oscillates, grey where it settles; the black
    line is the boundary predicted by the stationary branches; crosses mark points where
    the two classifications disagree."""
    from ..common.plotting import pyplot, save
    from .sweep_plot import parameter_label

    plt = pyplot()

    xs = np.sort(table[x].unique())
    ys = np.sort(table[y].unique())
    period = np.full((len(ys), len(xs)), np.nan)
    state = np.full_like(period, np.nan)  # 1 oscillation, 0 equilibrium, nan failed/undetermined
    pred = np.zeros_like(period)
    for _, row in table.iterrows():
        i, j = np.searchsorted(ys, row[y]), np.searchsorted(xs, row[x])
        if row.get("regime") == "oscillation":
            period[i, j] = row["period_s"]
            state[i, j] = 1
        elif row.get("regime") == "equilibrium":
            state[i, j] = 0
        pred[i, j] = 1.0 if row.get("regime_branches") == "oscillation" else 0.0
    fig, ax = plt.subplots(figsize=(6.6, 4.8))
    ax.pcolormesh(xs, ys, np.where(state == 0, 1.0, np.nan), cmap="Greys", vmin=0.0,
                  vmax=4.0, shading="nearest")  # light grey: settles
    mesh = ax.pcolormesh(xs, ys, period, cmap="viridis", shading="nearest")
    fig.colorbar(mesh, ax=ax, label="period (s)")
    if 0 < pred.sum() < pred.size:
        ax.contour(xs, ys, pred, levels=[0.5], colors="crimson", linewidths=2)
    failed = np.isnan(state)
    if failed.any():
        yy, xx = np.nonzero(failed)
        ax.plot(xs[xx], ys[yy], "o", color="k", ms=4, label="simulation failed / undetermined")
    bad = ~failed & (state != pred)
    if bad.any():
        yy, xx = np.nonzero(bad)
        ax.plot(xs[xx], ys[yy], "x", color="crimson", ms=7, mew=2, label="classifications differ")
    if failed.any() or bad.any():  # below the map, not over it
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
    ax.set_xlabel(parameter_label(x))
    ax.set_ylabel(parameter_label(y))
    ax.set_title(title or "regime map: grey = equilibrium, colour = oscillation period\n"
                          "red line: boundary from the stationary branches", fontsize=10)
    return save(fig, path) if path is not None else fig
