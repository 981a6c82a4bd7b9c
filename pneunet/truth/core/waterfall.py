"""The error waterfall: base model → + best effect → + next, held-out error per step,
as a table, as JSON and as a bar chart (shared by valve and circuit diagnoses)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .verdict import Step


@dataclass
class Waterfall:
    """Held-out errors of successive models with the noise floor, in ``unit``."""

    steps: list  # of Step
    floor: float
    unit: str
    base_label: str = "base model"

    def labels(self) -> list[str]:
        return [self.base_label if i == 0 else f"+ {s.label}" for i, s in enumerate(self.steps)]

    def table(self) -> str:
        """Plain-text table: label, held-out error, change, ratio to the floor (and the
        fitted window's error where known)."""
        fitted = any(np.isfinite(s.train) for s in self.steps)
        lines = [f"    {'model':<28}{'held-out':>10}{'change':>10}{'× floor':>9}"
                 + (f"{'fitted':>10}" if fitted else "") + f"  ({self.unit})"]
        prev = None
        for lab, s in zip(self.labels(), self.steps):
            change = "" if prev is None else f"{s.held_out - prev:+10.3g}"
            ratio = s.held_out / self.floor if self.floor > 0 else float("nan")
            lines.append(f"    {lab:<28}{s.held_out:10.3g}{change:>10}{ratio:9.2f}"
                         + (f"{s.train:10.3g}" if fitted else ""))
            prev = s.held_out
        lines.append(f"    {'noise floor':<28}{self.floor:10.3g}")
        return "\n".join(lines)

    def to_json(self) -> list:
        return [dict(s.to_json(), label=lab) for lab, s in zip(self.labels(), self.steps)]

    def draw(self, ax, tolerance: float | None = None) -> None:
        """Bars on a matplotlib axis: the first full, each next one the drop it brings."""
        vals = [s.held_out for s in self.steps]
        ses = np.array([s.se for s in self.steps], float)
        x = np.arange(len(vals))
        bottoms = [0.0] + vals[1:]
        heights = [vals[0]] + [vals[i - 1] - vals[i] for i in range(1, len(vals))]
        colors = ["#4c72b0"] + ["#55a868"] * (len(vals) - 1)
        ax.bar(x, heights, bottom=bottoms, color=colors, width=0.6)
        if np.isfinite(ses).any():
            ax.errorbar(x, vals, yerr=1.96 * np.nan_to_num(ses), fmt="none", ecolor="k",
                        capsize=4)
        ax.axhline(self.floor, color="#c44e52", ls="--",
                   label=f"noise floor {self.floor:.3g} {self.unit} (from data)")
        if tolerance:
            ax.axhline(tolerance * self.floor, color="#c44e52", ls=":",
                       label=f"{tolerance:g} × noise floor")
        ax.set_xticks(x, self.labels(), rotation=20)
        ax.set_ylabel(f"held-out error [{self.unit}]")
        for xi, v in zip(x, vals):
            ax.text(xi, v, f"{v:.3g}", ha="center", va="bottom", fontsize=8)
        from ...common.plotting import legend_outside

        legend_outside(ax, fontsize=8)

    def plot(self, path, title: str = "error waterfall", tolerance: float | None = None):
        """Save the waterfall as an image (PNG by suffix)."""
        from ...common.plotting import pyplot, save

        plt = pyplot()
        fig, ax = plt.subplots(figsize=(1.6 * len(self.steps) + 3, 4))
        self.draw(ax, tolerance)
        ax.set_title(title, fontsize=10)
        fig.tight_layout()
        return save(fig, path)


__all__ = ["Step", "Waterfall"]
