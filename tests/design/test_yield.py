"""Yield under spread: the reported yield equals a brute-force simulation of the same
samples drawn independently; a fitted covariance is used; missing spread is exit 2."""
import dataclasses
import json
import math

import numpy as np
import pandas as pd
import pytest

from pneunet.engine import measure
from pneunet.interfaces.cli import main
from pneunet.common.errors import ParameterError
from pneunet.netlist import parse_file


def brute_force_period(path, rvent, pclose):
    """Period (s) of p(tank) from 7 s, simulated without pneunet.design."""
    circuit = parse_file(path, overrides={"Rvent": rvent}).circuit
    spec = circuit.elements["X1"]
    spec.params["model"] = dataclasses.replace(spec.params["model"], pclose=pclose)
    sol = circuit.tran(14.0)
    return measure.period(sol.t, sol.pressure("tank"), t_from=7.0)


def wilson_textbook(k, n, z=1.959963984540054):
    """The 95 % Wilson score interval of k successes in n trials (Wilson 1927):
    (p + z²/2n ± z·√(p(1−p)/n + z²/4n²)) / (1 + z²/n)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


@pytest.mark.parametrize("k, n", [(0, 10), (3, 12), (10, 20), (97, 100), (200, 200)])
def test_wilson_interval_is_the_95_percent_score_interval(k, n):
    from pneunet.design.yields import wilson

    assert wilson(k, n) == pytest.approx(wilson_textbook(k, n), abs=1e-12)


def test_yield_equals_brute_force_of_the_same_samples(short_oscillator, tmp_path, capsys):
    n, seed = 12, 3
    samples = tmp_path / "samples.csv"
    main(["design", str(short_oscillator), "--target", "period=3s±0.1s", "--yield", str(n),
          "--seed", str(seed), "--tolerance", "*.pclose=±5kPa", "--tolerance", "Rvent=±0.5%",
          "--samples", str(samples), "--derivatives", "--workers", "2", "--json"])
    out = json.loads(capsys.readouterr().out)["yield"]
    # the same samples drawn here: uniform p_close 96.42 ± 5 kPa, then R_vent 3 ± 0.5 %
    rng = np.random.default_rng(seed)
    pclose = 96.42 - 5 + 10 * rng.random(n)
    rvent = 3 * 0.995 + 0.03 * rng.random(n)
    table = pd.read_csv(samples)
    assert np.allclose(table["X1.pclose"], pclose, rtol=0, atol=1e-9)
    assert np.allclose(table["Rvent"], rvent, rtol=0, atol=1e-12)
    passed = sum(abs(brute_force_period(short_oscillator, rv, pc) - 3.0) <= 0.1
                 for rv, pc in zip(rvent, pclose))
    assert 0 < passed < n  # the tolerance straddles the target: a real count
    assert (out["passed"], out["n"]) == (passed, n)
    p = passed / n
    assert out["yield"] == pytest.approx(p)
    assert out["se"] == pytest.approx(math.sqrt(p * (1 - p) / n))
    assert out["interval95"] == pytest.approx(wilson_textbook(passed, n), abs=1e-12)
    assert out["most_important"] == {"period": "X1.pclose"}
    assert out["limiting_parameter"] == {"parameter": "X1.pclose", "metric": "period"}
    # p_close's effect of one SD (10/√12 kPa): the derivative by brute force, and the
    # regression on the samples agree with it (the period is near-linear in p_close)
    sd = 10 / math.sqrt(12)
    row = next(r for r in out["sensitivities"] if r["parameter"] == "X1.pclose")
    derivative = 0.5 * (brute_force_period(short_oscillator, 3.0, 96.42 + sd)
                        - brute_force_period(short_oscillator, 3.0, 96.42 - sd))
    assert row["sd"] == pytest.approx(sd)
    assert row["effect_fd"] == pytest.approx(derivative, rel=1e-3)
    assert row["effect"] == pytest.approx(derivative, rel=0.1)
    assert 0.8 < row["share"] <= 1


def test_yield_under_a_fitted_covariance(short_oscillator, tmp_path, capsys):
    """pneunet fit on a bench CSV → fit.json → the yield samples the fitted covariance."""
    from pneunet.truth.valves.identify import simulate_bench
    from pneunet.physics.valve_params import PAPER_VALVES

    bench = tmp_path / "bench.csv"
    simulate_bench(PAPER_VALVES["axi"], seed=6).to_csv(bench, index=False)
    assert main(["fit", str(bench), "--bootstrap", "20", "--json"]) == 0
    fit_json = tmp_path / "fit.json"
    fit_json.write_text(capsys.readouterr().out)
    fit = json.loads(fit_json.read_text())
    samples = tmp_path / "samples.csv"
    main(["design", str(short_oscillator), "--target", "period=3s±0.1s", "--yield", "6",
          "--fit", f"X1={fit_json}", "--samples", str(samples), "--workers", "2", "--json"])
    out = json.loads(capsys.readouterr().out)["yield"]
    spread = out["spread"]
    assert set(spread) == {f"X1.{k}" for k in fit["params"]}
    for k in fit["params"]:
        assert spread[f"X1.{k}"]["sd"] == pytest.approx(math.sqrt(fit["covariance"][k][k]))
        assert spread[f"X1.{k}"]["mean"] == pytest.approx(getattr(PAPER_VALVES["axi"], k))
    table = pd.read_csv(samples)
    assert table["X1.pclose"].nunique() == 6 and out["n"] == 6


def rc_fill(point):
    """A 1 L tank filled from 200 kPa through R (kPa·s/mg): p(0.2 s) falls as R grows."""
    from pneunet import Circuit

    c = Circuit("rc_fill", ambient=96.0)
    c.pressure_source("PS", "supply", 200.0)
    c.resistor("R1", "supply", "tank", R=point["R"])
    c.volume("V1", "tank", V=1000.0)
    return c


def test_yield_se_stops_once_the_interval_is_as_narrow_as_asked():
    """--yield-se: the early stop's Wilson interval is at most ±1.96·SE wide, its samples
    are the full run's first ones (simulated once), and its yield agrees with the full
    run's within the sampling error of the samples it left out."""
    from pneunet.design.sweep import tolerance
    from pneunet.design.problem import Problem
    from pneunet.design.spread import Spread
    from pneunet.design.yields import yield_analysis

    n_max, se, z = 150, 0.04, 1.959963984540054
    spread = Spread(independent={"R": tolerance(1.0, 0.5)})  # uniform 0.5–1.5
    problem = Problem(rc_fill, ["p_max@tank>=100kPa"], t_stop=0.2, workers=1)
    for bad in (0, 0.5, -0.1, math.nan, "0.02"):
        with pytest.raises(ParameterError, match="--yield-se.*between 0 and 0.5"):
            yield_analysis(problem, {}, spread, n=n_max, se=bad)
    assert problem.simulations == 0
    early = yield_analysis(problem, {}, spread, n=n_max, seed=1, nominal={}, se=se)
    low, high = wilson_textbook(early.passed, early.n)
    assert early.interval == pytest.approx((low, high), abs=1e-12)
    assert (high - low) / 2 <= z * se
    assert 0 < early.passed < early.n < n_max and early.simulations == early.n
    assert (early.se_target, early.n_max) == (se, n_max)
    assert (early.to_json()["se_target"], early.to_json()["n_max"]) == (se, n_max)
    assert f"stopped at {early.n} of at most {n_max}" in early.report()
    full = yield_analysis(problem, {}, spread, n=n_max, seed=1, nominal={})
    assert full.simulations == n_max - early.n  # the early samples came from the cache
    assert np.array_equal(full.samples["R"][:early.n], early.samples["R"])
    assert np.array_equal(full.samples["pass"][:early.n], early.samples["pass"])
    p = full.yield_
    assert 0.1 < p < 0.9
    assert abs(early.yield_ - p) <= 3 * math.sqrt(p * (1 - p) * (1 / early.n - 1 / n_max))
    # it went on past its first batch (64 samples) because that one was not narrow enough
    first = int(early.samples["pass"][:64].sum())
    low64, high64 = wilson_textbook(first, 64)
    assert early.n > 64 and (high64 - low64) / 2 > z * se
    short = yield_analysis(problem, {}, spread, n=16, seed=1, nominal={}, se=se)
    assert (short.n, short.simulations) == (16, 0)  # the same first 16 samples, cached
    assert "all 16 samples drawn: the Wilson half-width" in short.report()


