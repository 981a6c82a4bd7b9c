"""Big measurement files: peak memory and time of ``pneunet fit`` (bench data) and
``pneunet fit-trace`` (a recording) on files of millions of rows (issue 17).

    python benchmarks/bench_bigdata.py                  # 2e6 and 1e7 bench rows, 2e6 samples
    python benchmarks/bench_bigdata.py --rows 2000000   # one size

The files are written once to --dir (default /tmp/pneunet-bigdata; 1e7 rows ≈ 0.5 GB):
the sample bench data of examples/data repeated with times that continue, and the
sample recording of the oscillator repeated (its cycle continues).  Each command runs
in its own process under ``/usr/bin/time -v`` (peak resident memory) with the default
row caps (``--max-rows``): the file is streamed and thinned evenly with a notice.
"""
import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "examples" / "data"


def repeated(sample: Path, rows: int, path: Path, period: float) -> Path:
    """``sample`` repeated until ``rows`` data rows, time shifted by ``period`` per copy."""
    if path.exists():
        return path
    base = pd.read_csv(sample, comment="#")
    block = max(1, 200_000 // len(base))
    with path.open("w") as fh:
        fh.write(",".join(base.columns) + "\n")
        written, copy = 0, 0
        while written < rows:
            chunk = pd.concat([base.assign(time_s=base.time_s + (copy + k) * period)
                               for k in range(block)], ignore_index=True)
            chunk = chunk.iloc[:rows - written]
            chunk.to_csv(fh, header=False, index=False, float_format="%.4f")
            written += len(chunk)
            copy += block
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
    bench_period = float(pd.read_csv(SAMPLES / "bench_axi.csv", comment="#").time_s.iloc[-1]) + 5
    runs = []
    for n in args.rows:
        path = repeated(SAMPLES / "bench_axi.csv", n, out / f"bench_{n}.csv", bench_period)
        runs.append((f"fit, {n:,} bench rows ({path.stat().st_size / 1e6:.0f} MB)",
                     ["fit", str(path), "--bootstrap", "10"]))
    for n in args.trace_rows:
        path = repeated(SAMPLES / "oscillator_rec.csv", n, out / f"trace_{n}.csv", 30.05)
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
