"""Which parameter's spread matters most: first-order sensitivities from Monte Carlo samples.

For each metric, a linear regression on the sampled parameters gives the slope b_j; the
effect of one standard deviation of parameter j is b_j·σ_j (metric units) and its share
of the metric's variance (b_j·σ_j)²/Var(metric) (the squared standardized regression
coefficient: a variance-based first-order index when the parameters are independent and
the metric is near-linear over the spread; ``r2`` says how near).  Samples whose metric
was not measured are left out.  :func:`plot_tornado` draws the effects.
"""
from __future__ import annotations

import numpy as np


def sensitivities(samples, parameters: list, metrics: list):
    """A table (metric, parameter, sd, effect, share, r2) from the samples table."""
    import pandas as pd

    rows = []
    for metric in metrics:
        y = samples[metric].to_numpy(float)
        X = samples[parameters].to_numpy(float)
        ok = np.isfinite(y) & np.all(np.isfinite(X), axis=1)
        y, X = y[ok], X[ok]
        sd = X.std(axis=0, ddof=1) if len(y) > 1 else np.zeros(len(parameters))
        var = y.var(ddof=1) if len(y) > 1 else 0.0
        if len(y) <= len(parameters) + 1 or var == 0 or not np.all(sd > 0):
            b, r2 = np.full(len(parameters), np.nan), np.nan
        else:
            A = np.column_stack([np.ones(len(y)), (X - X.mean(axis=0)) / sd])
            coef, *_ = np.linalg.lstsq(A, y, rcond=None)
            b = coef[1:]
            r2 = 1 - np.sum((y - A @ coef) ** 2) / np.sum((y - y.mean()) ** 2)
        for j, name in enumerate(parameters):
            rows.append({"metric": metric, "parameter": name, "sd": float(sd[j]),
                         "effect": float(b[j]), "share": float(b[j] ** 2 / var) if var else
                         np.nan, "r2": float(r2), "samples": int(len(y))})
    return pd.DataFrame(rows)


def most_important(table) -> dict:
    """{metric: the parameter with the largest share of its variance}."""
    out = {}
    for metric, group in table.groupby("metric", sort=False):
        group = group.dropna(subset=["share"])
        if len(group):
            out[metric] = group.loc[group["share"].idxmax(), "parameter"]
    return out


def plot_tornado(table, nominal: dict, units: dict, path=None, top: int = 6):
    """One panel per metric: the metric's value ± one SD of each parameter (the ``top``
    largest, largest on top)."""
    from ..plotting import pyplot, save

    plt = pyplot()
    metrics = list(dict.fromkeys(table["metric"]))
    shown = {m: table[table["metric"] == m].dropna(subset=["effect"]) for m in metrics}
    shown = {m: g.reindex(g["effect"].abs().sort_values().index).tail(top)
             for m, g in shown.items()}
    bars = sum(max(1, len(g)) for g in shown.values())
    fig, axes = plt.subplots(len(metrics), 1, figsize=(6.4, 1.0 + 0.45 * bars + 0.6 *
                                                          len(metrics)), squeeze=False)
    for ax, metric in zip(axes[:, 0], metrics):
        group = shown[metric]
        centre = nominal.get(metric, 0.0)
        effects = group["effect"].to_numpy()
        y = np.arange(len(group))
        ax.barh(y, effects, left=centre, color="tab:red", label="+1 SD")
        ax.barh(y, -effects, left=centre, color="tab:blue", label="−1 SD")
        ax.set_yticks(y, [f"{p} ({s:.0%})" for p, s in zip(group["parameter"], group["share"])])
        ax.axvline(centre, color="k", lw=0.8)
        ax.set_xlabel(f"{metric} ({units.get(metric) or '-'})")
    axes[0, 0].legend(loc="lower right", fontsize="small")
    axes[0, 0].set_title("effect of one standard deviation (share of variance)")
    fig.tight_layout()
    return save(fig, path) if path else fig
