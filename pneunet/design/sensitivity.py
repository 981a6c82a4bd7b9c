"""Which parameter's spread matters most: first-order sensitivities from Monte Carlo samples.

For each metric, a linear regression on the sampled parameters gives the slope b_j; the
effect of one standard deviation σ_j of parameter j's distribution is b_j·σ_j (metric
units) and its share of the metric's variance (b_j·σ_j)²/(Σ_k (b_k·σ_k)² + residual
variance): the variance of the linear model with independent parameters, a first-order
variance-based index where the metric is near-linear over the spread (``r2`` says how
near; the shares add up to about ``r2``).  Samples whose metric
was not measured are left out.  :func:`derivative_effects` gives the same effects from
central differences at the design, and :func:`plot_tornado` draws them.
"""
from __future__ import annotations

import numpy as np


def sensitivities(samples, sds: dict, metrics: list):
    """A table (metric, parameter, sd, effect, share, r2, samples) from the samples table;
    ``sds``: {parameter: standard deviation of its distribution}."""
    import pandas as pd

    parameters = list(sds)
    sd = np.array([sds[k] for k in parameters])
    rows = []
    for metric in metrics:
        y = samples[metric].to_numpy(float)
        X = samples[parameters].to_numpy(float)
        ok = np.isfinite(y) & np.all(np.isfinite(X), axis=1)
        y, X = y[ok], X[ok]
        var = y.var(ddof=1) if len(y) > 1 else 0.0
        if len(y) <= len(parameters) + 1 or var == 0:
            effects, r2, total = np.full(len(parameters), np.nan), np.nan, np.nan
        else:
            A = np.column_stack([np.ones(len(y)), X - X.mean(axis=0)])
            coef, *_ = np.linalg.lstsq(A, y, rcond=None)
            residual = np.sum((y - A @ coef) ** 2)
            effects = coef[1:] * sd
            r2 = 1 - residual / np.sum((y - y.mean()) ** 2)
            total = np.sum(effects ** 2) + residual / (len(y) - len(parameters) - 1)
        for j, name in enumerate(parameters):
            rows.append({"metric": metric, "parameter": name, "sd": float(sd[j]),
                         "effect": float(effects[j]), "share": float(effects[j] ** 2 / total),
                         "r2": float(r2), "samples": int(len(y))})
    return pd.DataFrame(rows)


def derivative_effects(problem, values: dict, spread) -> dict:
    """{(metric, parameter): (m(x + σ) − m(x − σ))/2}: central differences of one SD at
    the design, the other parameters at their nominal values (2 simulations per
    parameter, one parallel batch).  Where they agree with the regression's effects the
    metric is linear over the spread."""
    names = spread.names
    points = [dict(values, **{k: spread.centre(k) + sign * spread.sd(k)})
              for k in names for sign in (1, -1)]
    metrics = [problem.metrics(r) for r in problem.evaluate(points)]
    return {(t.key, k): 0.5 * (metrics[2 * j][t.key] - metrics[2 * j + 1][t.key])
            for j, k in enumerate(names) for t in problem.targets}


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
    from ..common.plotting import pyplot, save

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
