"""Figures of a :class:`~pneunet.truth.valves.diagnose.Diagnosis` (matplotlib via pneunet.common.plotting)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ....common.plotting import legend_outside, pyplot, save
from ...core.verdict import TOLERANCE
from .features import FEATURE_LABELS
from .residuals import binned_map

#: feature pairs of the residual maps
MAP_PAIRS = (("ratio", "dp"), ("p_in", "p_out"), ("p_ctrl", "p_in"), ("time", "mdot"),
             ("dp", "sweep"))


def plot_waterfall(diag, path):
    """Error waterfall (CV RMSE: baseline → each accepted effect) and candidate ranking."""
    plt = pyplot()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [1, 1.3]})
    diag.waterfall.draw(ax, tolerance=TOLERANCE)
    ax.set_title(f"error waterfall: {diag.verdict}")
    rnd = diag.ranking
    names = [c.effect for c in rnd]
    gains = [c.gain if c.gain is not None else c.insample_gain for c in rnd]
    errs = [1.96 * c.gain_se if c.gain_se is not None else 0 for c in rnd]
    cols = ["#55a868" if c.accepted else ("#dd8452" if c.screened else "#bbbbbb") for c in rnd]
    y = np.arange(len(rnd))[::-1]
    ax2.barh(y, gains, xerr=errs, color=cols, capsize=3)
    ax2.set_yticks(y, names)
    ax2.axvline(0, color="k", lw=0.8)
    thr = diag.settings["min_gain"] * diag.baseline.cv_rmse
    ax2.axvline(thr, color="#c44e52", ls=":", label=f"practical floor {thr:.2g} mg/s")
    ax2.set_xlabel("CV gain over the six-parameter model [mg/s] (95 % CI)")
    ax2.set_title("candidates, round 1 (green accepted, grey screened out)")
    legend_outside(ax2, fontsize=8)
    fig.tight_layout()
    return save(fig, path)


def plot_residual_maps(diag, path, pairs=MAP_PAIRS):
    """Binned mean residual over feature pairs, before (top) and after (bottom).

    Bins whose mean is within 2 standard errors of zero are grey; each column
    shares one colour scale, so what is left after the effects shows as pale.
    """
    plt = pyplot()
    stages = [diag.baseline] + ([diag.final] if diag.added else [])
    fig, axes = plt.subplots(len(stages), len(pairs), figsize=(4.2 * len(pairs),
                                                               3.6 * len(stages)), squeeze=False)
    for col, (fx, fy) in enumerate(pairs):
        maps = []
        for stage in stages:
            F = stage.features
            maps.append(binned_map(F[fx].to_numpy(), F[fy].to_numpy(), stage.resid))
        base_mean = maps[0][2]
        lim = float(np.nanmax(np.abs(base_mean))) if np.isfinite(base_mean).any() else 1.0
        lim = max(lim, 1e-9)
        for row, (stage, (ex, ey, mean, se, n)) in enumerate(zip(stages, maps)):
            ax = axes[row, col]
            ax.pcolormesh(ex, ey, np.where(np.isfinite(mean), 0.0, np.nan).T, cmap="Greys",
                          vmin=-1, vmax=4)
            clear = np.where(np.abs(mean) >= 2 * se, mean, np.nan)
            im = ax.pcolormesh(ex, ey, clear.T, cmap="RdBu", vmin=-lim, vmax=lim)
            ax.set_xlabel(FEATURE_LABELS[fx], fontsize=8)
            ax.set_ylabel(FEATURE_LABELS[fy].replace(" (−1 falling, +1 rising p_ctrl)", ""),
                          fontsize=8)
            if fy == "sweep":
                ax.set_yticks([-1, 1], ["falling", "rising"])
            name = "six-parameter model" if stage.label == "baseline" else "final model"
            ax.set_title(f"{name}: measured − model", fontsize=9)
            fig.colorbar(im, ax=ax, label="mean residual [mg/s]")
    fig.suptitle("binned mean residual (grey: within 2 standard errors of zero; same colour "
                 "scale before and after)", fontsize=10)
    fig.tight_layout()
    return save(fig, path)


def plot_where(diag, path):
    """Feature importance of the learned residual model (before / after)."""
    plt = pyplot()
    stages = [diag.baseline] + ([diag.final] if diag.added else [])
    fig, axes = plt.subplots(1, len(stages), figsize=(5 * len(stages), 3.4), squeeze=False)
    for ax, stage in zip(axes[0], stages):
        s = stage.structure
        names = [FEATURE_LABELS.get(f, f).split(" [")[0].split(" (")[0] for f, _ in s["importance"]][::-1]
        vals = [v for _, v in s["importance"]][::-1]
        ax.barh(names, vals, color="#4c72b0" if s["learnable"] else "#bbbbbb")
        verdict = "learnable structure" if s["learnable"] else "no learnable structure"
        lab = "six-parameter model" if stage.label == "baseline" else "final model"
        ax.set_title(f"{lab}: {verdict}\n(residual model removes {s['gain']:.2f} ± "
                     f"{s['gain_se']:.2f} mg/s out of sample)", fontsize=9)
        ax.set_xlabel("share of permutation importance")
    fig.tight_layout()
    return save(fig, path)


def plot_all(diag, directory) -> list[Path]:
    d = Path(directory)
    return [plot_waterfall(diag, d / "waterfall.png"),
            plot_residual_maps(diag, d / "residual_maps.png"),
            plot_where(diag, d / "where.png")]
