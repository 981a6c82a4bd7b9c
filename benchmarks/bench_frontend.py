"""Front-end benchmark (issue 18): parse + elaborate + validate + assemble an array netlist.

The netlist is ``benchmarks/cells10k.pn``'s text for N cells (``.param N``, ``Xcell[0:N-1]``):
each cell is a PULSE control source with its own delay {0.2 + 4*index/N} feeding a control
volume through a resistor, a valve from the shared supply line to the cell's actuator
volume, and a vent resistor.  Times are the best of ``--repeat`` runs of
``parse_netlist`` (parse + elaborate), ``circuit.validate()`` and ``CircuitDAE(circuit)``;
the growth exponent is the slope of log(total) against log(N) between the two largest sizes,
and the least-squares slope over all sizes.

Run:  python benchmarks/bench_frontend.py [--sizes 1000,3000,10000,30000] [--repeat 3]
          [--profile N]     (cProfile of one run at N cells, top 25 by own time)
"""
from __future__ import annotations

import argparse
import math
import re
import time
from pathlib import Path

CELLS = Path(__file__).resolve().parent / "cells10k.pn"


def netlist_text(n: int) -> str:
    """``benchmarks/cells10k.pn`` with N cells."""
    text = CELLS.read_text()
    text = re.sub(r"^\.param N=\d+", f".param N={n}", text, flags=re.M)
    return text.replace("[0:9999]", f"[0:{n - 1}]").replace("act[9999]", f"act[{n - 1}]")


def run_once(text: str):
    from pneunet.engine.assembly import CircuitDAE
    from pneunet.netlist import parse_netlist

    t0 = time.perf_counter()
    deck = parse_netlist(text, str(CELLS), limits={"max_elements": 1_000_000})
    t1 = time.perf_counter()
    deck.circuit.validate()
    t2 = time.perf_counter()
    dae = CircuitDAE(deck.circuit)
    t3 = time.perf_counter()
    return dict(parse=t1 - t0, validate=t2 - t1, assemble=t3 - t2, total=t3 - t0,
                nodes=len(deck.circuit.nodes), elements=len(deck.circuit.elements), n=dae.n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,3000,10000,30000")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--profile", type=int, default=0, metavar="N")
    args = ap.parse_args()
    if args.profile:
        import cProfile
        import pstats

        text = netlist_text(args.profile)
        cProfile.runctx("run_once(text)", globals(), {"text": text}, "/tmp/bench_frontend.prof")
        pstats.Stats("/tmp/bench_frontend.prof").sort_stats("tottime").print_stats(25)
        return
    sizes = [int(s) for s in args.sizes.split(",")]
    print(f"{'cells':>7} {'nodes':>7} {'elements':>8} {'parse+elab s':>12} {'validate s':>10} "
          f"{'assemble s':>10} {'total s':>8}")
    totals = []
    for n in sizes:
        text = netlist_text(n)
        runs = [run_once(text) for _ in range(args.repeat)]
        best = {k: min(r[k] for r in runs) for k in ("parse", "validate", "assemble", "total")}
        r = runs[0]
        totals.append(best["total"])
        print(f"{n:>7} {r['nodes']:>7} {r['elements']:>8} {best['parse']:>12.3f} "
              f"{best['validate']:>10.3f} {best['assemble']:>10.3f} {best['total']:>8.3f}",
              flush=True)
    if len(sizes) >= 2:
        slope = math.log(totals[-1] / totals[-2]) / math.log(sizes[-1] / sizes[-2])
        print(f"growth {sizes[-2]} -> {sizes[-1]} cells: x{totals[-1] / totals[-2]:.2f} "
              f"(exponent {slope:.2f})")
    if len(sizes) >= 3:
        import numpy as np

        fit = np.polyfit(np.log(sizes), np.log(totals), 1)[0]
        print(f"growth exponent over all sizes (least squares of log total on log N): "
              f"{fit:.2f} (target ≤ 1.1)")


if __name__ == "__main__":
    main()
