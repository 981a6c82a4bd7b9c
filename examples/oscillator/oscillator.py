"""The paper's single-valve oscillator (sec. 6.2), designed in Python.

    python examples/oscillator/oscillator.py [-o OUTDIR] [--rout R]

Builds the circuit of Fig. 11A, simulates 30 s, writes the trace as CSV and a
plot as PNG, and prints the oscillation period and pressure swing.
"""
import argparse
from pathlib import Path

from pneunet import Circuit
from pneunet.engine.oscillation import analyze_oscillation


def build(r_out: float) -> Circuit:
    c = Circuit("pneumatic oscillator", ambient=96.0)      # the lab's atmosphere, kPa
    c.pressure_source("PH", "supply", "400kPag")             # p_H = 496 kPa abs
    c.valve("X1", "supply", "out", "tank", model="axi")      # in, out, ctrl
    if r_out > 0:
        c.resistor("Rout", "out", "tank", R=r_out)           # kPa·s/mg
    else:
        c.resistor("Rout", "out", "tank", R=1e-3)            # practically a wire
    c.volume("V1", "tank", V="200mL", p0="96kPa")
    c.resistor("Rvent", "tank", "atm", R=3.0)                # vent to p_L = 96 kPa
    return c


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--outdir", default=Path(__file__).parent / "out", type=Path)
    parser.add_argument("--rout", type=float, default=2 * 0.566,
                        help="output resistance R_out in kPa·s/mg (default 2 R_f = 1.132)")
    parser.add_argument("--t-stop", type=float, default=30.0, help="simulated time, s")
    args = parser.parse_args()

    solution = build(args.rout).tran(args.t_stop, progress=True)
    args.outdir.mkdir(parents=True, exist_ok=True)
    csv = args.outdir / "oscillator.csv"
    png = args.outdir / "oscillator.png"
    solution.to_csv(csv)
    solution.plot(png, signals=["p_supply", "p_out", "p_tank", "mdot_X1", "mdot_Rvent"])

    osc = analyze_oscillation(solution.t, solution.pressure("tank"))
    print(f"R_out = {args.rout:g} kPa·s/mg: {osc.kind}")
    if osc.oscillating:
        print(f"period = {osc.period_s:.4f} s  ({osc.frequency_hz:.4f} Hz), "
              f"p_tank {osc.p_min:.1f} … {osc.p_max:.1f} kPa, duty cycle {osc.duty_cycle:.2f}")
    else:
        print(f"equilibrium p_tank = {osc.final:.2f} kPa")
    print(f"IDA: {solution.stats['residual_calls']} residual calls, "
          f"{solution.stats['branch_jumps']} branch jumps, {solution.stats['wall_time_s']:.2f} s")
    print(f"wrote {csv} and {png}")


if __name__ == "__main__":
    main()
