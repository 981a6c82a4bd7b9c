"""A McKibben muscle driven by a circuit (issue 12, the paper's Fig. 12): the cycle of
its driving pressure and of its contraction, measured and drawn."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.reprs import Summarized, number
from ..engine.oscillation import Oscillation, analyze_oscillation


@dataclass(frozen=True, repr=False)
class MuscleCycle(Summarized):
    """:func:`muscle_cycle`'s result: the oscillations of the driving pressure (kPa) and
    of the contraction (mm) over the last full cycles after the settling time."""

    muscle: str
    node: str
    pressure: Oscillation
    contraction: Oscillation

    @property
    def amplitude_mm(self) -> float:
        """Peak-to-peak contraction over the last full cycles, mm."""
        return self.contraction.p_max - self.contraction.p_min

    def _summary(self):
        p, x = self.pressure, self.contraction
        rows = [("period", number(p.period_s, "s")),
                (f"p({self.node})", f"{p.p_min:.4g}–{p.p_max:.4g} kPa"),
                (f"contraction({self.muscle})", f"{x.p_min:.4g}–{x.p_max:.4g} mm "
                                                f"(swing {self.amplitude_mm:.3g} mm)")]
        return p.kind, rows, ".pressure, .contraction (Oscillation), .amplitude_mm"


def muscle_cycle(sol, muscle: str, node: str, *, settle: float = 10.0,
                 min_swing_mm: float = 0.01) -> MuscleCycle:
    """The cycle of p(``node``) and contraction(``muscle``) in ``sol`` after ``settle`` s
    (:func:`~pneunet.engine.oscillation.analyze_oscillation` on each); a contraction
    swinging less than ``min_swing_mm`` counts as still."""
    after = sol.t >= settle
    t = sol.t[after]
    return MuscleCycle(muscle, node, analyze_oscillation(t, sol.pressure(node)[after]),
                       analyze_oscillation(t, sol[f"contraction_{muscle}"][after],
                                           min_amplitude=min_swing_mm))


def plot_muscle_run(sol, muscle: str, nodes=("tank",), path=None, title=None,
                    settle: float = 10.0):
    """Pressures of ``nodes`` (kPa, top), the muscle's contraction (mm, middle) and the
    contraction after ``settle`` s drawn at its own scale (bottom) against time, as the
    paper's Fig. 12B; saves a PNG at ``path`` or returns the figure."""
    from ..common.plotting import draw_traces, legend_outside, pyplot, save

    plt = pyplot()
    fig, (top, middle, bottom) = plt.subplots(3, 1, sharex=True, figsize=(8, 7),
                                              gridspec_kw={"height_ratios": [3, 2, 2]})
    draw_traces(top, sol.t, {f"p({n})": sol.pressure(n) for n in nodes},
                "pressure (kPa abs)")
    x = np.asarray(sol[f"contraction_{muscle}"])
    later = sol.t >= settle
    for ax, label in ((middle, f"contraction({muscle})"),
                      (bottom, f"contraction({muscle}) after {settle:g} s")):
        ax.plot(sol.t if ax is middle else sol.t[later], x if ax is middle else x[later],
                color="tab:red", label=label)
        ax.set_ylabel("contraction (mm)")
        legend_outside(ax, fontsize="small")
    bottom.set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    return save(fig, path) if path is not None else fig
