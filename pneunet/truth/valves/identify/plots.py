"""The paper's identification figures, one function each (PNG via pneunet.common.plotting).

Every function takes results (a :class:`~pneunet.truth.valves.identify.fit.ValveFit` or an
analysis result), draws one figure, saves it when ``path`` is given and returns the
matplotlib figure (closed after saving).
"""
from __future__ import annotations

import numpy as np

from ....common.plotting import legend_outside, pyplot, save
from .analyses import areas_vs_threshold, open_valve_resistance

OPEN, CLOSED, WRONG, MODEL = "tab:blue", "tab:green", "tab:red", "tab:red"


def _finish(fig, path):
    if path is not None:
        save(fig, path)
    return fig


def fig6a_open_valve(check, path=None):
    """Fig. 6A: √(p_in² − p_out²) against ṁ on the fully open points, zero-intercept line."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(check.mdot, check.root, "o", color=OPEN, ms=4, label=f"data ({check.n} points)")
    x = np.linspace(0, check.mdot.max() * 1.05, 50)
    ax.plot(x, check.R_open * x, "-", color=MODEL,
            label=f"R_open = {check.R_open:.4g} kPa·s/mg, r² = {check.r2:.4f}")
    ax.set_xlabel("mass flow ṁ [mg/s]")
    ax.set_ylabel("√(p_in² − p_out²) [kPa]")
    ax.set_title("Fully open valve (p_ctrl at atmosphere, p_in + p_out ≥ 900 kPa)", fontsize=9)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    legend_outside(ax, fontsize=8)
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def fig6b_separation(fit, path=None):
    """Fig. 6B: p_ctrl against a_in p_in + a_out p_out, open/closed/misclassified points."""
    plt = pyplot()
    p = fit.params
    frame = fit.frame
    x = p.ain * frame["p_in_kPa"].to_numpy() + p.aout * frame["p_out_kPa"].to_numpy()
    pc = frame["p_ctrl_kPa"].to_numpy()
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    closed = ~fit.open
    ax.plot(x[closed], pc[closed], ".", color=CLOSED, ms=3, label=f"closed ({closed.sum()})")
    ax.plot(x[fit.open], pc[fit.open], ".", color=OPEN, ms=3, label=f"open ({fit.open.sum()})")
    wrong = fit.misclassified
    ax.plot(x[wrong], pc[wrong], "o", mfc="none", mec="k", ms=7,
            label=f"misclassified ({wrong.sum()})")
    line = np.linspace(x.min(), x.max(), 10)
    ax.plot(line, line - p.pclose, "-", color=MODEL, lw=1.5,
            label=f"Δp = p_close ({p.pclose:.4g} kPa)")
    ax.set_xlabel("a_in·p_in + a_out·p_out [kPa]" + f"   (a_in {p.ain:.3f}, a_out {p.aout:.3f})")
    ax.set_ylabel("p_ctrl [kPa]")
    ax.set_title(f"Open/closed separation, ṁ_min = {fit.mdot_min:.3g} mg/s", fontsize=9)
    legend_outside(ax, fontsize=8)
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def fig6c_inverse_resistance(fit, path=None):
    """Fig. 6C: measured 1/R against Δp with the fitted eq. 24 curve."""
    from .fit import _conductance

    plt = pyplot()
    p = fit.params
    dp = fit.delta_p()
    inv_r = fit.inverse_resistance()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    use = fit.fitted
    ax.plot(dp[use], inv_r[use], ".", color=OPEN, ms=3, label=f"data, Δp > p_close ({use.sum()})")
    grid = np.linspace(min(dp[use].min(), p.pclose) - 10, dp[use].max(), 400)
    ax.plot(grid, _conductance(grid, p.Rf, p.pclose, p.ptrans, p.e), "-", color=MODEL, lw=2,
            label=f"eq. 24: R_f {p.Rf:.4g}, p_trans {p.ptrans:.4g}, e {p.e:.3g}")
    ax.axhline(1 / p.Rf, color="gray", ls=":", lw=1)
    ax.axvline(p.pclose, color="gray", ls="--", lw=1)
    ax.axvline(p.ptrans, color="gray", ls="-.", lw=1)
    ax.set_xlabel("Δp = a_in·p_in + a_out·p_out − p_ctrl [kPa]")
    ax.set_ylabel("1/R = ṁ / √(p_in² − p_out²) [mg/(s·kPa)]")
    ax.set_title(f"Valve characteristic, RMSE 1/R = {fit.metrics['rmse_inv_r']:.3g} mg/(s·kPa)",
                 fontsize=9)
    legend_outside(ax, fontsize=8)
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def _slice(fit, p_in):
    frame = fit.frame
    if "p_in_cmd_kPa" in frame:
        levels = np.unique(frame["p_in_cmd_kPa"].to_numpy())
        level = levels[np.argmin(np.abs(levels - p_in))]
        return frame["p_in_cmd_kPa"].to_numpy() == level, level
    pin = frame["p_in_kPa"].to_numpy()
    level = pin[np.argmin(np.abs(pin - p_in))]
    return np.abs(pin - level) <= 5.0, level


def fig7_flow_surface(fit, p_in=396.0, path=None):
    """Fig. 7: measured flow and model surface over (p_out, p_ctrl) at one p_in; errors."""
    plt = pyplot()
    mask, level = _slice(fit, p_in)
    frame = fit.frame[mask]
    pout = frame["p_out_kPa"].to_numpy()
    pctrl = frame["p_ctrl_kPa"].to_numpy()
    mdot = frame["mdot_mg_s"].to_numpy()
    pin_mean = frame["p_in_kPa"].mean()
    go, gc = np.meshgrid(np.linspace(pout.min(), min(pout.max(), pin_mean - 1), 40),
                         np.linspace(pctrl.min(), pctrl.max(), 40))
    model = fit.predict({"p_in_kPa": np.full(go.size, pin_mean), "p_out_kPa": go.ravel(),
                         "p_ctrl_kPa": gc.ravel()}).reshape(go.shape)
    error = mdot - fit.predict(frame)
    p = fit.params
    # separation line Δp = p_close at p_in: p_ctrl = a_in p_in + a_out p_out − p_close
    line_out = np.linspace(go.min(), go.max(), 20)
    line_ctrl = p.ain * pin_mean + p.aout * line_out - p.pclose
    keep = (line_ctrl >= pctrl.min()) & (line_ctrl <= pctrl.max())
    fig = plt.figure(figsize=(11, 4.8))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.plot_surface(go, gc, model, cmap="viridis", alpha=0.45, linewidth=0)
    ax.scatter(pout, pctrl, mdot, color=OPEN, s=6, depthshade=False)
    ax.plot(line_out[keep], line_ctrl[keep], np.zeros(keep.sum()), color=WRONG, lw=2)
    ax.set_xlabel("p_out [kPa]")
    ax.set_ylabel("p_ctrl [kPa]")
    ax.set_zlabel("ṁ [mg/s]")
    ax.set_title(f"A: flow at p_in ≈ {level:.0f} kPa (dots data, surface model)", fontsize=9)
    ax.view_init(elev=25, azim=-120)
    ax2 = fig.add_subplot(1, 2, 2, projection="3d")
    ax2.plot_surface(go, gc, np.zeros_like(go), color="gray", alpha=0.2, linewidth=0)
    ax2.scatter(pout, pctrl, error, color=OPEN, s=6, depthshade=False)
    ax2.plot(line_out[keep], line_ctrl[keep], np.zeros(keep.sum()), color=WRONG, lw=2)
    ax2.set_xlabel("p_out [kPa]")
    ax2.set_ylabel("p_ctrl [kPa]")
    ax2.set_zlabel("error ṁ − model [mg/s]")
    ax2.set_title(f"B: error; RMSE all {fit.metrics['rmse']:.3g}, open "
                  f"{fit.metrics['rmse_open']:.3g} mg/s", fontsize=9)
    ax2.view_init(elev=25, azim=-130)
    return _finish(fig, path)


def fig8_areas(fit, table=None, path=None):
    """Fig. 8: ã_in, ã_out against the threshold 1/R_sep (A) and misclassified % (B)."""
    plt = pyplot()
    if table is None:
        table = areas_vs_threshold(fit)
    p = fit.params
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    ax.plot(table["inv_r_sep"], table["ain"], "o-", color=OPEN, label="ã_in(R_sep)")
    ax.plot(table["inv_r_sep"], table["aout"], "s-", color="tab:cyan", label="ã_out(R_sep)")
    ax.axhline(p.ain, color=MODEL, lw=1, label=f"a_in = {p.ain:.3f} (ṁ_min)")
    ax.axhline(p.aout, color=MODEL, lw=1, ls="--", label=f"a_out = {p.aout:.3f} (ṁ_min)")
    for a in (ax, bx):
        a.axvline(np.sqrt(0.5) / p.Rf, color="gray", ls=":", lw=1)
        a.set_xlabel("threshold 1/R_sep [mg/(s·kPa)]")
        a.grid(alpha=0.3)
    ax.set_ylabel("relative effective area [-]")
    ax.set_title("A: areas from separating 1/R > 1/R_sep (dotted: √2/2 / R_f)", fontsize=9)
    legend_outside(ax, fontsize=8)
    bx.plot(table["inv_r_sep"], 100 * table["misclassified"], "o-", color=OPEN,
            label="own plane (ã_in, ã_out, p̃_sep)")
    bx.plot(table["inv_r_sep"], 100 * table["misclassified_fixed"], "s-", color=MODEL,
            label="fixed a_in, a_out, best offset")
    bx.axhline(1.0, color="gray", ls="--", lw=1)
    bx.set_ylabel("misclassified [%]")
    bx.set_title("B: misclassified points", fontsize=9)
    legend_outside(bx, fontsize=8)
    return _finish(fig, path)


def fig9_seat_height(values, trends, path=None, *, title=None):
    """Fig. 9: each parameter against seat height with its linear trend."""
    from .fit import NAMES
    from ....physics.valve_params import VALVE_PARAMETERS

    plt = pyplot()
    fig, axes = plt.subplots(2, 3, figsize=(11, 6))
    h = values["h_seat_mm"].to_numpy()
    grid = np.linspace(h.min(), h.max(), 10)
    for ax, k in zip(axes.ravel(), NAMES):
        err = values.get(f"{k}_stderr")
        ax.errorbar(h, values[k], yerr=None if err is None else 1.96 * err, fmt="o",
                    color=OPEN, ms=4, capsize=2)
        t = trends.loc[k]
        ax.plot(grid, t["slope"] * grid + t["intercept"], "-", color=MODEL,
                label=f"slope {t['slope']:.3g} ± {t['slope_stderr']:.2g}/mm")
        unit = VALVE_PARAMETERS[k][0]
        ax.set_ylabel(f"{k} [{unit}]")
        ax.set_xlabel("seat height h_seat [mm]")
        legend_outside(ax, fontsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle(title or "Parameters against seat height, linear least-squares trends",
                 fontsize=10)
    fig.tight_layout()
    return _finish(fig, path)


def all_figures(fit, outdir, *, p_in=396.0) -> list:
    """Figs. 6A (when the data has fully open points), 6B, 6C, 7 and 8 into ``outdir``."""
    from pathlib import Path

    from ....common.errors import DataError

    outdir = Path(outdir)
    paths = []
    try:
        check = open_valve_resistance(fit.frame)
        fig6a_open_valve(check, outdir / "fig6a_open_valve.png")
        paths.append(outdir / "fig6a_open_valve.png")
    except DataError:
        pass
    for name, function in (("fig6b_separation", fig6b_separation),
                           ("fig6c_inverse_resistance", fig6c_inverse_resistance)):
        function(fit, outdir / f"{name}.png")
        paths.append(outdir / f"{name}.png")
    fig7_flow_surface(fit, p_in, outdir / "fig7_flow_surface.png")
    paths.append(outdir / "fig7_flow_surface.png")
    fig8_areas(fit, path=outdir / "fig8_areas.png")
    paths.append(outdir / "fig8_areas.png")
    return paths
