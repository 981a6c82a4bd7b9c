"""Simulation options: tolerances, ambient conditions, gas and numerical bands."""
from __future__ import annotations

from dataclasses import dataclass, fields, replace
from numbers import Real

from ..common.errors import ParameterError
from ..physics.gas import AIR, GASES, ROOM_TEMPERATURE_K, STANDARD_ATMOSPHERE_KPA, Gas
from ..physics.laws import DEFAULT_FLOW_BAND_KPA2
from ..physics.liquids import LIQUIDS, Liquid


METHODS = ("auto", "single", "multirate")


@dataclass(frozen=True)
class SimulationOptions:
    """Options of a circuit's analyses (netlist ``.options``).

    rtol, atol          relative and absolute (kPa) tolerances of IDA
    ambient             ambient pressure in kPa: reference nodes and gauge units
    temperature         gas temperature in K (isothermal elements)
    gas                 name of the gas ('air', 'nitrogen', or one of ``fluids``), or a
                        :class:`~pneunet.physics.gas.Gas`
    fluid               'gas' (default: the gas above) or a liquid ('water',
                        'hydraulic_oil'; see pneunet.physics.liquids; or one of ``fluids``), or a
                        :class:`~pneunet.physics.liquids.Liquid`
    fluids              the user's own liquids and gases (netlist ``.fluid`` cards): a
                        Gas or Liquid given as ``gas``/``fluid`` is added here, by name
    flow_band           zero-flow regularisation band ε in kPa² (see laws.signed_root)
    dead_volume         volume in mL added at every node without a volume; 0 keeps
                        those nodes algebraic and folds are crossed by explicit jumps
    max_step            largest IDA step in s (0: no limit)
    fold_threshold      fold indicator below which a jump to the other branch is made
    method              transient integration: 'single' (one IDA step for the whole
                        circuit), 'multirate' (cells on their own steps, coupled through
                        hub nodes; docs/numerics.md) or 'auto' (multirate for large
                        circuits of many loosely coupled cells)
    """

    rtol: float = 1e-5
    atol: float = 1e-5
    ambient: float = STANDARD_ATMOSPHERE_KPA
    temperature: float = ROOM_TEMPERATURE_K
    gas: str = "air"
    fluid: str = "gas"
    fluids: tuple = ()
    flow_band: float = DEFAULT_FLOW_BAND_KPA2
    dead_volume: float = 0.0
    max_step: float = 0.0
    fold_threshold: float = 1e-2
    method: str = "auto"

    _RANGES = {
        "rtol": (1e-12, 1e-2), "atol": (1e-12, 10.0), "ambient": (1.0, 1e4),
        "temperature": (1.0, 2000.0), "flow_band": (1e-6, 1e4), "dead_volume": (0.0, 1e6),
        "max_step": (0.0, 1e9), "fold_threshold": (1e-8, 0.5),
    }

    def __post_init__(self):
        self._take_fluid_objects()
        for key, (lo, hi) in self._RANGES.items():
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, Real):
                raise ParameterError(f"option {key} must be a number, got {value!r}",
                                     hint="options take numbers in internal units (kPa, K, "
                                          "s, mL); in a netlist: .options ambient=96kPa")
            if not lo <= value <= hi:
                raise ParameterError(f"option {key}={value} is outside [{lo:g}, {hi:g}]")
        gases, liquids = self._known(Gas), self._known(Liquid)
        if self.gas.lower() not in gases:
            raise ParameterError(f"unknown gas {self.gas!r}", hint="known: " + ", ".join(gases)
                                 + "; your own: .fluid NAME M=…g/mol (docs/netlist.md)")
        if self.method not in METHODS:
            raise ParameterError(f"unknown method {self.method!r}", hint="known: " + ", ".join(METHODS))
        if self.fluid.lower() != "gas" and self.fluid.lower() not in liquids:
            raise ParameterError(f"unknown fluid {self.fluid!r}",
                                 hint="known: gas, " + ", ".join(liquids)
                                      + "; your own: .fluid NAME rho=… mu=… K=… (docs/netlist.md)")

    def _take_fluid_objects(self) -> None:
        """A Gas/Liquid given as ``gas``/``fluid`` joins ``fluids`` (named there); every
        user fluid is checked: a Gas or Liquid, its name new (not built in, not twice)."""
        extra = list(self.fluids)
        for key, kind in (("gas", Gas), ("fluid", Liquid)):
            value = getattr(self, key)
            if isinstance(value, kind):
                if value not in (GASES | LIQUIDS).values() and value not in extra:
                    extra.append(value)
                object.__setattr__(self, key, value.name)
            elif not isinstance(value, str):
                raise ParameterError(f"option {key} must be a name or a {kind.__name__}, got "
                                     f"{value!r}")
        seen = {}
        for fluid in extra:
            if not isinstance(fluid, (Gas, Liquid)):
                raise ParameterError(f"a user fluid is a pneunet Gas or Liquid, got {fluid!r}")
            key = fluid.name.lower()
            if key == "gas" or key in GASES or key in LIQUIDS:
                raise ParameterError(f"fluid {fluid.name!r} is built in",
                                     hint="give your own fluid another name")
            if seen.get(key, fluid) != fluid:
                raise ParameterError(f"fluid {fluid.name!r} is defined twice, differently")
            seen[key] = fluid
        object.__setattr__(self, "fluids", tuple(seen.values()))

    def _known(self, kind) -> dict:
        """Built-in and user fluids of ``kind`` (Gas or Liquid), by lower-case name."""
        built_in = GASES if kind is Gas else LIQUIDS
        return {**built_in, **{f.name.lower(): f for f in self.fluids if isinstance(f, kind)}}

    @property
    def gas_model(self) -> Gas:
        return self._known(Gas).get(self.gas.lower(), AIR)

    @property
    def volume_flow_fluid(self) -> Gas | Liquid:
        """What a volume flow (``1L/min``) in a flow slot is a volume of: the liquid of a
        liquid circuit (its own litres), else the gas (normal litres)."""
        return self.liquid or self.gas_model

    @property
    def liquid(self) -> Liquid | None:
        """The circuit's liquid, or None for a gas circuit."""
        return self._known(Liquid).get(self.fluid.lower())

    def replace(self, **changes) -> "SimulationOptions":
        names = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ParameterError(f"unknown option {unknown[0]!r}", hint="known: " + ", ".join(sorted(names)))
        return replace(self, **changes)
