"""Two-stage identification: round trips on bench data, figures of merit, outputs."""
import json
import re

import numpy as np
import pytest

from pneunet.common.errors import DataError
from pneunet.truth.valves.identify import fit_valve, simulate_bench
from pneunet.truth.valves.identify.fit import NAMES, auto_mdot_min
from pneunet.physics.valve_params import PAPER_VALVES, ValveParams


VALVES = ("axi", "mirror_forward", "mirror_backward")


def _misses(fits, truth):
    """Per parameter, the seeds whose 95 % interval misses the truth."""
    return {k: [seed for seed, fit in fits.items()
                if not fit.ci95[k][0] <= getattr(truth, k) <= fit.ci95[k][1]] for k in NAMES}


@pytest.mark.parametrize("name", VALVES)
def test_round_trip_accuracy_every_seed(round_trips, name):
    """Done-criterion 1, accuracy: realistic bench data (4410 points), every seed."""
    truth = PAPER_VALVES[name]
    for seed, fit in round_trips(name, mdot_min="auto").items():
        assert fit.metrics["n"] == 4410
        assert all(fit.stderr[k] > 0 for k in NAMES), seed
        assert fit.params.Rf == pytest.approx(truth.Rf, rel=0.03), seed
        assert fit.params.ain + fit.params.aout == pytest.approx(truth.ain + truth.aout,
                                                                 rel=0.03), seed
        assert abs(fit.params.pclose - truth.pclose) < 5.0, seed


def test_round_trip_intervals_hold_the_truth(round_trips):
    """Done-criterion 1, intervals: over the first seeds of all three valves.

    A 95 % interval misses in 1 fit of 20, so no single seed can be required to
    pass all six checks.  Counted over 3 valves × 6 seeds (18 fits per parameter),
    each parameter's interval must hold the truth in at least 15: with independent
    fits and honest intervals a 4th miss has probability ~1 % (~28 % at the old
    ~85 % coverage).  The valves share the seeds' noise draws, which makes misses
    cluster: in the 110-seed study (benchmarks/coverage_fit.py, docs/identify.md)
    16 of the 18 blocks of 6 consecutive seeds pass; seeds 0-5 have 3 misses at most
    and 13 of the 108 checks in all (the study's worst blocks have 16).
    """
    per_param = {k: [] for k in NAMES}
    for name in VALVES:
        for k, seeds in _misses(round_trips(name, mdot_min="auto"), PAPER_VALVES[name]).items():
            per_param[k] += [(name, seed) for seed in seeds]
    assert all(len(v) <= 3 for v in per_param.values()), per_param
    assert sum(len(v) for v in per_param.values()) <= 16, per_param


def test_round_trip_intervals_are_not_too_wide(round_trips):
    """The other bound (issue 39): the 95 % intervals are as wide as the estimates'
    errors, not wider.  Over the same 108 checks, the errors in units of the interval's
    standard error (half-width ÷ 1.96) have an rms of 1.18 (honest: 1 ± 0.07) and 13
    fall outside ±1.96; intervals 1.8× too wide would give an rms of ~0.65 and no miss."""
    z = []
    for name in VALVES:
        truth = PAPER_VALVES[name]
        for fit in round_trips(name, mdot_min="auto").values():
            z += [(getattr(fit.params, k) - getattr(truth, k))
                  / ((fit.ci95[k][1] - fit.ci95[k][0]) / 2 / 1.959963984540054) for k in NAMES]
    z = np.array(z)
    assert len(z) == 108
    assert 0.8 <= np.sqrt(np.mean(z ** 2)) <= 1.4, np.sqrt(np.mean(z ** 2))
    assert (np.abs(z) > 1.959963984540054).sum() >= 2  # coverage below 98 %


