"""The valve element family on its vectorised route, against the paper's equations
(tests/reference_valve.py) and a user's flow model written here: six-parameter valves
with and without backward parameters next to user models in one family, the flows and
partials at one time, the flows over a history, and the recorded signals (issue 39:
mutants of physics/elements/valves.py in the user-model and history paths survived)."""
import numpy as np
import pytest

from pneunet.physics import elements
from pneunet.physics.elements.base import ElementSpec, FamilyContext
from pneunet.engine.options import SimulationOptions
from pneunet.physics.valve_params import PAPER_VALVES, ValveParams
import reference_valve as ref  # tests/ is on pytest's sys.path

AXI = PAPER_VALVES["axi"].as_dict()
BACKWARD = ValveParams(Rf=0.9, pclose=60.0, ptrans=150.0, e=1.8, ain=0.7, aout=0.4)


class Orifice:
    """A user's valve model: ṁ = (p_in³ − p_out³)·e^(p_ctrl/100)/R₀ (mg/s), smooth (cubic:
    central differences are not exact for it, a 1 kPa step would be off by ~1e-5), with
    its exact partials for the test."""

    R0 = 4e5

    def flow(self, p_in, p_out, p_ctrl):
        return (p_in ** 3 - p_out ** 3) * np.exp(p_ctrl / 100) / self.R0

    def partials(self, p_in, p_out, p_ctrl):
        k = np.exp(p_ctrl / 100) / self.R0
        return 3 * p_in ** 2 * k, -3 * p_out ** 2 * k, (p_in ** 3 - p_out ** 3) * k / 100


USER = Orifice()
#: instance i: axi, axi with backward parameters, the user's model (cycled: 12 valves)
MODELS = [("axi", False), ("axi", BACKWARD), (USER, False)] * 4


def _family(models=MODELS):
    specs = [ElementSpec("valve", f"X{i}", ("a", "b", "c"), {"model": m, "backward": b})
             for i, (m, b) in enumerate(models)]
    cls = elements.family("valve")
    for s in specs:
        cls.check_spec(s)
    return cls(specs, FamilyContext(SimulationOptions()))


def _band_flow(p_in, p_out, p_ctrl, params):
    """Eq. 19 with eq. 25 and the circuits' flow band (10 kPa²) on the root."""
    dp = ref.delta_p(p_in, p_out, p_ctrl, params["ain"], params["aout"])
    if dp <= params["pclose"]:
        return 0.0
    u = (dp - params["pclose"]) / (params["ptrans"] - params["pclose"])
    d = p_in ** 2 - p_out ** 2
    return d / (d * d + 100.0) ** 0.25 / (params["Rf"] * np.sqrt(1 + u ** (-2 * params["e"])))


def _want(i, x):
    model, backward = MODELS[i]
    if model is USER:
        return USER.flow(*x)
    params = backward.as_dict() if backward and x[1] > x[0] else AXI
    return _band_flow(*x, params)


def _pressures(rng, n):
    p = np.column_stack([rng.uniform(150, 500, n), rng.uniform(100, 450, n),
                         rng.uniform(96, 200, n)])
    p[1::2, :2] = p[1::2, 1::-1]  # every other valve flows backward
    return p


