"""``.fluid NAME key=value …``: the user's own liquid or gas (issue 34), then named by
``.options fluid=NAME`` (a liquid) or ``.options gas=NAME`` (a gas).

* liquid: ``rho`` (density), ``mu`` (dynamic viscosity), ``K`` (bulk modulus), all required:
  ``.fluid glycerol rho=1260kg/m3 mu=1.41Pa*s K=4.35GPa``;
* gas: ``M`` (molar mass, required), ``mu`` (viscosity at ``T0``, default 273.15 K),
  ``S`` (Sutherland's constant, K; without it μ is the same at every temperature) and
  ``gamma`` (c_p/c_v, default 1.4: the thermal elements' default):
  ``.fluid helium M=4.0026g/mol mu=1.87e-5Pa*s S=79.4K``.

Keys are case-insensitive; bare numbers are in kg/m³, Pa·s, kPa, g/mol and K.
"""
from __future__ import annotations

from ..common.errors import PneunetError
from ..physics.gas import GASES, Gas
from ..physics.liquids import LIQUIDS, Liquid
from .located import error_at as _err
from .syntax import Pair, Word

#: key -> (slot, what)
LIQUID_KEYS = {"rho": ("density", "density"), "mu": ("viscosity", "dynamic viscosity"),
               "k": ("pressure_difference", "bulk modulus")}
GAS_KEYS = {"m": ("molar_mass", "molar mass"), "mu": ("viscosity", "viscosity at T0"),
            "t0": ("temperature", "temperature of mu"), "s": ("temperature", "Sutherland's "
                                                           "constant"),
            "gamma": ("dimensionless", "heat-capacity ratio c_p/c_v")}
EXAMPLE = ".fluid glycerol rho=1260kg/m3 mu=1.41Pa*s K=4.35GPa, or .fluid helium M=4.0026g/mol"


def read_fluid_cards(statements, number) -> tuple:
    """The fluids of the ``.fluid`` statements, in order; ``number(word, slot, key)`` reads
    a value in the slot's internal unit.  Errors are located NetlistErrors."""
    fluids, first = [], {}
    for st in statements:
        items = st.items[1:]
        if not items or not isinstance(items[0], Word):
            raise _err(".fluid needs a name", items[0] if items else st.span, EXAMPLE)
        name_item, pairs = items[0], items[1:]
        values = {}
        for it in pairs:
            if not isinstance(it, Pair) or not isinstance(it.key, Word):
                raise _err(f".fluid {name_item.text}: expected key=value, got {it}", it, EXAMPLE)
            key = it.key.text.lower()
            known = LIQUID_KEYS if ("rho" in _keys(pairs) or "k" in _keys(pairs)) else GAS_KEYS
            if key not in known:
                kind = "liquid" if known is LIQUID_KEYS else "gas"
                raise _err(f".fluid {name_item.text}: unknown key {it.key.text!r} for a {kind}",
                           it.key, "a liquid takes rho, mu, K; a gas M, mu, T0, S, gamma")
            if key in values:
                raise _err(f".fluid {name_item.text}: {it.key.text} given twice", it.key)
            values[key] = number(it.value, known[key][0], it.key.text)
        fluid = _build(name_item, values, st)
        key = fluid.name.lower()
        if key == "gas" or key in GASES or key in LIQUIDS:
            raise _err(f"fluid {fluid.name!r} is built in", name_item,
                       "give your own fluid another name")
        if key in first:
            raise _err(f"fluid {fluid.name!r} defined twice", name_item,
                       f"first defined at {first[key]}")
        first[key] = st.span
        fluids.append(fluid)
    return tuple(fluids)


def _keys(pairs):
    return {it.key.text.lower() for it in pairs if isinstance(it, Pair) and
            isinstance(it.key, Word)}


def _build(name_item, values, st):
    name = name_item.text
    liquid = "rho" in values or "k" in values
    required = ("rho", "mu", "k") if liquid else ("m",)
    missing = [k for k in required if k not in values]
    if missing:
        what = (LIQUID_KEYS if liquid else GAS_KEYS)[missing[0]][1]
        raise _err(f".fluid {name}: {'a liquid' if liquid else 'a gas'} needs "
                   f"{missing[0].upper() if missing[0] in ('k', 'm') else missing[0]} "
                   f"({what})", st.span, EXAMPLE)
    try:
        if liquid:
            return Liquid(name, values["rho"], values["mu"], values["k"])
        return Gas(name, values["m"], values.get("mu", float("nan")), values.get("t0", 273.15),
                   values.get("s", float("nan")), values.get("gamma", 1.4))
    except PneunetError as err:
        raise _err(err.message, name_item, err.hint) from None
