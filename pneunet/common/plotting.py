"""The one module that imports matplotlib.

Plot functions elsewhere in pneunet call :func:`pyplot` to get matplotlib's
pyplot with a non-interactive backend, draw, and save with :func:`save`.
"""
from __future__ import annotations

import functools
from pathlib import Path


@functools.lru_cache(maxsize=1)
def pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no screen needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def figure_and_patches():
    """(matplotlib's ``Figure``, ``matplotlib.patches``) on the Agg backend: for drawings
    made without pyplot's global state (the schematic)."""
    from matplotlib import patches
    from matplotlib.figure import Figure

    pyplot()  # the Agg backend
    return Figure, patches


def save(fig, path) -> Path:
    """Save ``fig`` as PNG at ``path`` (folders created), close it, return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    pyplot().close(fig)
    return path


def identical_groups(traces: dict, tol: float = 1e-2) -> list[list[str]]:
    """Names of the traces grouped where they coincide on a plot (differences within
    ``tol`` of the first one's range), in first-seen order."""
    import numpy as np

    groups: list[list[str]] = []
    for name, y in traces.items():
        for group in groups:
            ref = traces[group[0]]
            scale = tol * max(float(np.ptp(ref)) if ref.size else 0.0, 1e-9)
            if ref.shape == y.shape and np.allclose(ref, y, rtol=0.0, atol=scale):
                group.append(name)
                break
        else:
            groups.append([name])
    return groups


def draw_traces(ax, t, traces: dict, ylabel: str) -> None:
    """Plot ``traces`` ({label: values}) against ``t``: traces that coincide are one
    line labelled ``a = b = c`` (and a note says so), the legend outside on the right."""
    groups = identical_groups(traces)
    for group in groups:
        label = " = ".join(group) if len(group) <= 3 else \
            " = ".join(group[:2]) + f" = … ({len(group)} traces)"
        ax.plot(t, traces[group[0]], label=label)
    ax.set_ylabel(ylabel)
    legend_outside(ax, fontsize="small")
    if len(groups) < len(traces):
        ax.text(0.0, 1.01, "traces that coincide (within 1 % of their range) are drawn "
                "once, labelled a = b",
                transform=ax.transAxes, fontsize="x-small", color="0.35", va="bottom")


def legend_outside(ax, *args, **kwargs):
    """The axes' legend right of the axes, off the data (``args``: handles, labels)."""
    kwargs.setdefault("frameon", False)
    return ax.legend(*args, loc="upper left", bbox_to_anchor=(1.01, 1.0), **kwargs)
