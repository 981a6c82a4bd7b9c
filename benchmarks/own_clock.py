"""The inverter chain recorded on the logger's own clock, fitted next to the same
recording on the sources' clock (benchmarks/README.md, "The inverter chain on the
logger's own clock").

    python benchmarks/own_clock.py 6.7 3.3 1.1 5.0     # logger start times on the sources' clock

Stand-alone recordings (tests/traces/standalone_inverter.py, no pneunet code): R_pull 23
(the netlist says 20), 50 Hz, 0.3 kPa noise, 16 s; the own clock counts from 0.
"""
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pneunet.netlist.builder import NetlistBuilder  # noqa: E402
from pneunet.truth.circuits import fit_trace  # noqa: E402
from tests.traces.standalone_inverter import inverter_record  # noqa: E402

PARAMS = {"Rpull": (20.0, 2.0, 200.0), "X1.Vout.V": (2.5, 0.2, 20.0),
          "X2.Vout.V": (2.5, 0.2, 20.0)}


def main(starts):
    build = NetlistBuilder(str(ROOT / "netlists" / "inverter.pn"))
    for start in starts:
        rec = inverter_record(start, 16.0, dt=0.02, noise=0.3, seed=3, Rpull=23.0)
        own = rec.copy()
        own["time_s"] = 0.02 * np.arange(len(own))
        for name, r in (("sources' clock", rec), ("own clock", own)):
            t = time.perf_counter()
            f = fit_trace(build, r, PARAMS, node="out1")
            ci = ", ".join(f"{k} {f.values[k]:.4g} [{lo:.4g}, {hi:.4g}]"
                           for k, (lo, hi) in f.ci.items())
            rms = ", ".join(f"{k} {v:.3f}" for k, v in f.rmse.items())
            print(f"start {start:g} s, {name}: first sample at {f.start_state.first_time:.4f} s"
                  f" (≡ {f.start_state.first_time % 4.0:.4f} mod the 4 s period); {ci}; "
                  f"rms {rms} kPa; {time.perf_counter() - t:.1f} s", flush=True)


if __name__ == "__main__":
    main([float(a) for a in sys.argv[1:]] or [6.7])
