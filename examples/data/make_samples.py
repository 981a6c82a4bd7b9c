"""Write the sample measurement files of the README's ``fit``, ``diagnose`` and
``fit-trace`` commands (run from anywhere: ``python examples/data/make_samples.py [OUT_DIR]``, default
this directory).

* ``bench_axi.csv`` — static bench data of the paper's axi valve from the virtual bench
  (:func:`pneunet.truth.valves.identify.simulate_bench`: the paper's protocol, 4410 held points in
  210 sweeps; sensor noise, setpoint errors, seed 0).
* ``oscillator_rec.csv`` — a 30 s recording of ``netlists/oscillator.pn`` (R_out =
  1.132 kPa·s/mg): ``p_tank_kPa`` and ``p_out_kPa`` every 50 ms with 0.4 kPa of noise.

The files are deterministic: rerunning this script rewrites them byte for byte.
"""
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def bench(path: Path) -> None:
    from pneunet.truth.valves.identify import simulate_bench
    from pneunet.physics.valve_params import PAPER_VALVES

    data = simulate_bench(PAPER_VALVES["axi"], seed=0)
    columns = ["time_s", "p_in_kPa", "p_out_kPa", "p_ctrl_kPa", "mdot_mg_s", "sweep"]
    with path.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write("# virtual bench: the paper's axi valve and protocol, seed 0\n"
                 "# written by examples/data/make_samples.py\n")
        data[columns].to_csv(fh, index=False, float_format="%.3f", lineterminator="\n")


def recording(path: Path) -> None:
    from pneunet.netlist import parse_file

    circuit = parse_file(ROOT / "netlists" / "oscillator.pn").circuit
    sol = circuit.tran(30.0, progress=False)
    t = np.arange(0.0, 30.0 + 1e-9, 0.05)
    rng = np.random.default_rng(0)
    import pandas as pd

    frame = pd.DataFrame({"time_s": t})
    for node in ("tank", "out"):
        frame[f"p_{node}_kPa"] = np.interp(t, sol.t, sol.pressure(node)) \
            + 0.4 * rng.standard_normal(len(t))
    with path.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write("# netlists/oscillator.pn simulated for 30 s, 0.4 kPa noise, seed 0\n"
                 "# written by examples/data/make_samples.py\n")
        frame.to_csv(fh, index=False, float_format="%.4f", lineterminator="\n")


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    bench(out / "bench_axi.csv")
    recording(out / "oscillator_rec.csv")
    print(f"wrote {out / 'bench_axi.csv'} and {out / 'oscillator_rec.csv'}")


if __name__ == "__main__":
    import sys

    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
