"""Figures of circuit fits and diagnoses (matplotlib via pneunet.common.plotting)."""
from __future__ import annotations

import math
from pathlib import Path

from ..core.verdict import TOLERANCE
from .data import read_trace, signal_of_column


def plot_fit(fit, data, path=None, signals=None):
    """Recorded vs fitted signals (top), residuals over time (middle), rms residual over
    the oscillation phase (bottom)."""
    from ...common.plotting import legend_outside, pyplot, save

    plt = pyplot()
    df = read_trace(data)
    r = fit.residuals
    sigs = signals or fit.signals()
    fig, axes = plt.subplots(3, 1, figsize=(8, 8))
    for s in sigs:
        col = [c for c in df.columns if signal_of_column(c) == s][0]
        axes[0].plot(df["time_s"], df[col], ".", ms=2, alpha=0.5, label=f"{s} recorded")
        # the model as compared: on the record's axis, cycle-aligned where the fit was
        axes[0].plot(r["time_s"], df[col].to_numpy() + r[s].to_numpy(), lw=1,
                     label=f"{s} fitted")
        axes[1].plot(r["time_s"], r[s], lw=0.7, label=s)
        axes[2].plot(fit.phase_rms["phase"], fit.phase_rms[s], "o-", ms=3, label=s)
    if not r["fitted"].all():
        t_fit = r.loc[r["fitted"], "time_s"]
        for ax in axes[:2]:
            ax.axvspan(t_fit.min(), t_fit.max(), color="0.9", zorder=0, label="fit window")
    units = sorted({"mg/s" if s.startswith("mdot_") else "kPa" for s in sigs})
    axes[0].set_ylabel(("pressure (kPa abs)" if units == ["kPa"] else "flow (mg/s)"
                        if units == ["mg/s"] else "kPa abs / mg/s"))
    legend_outside(axes[0], fontsize=7)
    axes[1].set_ylabel(f"residual, model − recording ({' / '.join(units)})")
    for ax in axes[:2]:
        ax.set_xlabel("time (s)")
    axes[2].set_xlabel("oscillation phase (0 = rising through mid level)")
    axes[2].set_ylabel(f"rms residual ({' / '.join(units)})")
    legend_outside(axes[2], fontsize=7)
    title = ", ".join(f"{k} = {v:.4g}" for k, v in fit.values.items())
    if math.isfinite(fit.period_error):
        title += f"; period error {fit.period_error:+.3g} s"
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    return save(fig, path) if path is not None else fig


def plot_waterfall(diag, path):
    """The error waterfall of a trace diagnosis as a PNG."""
    return diag.waterfall.plot(path, title=f"error waterfall: {diag.verdict}",
                               tolerance=TOLERANCE)


def plot_diagnosis(diag, directory, data=None) -> list:
    """Waterfall and the final fit's residuals into ``directory``; returns the paths."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    return [plot_waterfall(diag, d / "waterfall.png")]
