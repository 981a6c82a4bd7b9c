"""The effect library as extensions of the valve law (fast, no fits)."""
import numpy as np
import pytest

from pneunet.physics.valve_effects import (LIBRARY_EFFECTS, Effect, Param, ValveModel,
                                           available_effects, get_effect, register_effect,
                                           unregister_effect)
from pneunet.common.errors import ParameterError
from pneunet.physics.laws import valve_flow
from pneunet.physics.valve_params import PAPER_VALVES

P = PAPER_VALVES["axi"]
rng = np.random.default_rng(3)
N = 2000
P_IN = rng.uniform(121, 596, N)
P_OUT = rng.uniform(96, P_IN)
P_CTRL = rng.uniform(96, 596, N)
SWEEP = np.where(rng.random(N) < 0.5, -1.0, 1.0)
TIME = np.arange(N, dtype=float)
BASE = valve_flow(P_IN, P_OUT, P_CTRL, **P.as_dict())


def flow(model):
    return model.flow(P_IN, P_OUT, P_CTRL, time=TIME, sweep=SWEEP)


def test_library_ids_registered_with_docs():
    assert set(LIBRARY_EFFECTS) <= set(available_effects())
    for eid in LIBRARY_EFFECTS:
        cls = get_effect(eid)
        doc = cls.__doc__
        assert "null value" in doc.lower() and "Residual signature" in doc and "=" in doc
        for p in cls.params.values():
            assert p.lo <= p.null <= p.hi and p.unit


@pytest.mark.parametrize("eid", LIBRARY_EFFECTS)
def test_null_value_is_the_plain_law(eid):
    assert np.allclose(flow(ValveModel(P, [eid])), BASE, rtol=0, atol=1e-9)


def test_all_null_effects_compose_to_plain_law():
    assert np.allclose(flow(ValveModel(P, list(LIBRARY_EFFECTS))), BASE, atol=1e-9)


def test_choked_is_iso6358():
    b = 0.3
    m = flow(ValveModel(P, [get_effect("choked")(b=b)]))
    g = BASE / np.sqrt(P_IN ** 2 - P_OUT ** 2)
    r = P_OUT / P_IN
    iso = np.where(r <= b, g * P_IN, g * P_IN * np.sqrt(1 - ((r - b) / (1 - b)) ** 2))
    assert np.allclose(m, iso, atol=1e-9)
    assert (m >= BASE - 1e-9).all()  # choked law passes more flow at equal G


def test_leak_flows_when_closed():
    m = flow(ValveModel(P, [get_effect("leak")(G=0.01)]))
    closed = BASE == 0
    assert closed.sum() > 100
    assert np.allclose(m[closed], 0.01 * np.sqrt(P_IN[closed] ** 2 - P_OUT[closed] ** 2))


def test_laminar_solves_series_law():
    K = 20.0
    m = flow(ValveModel(P, [get_effect("laminar")(K=K)]))
    op = BASE > 1
    g = BASE[op] / np.sqrt(P_IN[op] ** 2 - P_OUT[op] ** 2)
    # p_in^2 - p_out^2 = m^2/G^2 + K m
    assert np.allclose(m[op] ** 2 / g ** 2 + K * m[op], P_IN[op] ** 2 - P_OUT[op] ** 2, rtol=1e-9)
    assert (m[op] < BASE[op]).all()


def test_internal_drop_solves_the_implicit_equation():
    lam = 0.6
    m = flow(ValveModel(P, [get_effect("internal-drop")(lam=lam)]))
    p_ch = np.sqrt(P_IN ** 2 - (lam * P.Rf * m) ** 2)
    dp = P.ain * p_ch + P.aout * P_OUT - P_CTRL
    again = valve_flow(P_IN, P_OUT, P_CTRL + (P.ain * P_IN + P.aout * P_OUT - P_CTRL - dp),
                       **P.as_dict())
    assert np.allclose(m, again, atol=1e-6)
    assert (m <= BASE + 1e-9).all() and (m < BASE - 1).any()


def test_hysteresis_shifts_threshold_by_direction_and_is_neutral_without_sweep():
    h = 10.0
    model = ValveModel(P, [get_effect("hysteresis")(h=h)])
    m = flow(model)
    shifted = valve_flow(P_IN, P_OUT, P_CTRL - SWEEP * h / 2, **P.as_dict())
    assert np.allclose(m, shifted, atol=1e-9)
    assert np.allclose(model.flow(P_IN, P_OUT, P_CTRL), BASE)  # circuits: mean threshold


def test_pressure_offset_shifts_all_pressures():
    m = flow(ValveModel(P, [get_effect("pressure-offset")(p0=7.0)]))
    assert np.allclose(m, valve_flow(P_IN + 7, P_OUT + 7, P_CTRL + 7, **P.as_dict()))


def test_backward_flow_is_negative():
    model = ValveModel(P, [get_effect("leak")(G=0.01), get_effect("laminar")(K=5)])
    fwd = model.flow(P_IN, P_OUT, P_CTRL)
    bwd = model.flow(P_OUT, P_IN, P_CTRL)
    assert np.allclose(fwd, -bwd)


def test_card_round_trip_and_errors():
    model = ValveModel(P, [get_effect("leak")(G=0.01), get_effect("choked")(b=0.3),
                           get_effect("internal-drop")(lam=0.2),
                           get_effect("pressure-offset")(p0=-3)])
    card = model.card_params()
    assert card["leak_G"] == 0.01 and card["internal_drop_lam"] == 0.2
    assert card["pressure_offset_p0"] == -3
    back = ValveModel.from_card_params(card)
    assert back.card_params() == card
    assert np.allclose(flow(back), flow(model))
    assert ".model V1 VALVE(Rf=0.566" in model.model_card("V1")
    with pytest.raises(ParameterError, match="unknown valve model parameter"):
        ValveModel.from_card_params({**card, "leek_G": 1})
    with pytest.raises(ParameterError, match="outside"):
        get_effect("leak")(G=-1)
    with pytest.raises(ParameterError, match="no parameter"):
        get_effect("leak")(K=1)


def test_user_effect_registers_composes_and_round_trips():
    @register_effect
    class Drift(Effect):
        """Sensor gain drift: ṁ_meas = ṁ (1 + c t/3600). Null value 0."""
        id = "test-drift"
        needs = ("time",)
        params = {"c": Param("1/h", -1.0, 1.0, 0.0, "gain change per hour")}
        order = 90

        def flow(self, m, x, c):
            return m * (1 + c * x.time / 3600.0)

    try:
        model = ValveModel(P, [Drift(c=0.5), get_effect("leak")(G=0.01)])
        m = flow(model)
        leak_only = flow(ValveModel(P, [get_effect("leak")(G=0.01)]))
        assert np.allclose(m, leak_only * (1 + 0.5 * TIME / 3600))
        card = model.card_params()
        assert card["test_drift_c"] == 0.5
        assert ValveModel.from_card_params(card).card_params() == card
        with pytest.raises(ParameterError, match="already registered"):
            register_effect(type("Other", (Drift,), {"__doc__": "x"}))
    finally:
        unregister_effect("test-drift")


def test_bad_user_effects_are_refused():
    class NoHook(Effect):
        id = "no-hook"
        params = {}

    with pytest.raises(ParameterError, match="no hook"):
        register_effect(NoHook)

    class BadId(Effect):
        id = "Bad_Id"

        def flow(self, m, x):
            return m

    with pytest.raises(ParameterError, match="bad effect id"):
        register_effect(BadId)