def test_mixed_family_flows_and_partials_at_one_time():
    fam = _family()
    p = _pressures(np.random.default_rng(0), len(MODELS))
    q, dq, _ = fam.outflows(0.0, p, None)
    want = np.array([_want(i, x) for i, x in enumerate(p)])
    assert (want[2::3] != 0).all() and (want[:2] != 0).any()
    np.testing.assert_allclose(q[:, 0], want, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(q[:, 1], -want, rtol=1e-9, atol=1e-12)
    assert not q[:, 2].any() and not dq[:, 2].any()  # nothing flows at the control port
    for i, x in enumerate(p):
        if MODELS[i][0] is USER:
            exact = USER.partials(*x)
        else:
            h = 1e-4
            exact = [(_want(i, x + h * e) - _want(i, x - h * e)) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(dq[i, 0], exact, rtol=1e-7, atol=1e-9, err_msg=str(i))
        np.testing.assert_allclose(dq[i, 1], -np.asarray(exact), rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(fam.flows(0.0, p, None), q, rtol=1e-13, atol=1e-13)


def test_mixed_family_flows_over_a_history_and_its_signals():
    fam = _family()
    rng = np.random.default_rng(1)
    history = np.array([_pressures(rng, len(MODELS)) for _ in range(5)])  # (time, valve, port)
    flows = fam.flows(np.arange(5.0), history, None)
    assert flows.shape == (5, len(MODELS), 3)
    for k, p in enumerate(history):
        want = [_want(i, x) for i, x in enumerate(p)]
        np.testing.assert_allclose(flows[k, :, 0], want, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(flows[k, :, 1], -np.array(want), rtol=1e-9, atol=1e-12)
    sig = fam.signals(0.0, history[0])
    p = history[0]
    analytic = [i for i, (m, _) in enumerate(MODELS) if m is not USER]
    dp = np.array([ref.delta_p(*p[i], AXI["ain"], AXI["aout"]) for i in analytic])
    assert sig["dp"][0] == "kPa"
    np.testing.assert_allclose(sig["dp"][1][analytic], dp, rtol=1e-12)
    np.testing.assert_allclose(sig["opening"][1][analytic],
                               np.maximum(dp - AXI["pclose"], 0) / (AXI["ptrans"] - AXI["pclose"]),
                               rtol=1e-12)
    np.testing.assert_allclose(sig["mdot"][1], flows[0, :, 0], rtol=1e-13)
    # a user's model has no a_in, a_out, p_close: its dp and opening are undefined, not
    # numbers of made-up parameters (they were, of a_in = a_out = 0.5, p_close = 0)
    user = [i for i, (m, _) in enumerate(MODELS) if m is USER]
    assert user and np.isnan(sig["dp"][1][user]).all()
    assert np.isnan(sig["opening"][1][user]).all()
    assert fam.undefined_signals("dp") == fam.undefined_signals("opening") == set(user)
    assert fam.undefined_signals("mdot") == set()


def test_a_users_valve_has_no_dp_in_a_solution_and_asking_says_so():
    """A solution leaves out what a user-model valve cannot have: reading its dp is an
    error naming the signals there are, never a column of NaN."""
    from pneunet import Circuit
    from pneunet.common.errors import PneunetError

    c = Circuit("user valve", ambient=96.0)
    c.pressure_source("PS", "s", 300.0)
    c.pressure_source("PC", "c", 96.0)
    c.valve("X1", "s", "v", "c", model=USER)
    c.valve("X2", "s", "v", "c", model="axi")
    c.volume("V1", "v", V=20.0)
    sol = c.tran(0.2)
    assert np.isfinite(sol["mdot_X1"]).all() and sol["mdot_X1"][-1] > 0
    assert np.isfinite(sol["dp_X2"]).all() and np.isfinite(sol["opening_X2"]).all()
    for name in ("dp_X1", "opening_X1"):
        assert name not in sol.signals
        with pytest.raises(PneunetError, match=name):
            sol[name]


def test_a_small_family_with_a_users_model_is_evaluated_per_valve():
    """Three valves (a family this small takes the per-valve route when all are
    six-parameter ones): the user's model still gives its own flow."""
    fam = _family(MODELS[:3])
    p = _pressures(np.random.default_rng(2), 3)
    q, dq, _ = fam.outflows(0.0, p, None)
    np.testing.assert_allclose(q[:, 0], [_want(i, x) for i, x in enumerate(p)], rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(dq[2, 0], USER.partials(*p[2]), rtol=1e-7)
    np.testing.assert_allclose(fam.flows(0.0, p, None), q, rtol=1e-13, atol=1e-13)
