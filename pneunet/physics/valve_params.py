"""The six parameters of a membrane valve and the paper's identified valves."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from ..common.errors import ParameterError

#: parameter name -> (unit, description)
VALVE_PARAMETERS = {
    "Rf": ("kPa*s/mg", "fixed resistance of the fully open valve"),
    "pclose": ("kPa", "closing pressure p_close = F_offset/A_ctrl"),
    "ptrans": ("kPa", "Δp at which R_v = R_f"),
    "e": ("1", "exponent of the opening characteristic"),
    "ain": ("1", "relative effective area of the higher-pressure port"),
    "aout": ("1", "relative effective area of the lower-pressure port"),
}


#: Rf accepted, kPa*s/mg; |pclose|, |ptrans| at most, kPa; ptrans - pclose at least, kPa
#: (beyond these the laws' products underflow or overflow: Rf = 1e-90 divided by zero)
RF_RANGE, MAX_PRESSURE, MIN_SPAN = (1e-6, 1e6), 1e5, 1e-6


@dataclass(frozen=True)
class ValveParams:
    """Six-parameter membrane valve model (MODEL.md eqs. 10–19).

    Rf in kPa·s/mg, pclose and ptrans in kPa (pressure differences, so the same
    in gauge or absolute), e, ain and aout dimensionless.
    """

    Rf: float
    pclose: float
    ptrans: float
    e: float
    ain: float
    aout: float

    def __post_init__(self):
        self.validate()

    def validate(self, name: str | None = None) -> None:
        """Raise :class:`ParameterError` naming the offending parameter."""
        where = f"valve model {name}" if name else "valve model"
        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"parameter {f.name} must be a finite number, got {v!r}",
                                     where=where)
        if not RF_RANGE[0] <= self.Rf <= RF_RANGE[1]:
            raise ParameterError(f"Rf must lie in [{RF_RANGE[0]:g}, {RF_RANGE[1]:g}] kPa*s/mg, "
                                 f"got {self.Rf:g}", where=where,
                                 hint="the paper's valves have 0.3-1 kPa*s/mg")
        for key in ("pclose", "ptrans"):
            if abs(getattr(self, key)) > MAX_PRESSURE:
                raise ParameterError(f"{key} must lie within ±{MAX_PRESSURE:g} kPa, got "
                                     f"{getattr(self, key):g}", where=where)
        if self.ptrans - self.pclose < MIN_SPAN:
            raise ParameterError(
                f"ptrans ({self.ptrans} kPa) must be greater than pclose ({self.pclose} kPa)"
                f" by {MIN_SPAN:g} kPa at least",
                where=where, hint="ptrans is the Δp at which the valve is 71 % open")
        if not 0.1 <= self.e <= 10:
            raise ParameterError(f"e must lie in [0.1, 10], got {self.e}", where=where)
        for key in ("ain", "aout"):
            if not 0 <= getattr(self, key) <= 3:
                raise ParameterError(f"{key} must lie in [0, 3], got {getattr(self, key)}",
                                     where=where, hint="relative effective areas sum to about 1")

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    def model_card(self, name: str) -> str:
        """A netlist ``.model`` line for these parameters."""
        return (f".model {name} VALVE(Rf={self.Rf:.6g} pclose={self.pclose:.6g} "
                f"ptrans={self.ptrans:.6g} e={self.e:.6g} ain={self.ain:.6g} aout={self.aout:.6g})")


#: Identified valves of the paper (MODEL.md, "Reference numbers").
PAPER_VALVES: dict[str, ValveParams] = {
    "axi_0p6mm": ValveParams(Rf=0.566, pclose=96.42, ptrans=155.1, e=1.99, ain=0.32, aout=0.71),
    "mirror": ValveParams(Rf=0.400, pclose=21.86, ptrans=96.02, e=1.65, ain=0.578, aout=0.459),
    "mirror_backward": ValveParams(Rf=0.395, pclose=19.52, ptrans=93.44, e=1.62, ain=0.588,
                                   aout=0.439),
}
PAPER_VALVES["axi"] = PAPER_VALVES["axi_0p6mm"]
PAPER_VALVES["mirror_forward"] = PAPER_VALVES["mirror"]


def paper_valve(name: str) -> ValveParams:
    """Look up a named valve of the paper, with a clear error for unknown names."""
    key = name.lower()
    if key not in PAPER_VALVES:
        raise ParameterError(f"unknown valve model {name!r}",
                             hint="known: " + ", ".join(sorted(PAPER_VALVES)))
    return PAPER_VALVES[key]


def resolve_valve_model(model):
    """A ValveParams, a named paper valve, a parameter dict, or a flow-model object."""
    if isinstance(model, str):
        return paper_valve(model)
    if isinstance(model, dict):
        return ValveParams(**model)
    if isinstance(model, ValveParams) or callable(getattr(model, "flow", None)):
        return model
    raise ParameterError(f"a valve model must be a ValveParams, a paper valve name or an object "
                         f"with a flow(p_in, p_out, p_ctrl) method, got {model!r}")
