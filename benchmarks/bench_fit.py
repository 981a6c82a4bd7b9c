"""Time the two-stage fit of the paper's 4410-point protocol (target < 1 s).

The default fit includes the uncertainties (100 half-sample replicates of the
sweeps); ``n_boot=0`` is the point estimate with stage-2 errors only.

Baselines measured in the same run on the same data:
* ``SVC stage alone`` — one scikit-learn SVC(kernel="linear", C=0.1) on all 4410
  points (what the paper's stage 1 costs by itself);
* ``curve_fit direct`` — scipy.optimize.curve_fit of the full six-parameter flow
  law to the raw flows from the paper's values as start (the "one-stage" fit).

Run:  python benchmarks/bench_fit.py [--repeat 3]
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def best_of(function, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    from scipy.optimize import curve_fit
    from sklearn.svm import SVC

    from pneunet.truth.valves.identify import fit_valve, simulate_bench
    from pneunet.physics.laws import valve_flow
    from pneunet.physics.valve_params import PAPER_VALVES

    truth = PAPER_VALVES["axi"]
    data = simulate_bench(truth, seed=0)
    fit_valve(data, n_boot=5)  # warm up imports
    X = data[["p_in_kPa", "p_out_kPa", "p_ctrl_kPa"]].to_numpy()
    y = np.where(data["mdot_mg_s"] > 1.0, 1, -1)

    t_fit, fit = best_of(lambda: fit_valve(data), args.repeat)
    t_fit_noboot, _ = best_of(lambda: fit_valve(data, n_boot=0), args.repeat)
    t_paper, _ = best_of(lambda: fit_valve(data, correct_threshold=False, n_boot=0), args.repeat)
    t_svc, _ = best_of(lambda: SVC(kernel="linear", C=0.1).fit(X - X.mean(0), y), args.repeat)

    def direct():
        def model(x, Rf, pclose, ptrans, e, ain, aout):
            return valve_flow(x[0], x[1], x[2], Rf, pclose, max(ptrans, pclose + 1e-3), e,
                              ain, aout)
        return curve_fit(model, X.T, data["mdot_mg_s"].to_numpy(),
                         p0=list(truth.as_dict().values()), maxfev=2000)

    t_direct, _ = best_of(direct, args.repeat)
    print(f"data: {len(data)} points (paper protocol, axi valve, seed 0), best of {args.repeat}")
    print(f"fit_valve (defaults: correction, 100 replicates) {t_fit * 1e3:6.1f} ms "
          f"{'OK' if t_fit < 1.0 else 'SLOW'} (target < 1000 ms)")
    print(f"fit_valve n_boot=0                              {t_fit_noboot * 1e3:8.1f} ms")
    print(f"fit_valve paper procedure, n_boot=0             {t_paper * 1e3:8.1f} ms")
    print(f"baseline: sklearn SVC on all points (stage 1)   {t_svc * 1e3:8.1f} ms   "
          f"ratio fit/SVC {t_fit / t_svc:5.2f}")
    print(f"baseline: curve_fit of eq. 19 to raw flows      {t_direct * 1e3:8.1f} ms   "
          f"ratio fit/curve_fit {t_fit / t_direct:5.2f}")
    print(f"fit: Rf {fit.params.Rf:.4f} pclose {fit.params.pclose:.2f} misclassified "
          f"{fit.metrics['misclassified']}")


if __name__ == "__main__":
    main()