def test_yield_se_on_the_command_line(tmp_path, capsys):
    """--yield-se reaches the yield: its JSON says what was asked and where it stopped."""
    netlist = tmp_path / "rc.pn"
    netlist.write_text(".param R=1\nPS supply 200kPa\nR1 supply tank {R}kPa*s/mg\n"
                       "V1 tank 1000mL\n.tran 10ms 0.2s\n")
    assert main(["design", str(netlist), "--target", "p_max@tank>=100kPa", "--yield", "20",
                 "--yield-se", "0.3", "--tolerance", "R=±50%", "--workers", "1",
                 "--json"]) in (0, 1)
    out = json.loads(capsys.readouterr().out)["yield"]
    assert (out["se_target"], out["n_max"], out["n"]) == (0.3, 20, 20)
    low, high = out["interval95"]
    assert (high - low) / 2 <= 1.959963984540054 * 0.3


def test_yield_se_without_yield_is_exit_2(short_oscillator, capsys):
    argv = ["design", str(short_oscillator), "--target", "period=3s", "--yield-se", "0.02"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--yield-se needs --yield N" in err and "Traceback" not in err


@pytest.mark.parametrize("args, message", [
    (["--yield-se", "0"], "argument --yield-se: 0: must be > 0 (the yield's standard error"),
    (["--yield-se", "2%"], "argument --yield-se: '2%' is not a number"),
    (["--yield-se", "0.5"], "must be < 0.5"),
    ([], "the .model cards carry no uncertainty (valves: X1 (axi_0p6mm))"),
    (["--tolerance", "X1.pclos=±5kPa"], "did you mean 'pclose'?"),
    (["--tolerance", "X1.pclose=5kPa"], "cannot read tolerance"),
    (["--fit", "X1=missing.json"], "cannot read the fit"),
])
def test_yield_bad_input_is_exit_2(short_oscillator, capsys, args, message):
    argv = ["design", str(short_oscillator), "--target", "period=3s", "--yield", "5",
            "--json"] + args
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and message in captured.err and "Traceback" not in captured.err
