"""Flow amplification (paper sec. 6.1, Fig. 10): membrane valve vs a Clippard-like valve.

    python examples/amplifier/amplifier.py [-o OUTDIR]

A McKibben actuator is filled from p_H = 289 kPa by an in-valve and emptied to
p_L = 120 kPa by an out-valve; the valves' control pressures switch every 5 s.
The same circuit is simulated with the paper's mirror-symmetric membrane valves
and with an electronic valve of the Clippard's resistance (7.752 kPa·s/mg);
both rise times are printed, the traces are written as CSV and plotted.
"""
import argparse
from pathlib import Path

import numpy as np

from pneunet.design.paper_circuits import CLIPPARD_LIKE, flow_amplifier
from pneunet.common.plotting import pyplot, save


def rise_time(t, p, start, low=120.0, high=289.0, lo_frac=0.1, hi_frac=0.9):
    """10–90 % rise time of ``p`` after ``start`` (s)."""
    sel = t >= start
    t, p = t[sel], p[sel]
    a, b = low + lo_frac * (high - low), low + hi_frac * (high - low)
    return np.interp(b, p, t) - np.interp(a, p, t) if p.max() >= b else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--outdir", default=Path(__file__).parent / "out", type=Path)
    args = parser.parse_args()
    args.outdir.mkdir(parents=True, exist_ok=True)

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    for label, valve in (("membrane valve (mirror)", "mirror"),
                         ("Clippard-like, R = 7.752 kPa·s/mg", CLIPPARD_LIKE)):
        sol = flow_amplifier(valve).tran(30.0, t_step=0.005)
        t, p = sol.t, sol.pressure("act")
        first = t <= 5.0
        rise = rise_time(t[first], p[first], 0.0)
        print(f"{label}: 10–90 % rise time {rise * 1e3:.0f} ms, "
              f"end of fill {p[first][-1]:.1f} kPa, end of vent "
              f"{p[t <= 10.0][-1]:.1f} kPa")
        name = "membrane" if valve == "mirror" else "clippard"
        sol.to_csv(args.outdir / f"amplifier_{name}.csv")
        ax.plot(t, p, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("actuator pressure (kPa abs)")
    ax.legend()
    print(f"wrote {save(fig, args.outdir / 'amplifier.png')}")


if __name__ == "__main__":
    main()
