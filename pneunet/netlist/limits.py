"""What a netlist may ask for, at most: every cap is named in its error message and can be
changed (``--limit NAME=N`` on the command line, ``limits=`` in the Python API)."""
from __future__ import annotations

import dataclasses
import difflib
from dataclasses import dataclass

from ..common.errors import ParameterError


#: the most a limit can be raised to: nesting that is read by recursion
CEILINGS = {"max_subckt_depth": 150, "max_include_depth": 150}


@dataclass(frozen=True)
class Limits:
    """Caps on a netlist's size and on the work it asks for (defaults in docs/netlist.md)."""

    max_line_length: int = 100_000        # characters in one line
    max_expression_depth: int = 200       # nesting of operators and calls in one {expression}
    max_subckt_depth: int = 50            # subcircuit instances inside each other
    max_array_size: int = 100_000         # copies made by one [lo:hi] range
    max_include_depth: int = 20           # .include files inside each other
    max_includes: int = 1_000             # files included in all, repeats counted
    max_elements: int = 100_000           # elements in the flattened circuit
    max_output_points: int = 10_000_000   # output points of one .tran (t_stop / t_step)
    max_sweep_points: int = 100_000       # points of one .dc, all .step lines, one sweep's grid
    max_samples: int = 100_000            # random samples: --mc, --lhs, --yield, --bootstrap

    def __post_init__(self):
        for name, ceiling in CEILINGS.items():
            if getattr(self, name) > ceiling:
                raise ParameterError(f"limit {name} can be at most {ceiling}, got "
                                     f"{getattr(self, name)}",
                                     hint="each level is a few frames of Python's stack, which "
                                          "holds about 1000")

    def replace(self, specs) -> "Limits":
        """These limits with ``NAME=N`` entries (strings or a mapping) changed."""
        items = specs.items() if isinstance(specs, dict) else (_split(s) for s in specs)
        known = [f.name for f in dataclasses.fields(self)]
        changes = {}
        for name, value in items:
            if name not in known:
                close = difflib.get_close_matches(name, known, n=1, cutoff=0.5)
                raise ParameterError(f"unknown limit {name!r}",
                                     hint=f"did you mean {close[0]!r}?" if close else
                                     "limits: " + ", ".join(known))
            try:
                number = int(float(value))
            except (TypeError, ValueError, OverflowError):
                number = 0
            if number < 1 or number != float(value):
                raise ParameterError(f"limit {name} must be a whole number >= 1, got {value!r}")
            changes[name] = number
        return dataclasses.replace(self, **changes)

    def exceeded(self, name: str) -> str:
        """The text naming a limit in an error: ``limit max_elements = 100000``."""
        return f"limit {name} = {getattr(self, name)}"

    def hint(self, name: str) -> str:
        return f"if it is meant, raise the limit with --limit {name}=N"


def _split(spec: str):
    name, sep, value = str(spec).partition("=")
    if not sep:
        raise ParameterError(f"bad --limit {spec!r}", hint="NAME=N, e.g. --limit max_elements=2000000")
    return name.strip(), value.strip()


DEFAULT = Limits()