def test_paper_threshold_fixed_at_one_mg_s(round_trips):
    """With the paper's defaults (ṁ_min 1 mg/s, C 0.1) the same criteria hold for axi."""
    truth = PAPER_VALVES["axi"]
    fits = round_trips("axi")
    for fit in fits.values():
        assert fit.mdot_min == 1.0 and fit.C == 0.1
        assert abs(fit.params.pclose - truth.pclose) < 5.0
        assert fit.params.Rf == pytest.approx(truth.Rf, rel=0.03)
    misses = _misses(fits, truth)
    assert all(len(v) <= 2 for v in misses.values()), misses  # 6 fits per parameter
    assert sum(len(v) for v in misses.values()) <= 5, misses


def test_sweep_groups_of_the_paper_protocol(bench):
    from pneunet.truth.valves.identify.fit import sweep_groups

    data = bench("axi")
    groups = sweep_groups(data)
    assert groups.max() + 1 == 210 and np.all(np.bincount(groups) == 21)
    # without the sweep column: split at the highest p_ctrl of each run
    assert np.array_equal(sweep_groups(data.drop(columns=["sweep"])), groups)
    both = data.assign(group=data["p_in_cmd_kPa"])
    assert sweep_groups(both).max() + 1 == 20


def test_uncertainty_options(bench):
    """Groups: sweeps by default, points on request; n_boot=0 keeps stage-2 errors."""
    data = bench("axi")
    sweeps = fit_valve(data, n_boot=30)
    points = fit_valve(data, n_boot=30, groups=None)
    assert sweeps.settings["n_groups"] == 210 and points.settings["n_groups"] == 4410
    assert "30 half-samples of 210 sweeps" in sweeps.report()
    for k in NAMES:
        assert 0.3 < sweeps.stderr[k] / points.stderr[k] < 3.0, k
    bare = fit_valve(data, n_boot=0)
    assert np.isnan(bare.stderr["ain"]) and bare.stderr["Rf"] > 0
    assert "ain    = " in bare.report() and "not computed" in bare.report()
    assert bare.to_json()["params"]["ain"]["stderr"] is None
    with pytest.raises(DataError, match="no such column"):
        fit_valve(data, n_boot=0, groups="nope")


def test_threshold_correction_removes_the_paper_procedures_bias(fitted):
    """Without the correction, stage 1 puts p_close a few kPa high and e comes out low."""
    truth = PAPER_VALVES["axi"]
    paper = fitted("axi", correct_threshold=False)
    corrected = fitted("axi")
    assert 1.5 < paper.params.pclose - truth.pclose < 6.0
    assert abs(corrected.params.pclose - truth.pclose) < abs(paper.params.pclose - truth.pclose)
    assert abs(corrected.params.e - truth.e) < abs(paper.params.e - truth.e)


def test_clean_data_misclassification_and_rmse_at_the_noise_level():
    """Done-criterion 2."""
    truth = PAPER_VALVES["axi"]
    clean = simulate_bench(truth, noise_mdot=0, noise_rel=0, noise_p=0, setpoint_error=0)
    fit = fit_valve(clean, n_boot=20)
    assert fit.metrics["misclassified"] < 0.01 * 4410
    assert fit.metrics["rmse"] < 0.5  # lattice-limited identification, 0.06 % of max flow
    for k in NAMES:
        assert getattr(fit.params, k) == pytest.approx(getattr(truth, k), rel=0.01, abs=0.5)
    noisy = simulate_bench(truth, noise_mdot=2.0, noise_rel=0, noise_p=0, setpoint_error=0,
                           seed=7)
    fit = fit_valve(noisy, mdot_min="auto", n_boot=20)
    assert fit.metrics["misclassified"] < 0.01 * 4410
    assert fit.metrics["rmse"] == pytest.approx(2.0, rel=0.15)  # measured: 2.26
    # measured 2.85: the identification error near the boundary adds ~2 mg/s in quadrature
    assert 1.9 < fit.metrics["rmse_open"] < 3.0
    assert re.search(r"RMSE flow\s+= 2\.\d+ mg/s all", fit.report())


