"""Big measurement files: peak memory and time of ``pneunet fit`` (bench data) and
``pneunet fit-trace`` (a recording) on files of millions of rows (issue 17).

    python benchmarks/bench_bigdata.py                  # 2e6 and 1e7 bench rows, 2e6 samples
    python benchmarks/bench_bigdata.py --rows 2000000   # one size

The files are written once to --dir (default /tmp/pneunet-bigdata; 1e7 rows ≈ 0.5 GB):
a long bench log (the paper's protocol run again and again with new noise) and a fast
logger's recording (the 30 s sample recording of examples/data at 2e6 samples).  Each command runs
in its own process under ``/usr/bin/time -v`` (peak resident memory) with the default
row caps (``--max-rows``): the file is streamed and thinned evenly with a notice.
"""
import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "examples" / "data"


def bench_file(rows: int, path: Path) -> Path:
    """A long bench log: the paper's protocol on the axi valve run again and again
    (seed k for run k, times continuing), cut at ``rows`` data rows."""
    from pneunet.truth.valves.identify import simulate_bench
    from pneunet.physics.valve_params import PAPER_VALVES

    if path.exists():
        return path
    columns = ["time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s", "sweep"]
    with path.open("w") as fh:
        fh.write(",".join(columns) + "\n")
        written, seed, t0 = 0, 0, 0.0
        while written < rows:
            run = simulate_bench(PAPER_VALVES["axi"], seed=seed, include_truth=False)[columns]
            run = run.assign(time_s=run.time_s + t0).iloc[:rows - written]
            run.to_csv(fh, header=False, index=False, float_format="%.4f")
            written, seed, t0 = written + len(run), seed + 1, float(run.time_s.iloc[-1]) + 5
    return path


def trace_file(rows: int, path: Path) -> Path:
    """A fast logger: the 30 s sample recording interpolated to ``rows`` samples."""
    if path.exists():
        return path
    base = pd.read_csv(SAMPLES / "oscillator_rec.csv", comment="#")
    t = np.linspace(0.0, float(base.time_s.iloc[-1]), rows)
    with path.open("w") as fh:
        fh.write(",".join(base.columns) + "\n")
        for part in np.array_split(np.arange(rows), max(1, rows // 200_000)):
            frame = pd.DataFrame({c: np.interp(t[part], base.time_s, base[c]) for c in base})
            frame.to_csv(fh, header=False, index=False, float_format="%.6f")
    return path


def measure(argv) -> dict:
    """Wall time, peak RSS (MB), exit code and the notes printed by one CLI run."""
    t0 = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "pneunet", *argv],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr).group(1))
    notes = [line for line in proc.stderr.splitlines() if "note:" in line or "error:" in line]
    return {"wall_s": wall, "peak_mb": peak / 1024, "rc": proc.returncode, "notes": notes}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[2_000_000, 10_000_000])
    ap.add_argument("--trace-rows", type=int, nargs="*", default=[2_000_000])
    ap.add_argument("--dir", default="/tmp/pneunet-bigdata")
    args = ap.parse_args()
    out = Path(args.dir)
    out.mkdir(parents=True, exist_ok=True)
    runs = []
    for n in args.rows:
        path = bench_file(n, out / f"bench_{n}.csv")
        runs.append((f"fit, {n:,} bench rows ({path.stat().st_size / 1e6:.0f} MB)",
                     ["fit", str(path), "--bootstrap", "10"]))
    for n in args.trace_rows:
        path = trace_file(n, out / f"trace_{n}.csv")
        runs.append((f"fit-trace, {n:,} samples ({path.stat().st_size / 1e6:.0f} MB)",
                     ["fit-trace", str(path), str(ROOT / "netlists" / "oscillator.pn"),
                      "--fit", "Rout=1.4:0.3:5", "--max-nfev", "4", "--no-progress"]))
    print(f"{'run':<48} {'wall s':>8} {'peak MB':>8} {'rc':>3}")
    for label, argv in runs:
        r = measure(argv)
        print(f"{label:<48} {r['wall_s']:8.1f} {r['peak_mb']:8.0f} {r['rc']:3d}")
        for note in r["notes"]:
            print(f"    {note}")


if __name__ == "__main__":
    main()
