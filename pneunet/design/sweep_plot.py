"""Figure of a one-parameter sweep: one panel per measured quantity, with units.

Failed points (an error in the table), points without oscillation and points where a
measurement has no value are marked at the foot of the panels, never dropped; the
legend sits below the panels.
"""
from __future__ import annotations

import numpy as np

#: (columns, axis label) of the quantities an oscillation sweep measures
QUANTITIES = ((("period_s",), "period (s)"),
              (("p_min", "p_max"), "pressure extremes (kPa abs)"),
              (("duty_cycle",), "duty cycle (fraction of a period)"))

#: axis labels with units of the oscillator's sweep parameters
PARAMETER_LABELS = {"Rout": "R_out (kPa·s/mg)", "Rvent": "R_vent (kPa·s/mg)", "V": "V (mL)",
                    "pH": "p_H (kPa abs)", "pL": "p_L (kPa abs)", "n": "polytropic exponent n",
                    "V_out": "V_out (mL)", "R_tube": "R_tube (kPa·s/mg)",
                    "dead_volume": "dead volume (mL)"}

NOT_MEASURED = ("elapsed_s", "cycles", "solver_messages", "final", "frequency_hz",
                "amplitude_ratio", "period_change", "t_simulated", "rise_fraction")


def parameter_label(name: str) -> str:
    """Axis label of a swept parameter: with its unit where known."""
    return PARAMETER_LABELS.get(name, name)


def plot_sweep(table, x: str, path=None, title: str | None = None, units=None):
    """Each measured quantity of ``table`` (a sweep's table) against parameter ``x``;
    ``units``: {column: unit} of a ``.meas`` sweep's measurements."""
    from ..common.plotting import pyplot, save

    if "period_s" in table:  # an oscillation analysis
        panels = [(cols, label) for cols, label in QUANTITIES if all(c in table for c in cols)]
    else:  # a .meas sweep: its measurements, one panel per unit
        by_unit: dict[str, list] = {}
        for c in table.columns:
            if c != x and c not in NOT_MEASURED and table[c].dtype.kind == "f":
                by_unit.setdefault((units or {}).get(c, ""), []).append(c)
        panels = [(tuple(cols), ", ".join(cols) + (f" ({unit})" if unit else ""))
                  for unit, cols in list(by_unit.items())[:4]]
    failed = table["error"].notna().to_numpy() if "error" in table else np.zeros(len(table), bool)
    still = (~table["oscillating"].astype(bool).to_numpy() & ~failed
             if "oscillating" in table else np.zeros(len(table), bool))
    plt = pyplot()
    fig, axes = plt.subplots(max(len(panels), 1), 1, sharex=True, squeeze=False,
                             figsize=(6.4, 1.2 + 1.9 * max(len(panels), 1)))
    xs = table[x].to_numpy(float)
    for ax, (cols, label) in zip(axes[:, 0], panels):
        for c in cols:
            ax.plot(xs[~failed], table[c].to_numpy(float)[~failed], "o-", ms=4,
                    label=c if len(cols) > 1 else None)
        ax.set_ylabel(label, fontsize=9)
        foot = ax.get_xaxis_transform()  # x in data, y in axes fraction
        unmeasured = table[list(cols)].isna().all(axis=1).to_numpy() & ~failed & ~still
        if unmeasured.any():
            ax.plot(xs[unmeasured], np.full(unmeasured.sum(), 0.04), "d", mfc="none",
                    color="0.45", transform=foot, label="not measured")
        if still.any():
            ax.plot(xs[still], np.full(still.sum(), 0.04), "o", mfc="none", color="0.45",
                    transform=foot, label="no oscillation")
        if failed.any():
            ax.plot(xs[failed], np.full(failed.sum(), 0.04), "x", color="crimson", mew=2,
                    transform=foot, label="simulation failed")
    axes[-1, 0].set_xlabel(parameter_label(x))
    counts = f"{len(table)} points"
    counts += f", {int(failed.sum())} failed" if failed.any() else ""
    counts += f", {int(still.sum())} without oscillation" if still.any() else ""
    fig.suptitle(title or f"sweep of {x} ({counts})", fontsize=10)
    handles = {}
    for ax in axes[:, 0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    if handles:
        fig.legend(handles.values(), handles.keys(), loc="upper center", fontsize=8,
                   bbox_to_anchor=(0.5, 0.0), ncol=len(handles), frameon=False)
    fig.tight_layout()
    return save(fig, path) if path is not None else fig
