"""Results written on a schematic: each node's pressure (kPa absolute) and each element's
mass flow (mg/s), from an operating point or a transient at one time (an array drawn once
shows the range over its members).  A subcircuit box gets no flow: its ports' pressures
are on the nodes it is wired to."""
from __future__ import annotations

from ...common.errors import ParameterError


def values(results) -> tuple[dict, dict]:
    """``({node: kPa}, {element: mg/s})`` of an OperatingPoint or of ``(Solution, t)``."""
    if isinstance(results, tuple):
        sol, t = results
        lo, hi = float(sol.t[0]), float(sol.t[-1])
        if not lo - 1e-12 <= t <= hi + 1e-12:
            raise ParameterError(f"--at {t:g} s lies outside the transient ({lo:g} … {hi:g} s)",
                                 hint="give a time within the .tran interval")
        row = sol.at(t)
        return ({k[2:]: v for k, v in row.items() if k.startswith("p_")},
                {k[5:]: v for k, v in row.items() if k.startswith("mdot_")})
    return dict(results.pressures), dict(results.flows)


def _text(prefix: str, numbers: list, unit: str) -> str | None:
    if not numbers:
        return None
    lo, hi = min(numbers), max(numbers)
    span = f"{lo:.4g}" if abs(hi - lo) <= 5e-4 * max(abs(hi), 1.0) else f"{lo:.4g}…{hi:.4g}"
    return f"{prefix}{span} {unit}"


def notes(sch, results) -> tuple[dict, dict]:
    """Text lines ``({node key: "p=…"}, {part key: "ṁ=…"})`` for the schematic ``sch``."""
    pressures, flows = values(results)
    node_notes = {key: _text("p=", [pressures[n] for n in names if n in pressures], "kPa")
                  for key, names in sch.nodes.items()}
    part_notes = {}
    for key, part in sch.parts.items():
        if part.pins:
            continue
        members = part.names[::part.segments]       # a tube's flow is its first segment's
        part_notes[key] = _text("ṁ=", [flows[n] for n in members if n in flows], "mg/s")
    return ({k: v for k, v in node_notes.items() if v},
            {k: v for k, v in part_notes.items() if v})