def test_auto_mdot_min_follows_the_closed_point_noise():
    rng = np.random.default_rng(0)
    closed = 0.3 * rng.standard_normal(3000)
    opened = rng.uniform(20, 800, 1200)
    threshold, centre, sigma = auto_mdot_min(np.concatenate([closed, opened]))
    assert sigma == pytest.approx(0.3, rel=0.1)
    assert abs(centre) < 0.05
    assert threshold == pytest.approx(1.5, rel=0.15)


def test_outputs_json_report_and_predict(fitted, bench):
    fit = fitted("axi", mdot_min="auto")
    out = json.loads(json.dumps(fit.to_json()))
    assert set(out["params"]) == set(NAMES)
    for k in NAMES:
        assert {"value", "stderr"} <= set(out["params"][k])
    assert {"rmse", "rmse_open", "misclassified", "n", "n_open"} <= set(out["metrics"])
    text = fit.report()
    for k in NAMES:
        assert re.search(rf"^\s+{k}\s*= .*\+/- .*95% CI", text, re.M), k
    assert "misclassified" in text and "RMSE 1/R" in text
    data = bench("axi")
    error = fit.predict(data) - data["mdot_true_mg_s"]
    assert np.sqrt(np.mean(error ** 2)) < 10.0  # measured pressures carry sensor noise
    assert fit.metrics["rmse_inv_r"] > 0 and fit.misclassified.dtype == bool
    assert fit.open.sum() == fit.metrics["n_open"]


def _parse_card(card):
    m = re.fullmatch(r"\.model (\S+) VALVE\((.*)\)", card.strip())
    assert m, card
    values = dict(item.split("=") for item in m.group(2).split())
    return m.group(1), ValveParams(**{k: float(v) for k, v in values.items()})


def test_model_card_round_trips_into_the_same_flows(fitted, bench):
    """Done-criterion 3, part 1: card text -> ValveParams -> the fit's flows."""
    fit = fitted("axi", mdot_min="auto")
    name, params = _parse_card(fit.model_card("AXI_FIT"))
    assert name == "AXI_FIT"
    from pneunet.physics.laws import valve_flow

    data = bench("axi")
    flows = valve_flow(data["p_in_kPa"], data["p_out_kPa"], data["p_ctrl_kPa"],
                       **params.as_dict())
    np.testing.assert_allclose(flows, fit.predict(data), rtol=1e-4, atol=1e-3)


@pytest.mark.parametrize("p_in, p_out, p_ctrl", [(396.0, 221.0, 96.0), (596.0, 346.0, 246.0),
                                                 (296.0, 121.0, 171.0)])
def test_model_card_in_a_netlist_simulates_the_fits_flows(fitted, p_in, p_out, p_ctrl):
    """Done-criterion 3, part 2: the card pasted into a netlist, operating point."""
    from pneunet import netlist
    from pneunet.engine.simulate import operating_point

    fit = fitted("axi", mdot_min="auto")
    text = "\n".join([
        "* valve on three pressure sources",
        fit.model_card("AXI_FIT"),
        f"Pin a {p_in}kPa",
        f"Pout b {p_out}kPa",
        f"Pctrl c {p_ctrl}kPa",
        "X1 a b c AXI_FIT",
        ".op",
    ])
    deck = netlist.parse_netlist(text)
    op = operating_point(deck.circuit)
    expected = float(fit.predict({"p_in_kPa": [p_in], "p_out_kPa": [p_out],
                                  "p_ctrl_kPa": [p_ctrl]})[0])
    assert op.flows["X1"] == pytest.approx(expected, rel=1e-3, abs=1e-2)


def test_data_without_a_boundary_is_refused(bench):
    data = bench("axi").copy()
    data["mdot_mg_s"] = 0.0
    with pytest.raises(DataError, match="all 4410 points are labelled closed"):
        fit_valve(data)
