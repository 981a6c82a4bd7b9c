"""Manufacturing spread of parameters: stated tolerances and fitted covariances.

A :class:`Spread` holds independent distributions (``X1.pclose`` ± 5 kPa, uniform, or
normal with the interval as ±2σ: :func:`~pneunet.design.sweep.tolerance`) and
correlated normal groups (a fitted valve's parameters with the covariance that
``pneunet fit --json`` reports, centred on the circuit's own values).  ``sample(n,
seed)`` draws Monte Carlo points: the independent ones with
:func:`~pneunet.design.sweep.monte_carlo` (seed ``seed``), each group with
``numpy.random.default_rng([seed, i])``.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..netlist.builder import name_hint
from . import sweep as S
from ..common.errors import DataError, ParameterError
from .spec import Tolerance, parse_tolerance


@dataclass
class Spread:
    """Distributions of the spread parameters (module docstring); ``notes``: what a user
    should know about them (a fit whose values differ from the circuit's)."""

    independent: dict = field(default_factory=dict)
    groups: list = field(default_factory=list)  # (names, mean, covariance)
    notes: list = field(default_factory=list)

    @property
    def names(self) -> list:
        return list(self.independent) + [n for names, _, _ in self.groups for n in names]

    def sd(self, name: str) -> float:
        """Standard deviation of ``name`` (uniform ±a: a/√3)."""
        if name in self.independent:
            d = self.independent[name]
            return d.sd if isinstance(d, S.Normal) else (d.high - d.low) / math.sqrt(12)
        for names, _, cov in self.groups:
            if name in names:
                return math.sqrt(cov[names.index(name), names.index(name)])
        raise KeyError(name)

    def centre(self, name: str) -> float:
        """The nominal (mean) value of ``name``."""
        if name in self.independent:
            d = self.independent[name]
            return d.mean if isinstance(d, S.Normal) else 0.5 * (d.low + d.high)
        for names, mean, _ in self.groups:
            if name in names:
                return float(mean[names.index(name)])
        raise KeyError(name)

    def sample(self, n: int, seed: int = 0) -> list[dict]:
        """``n`` points {name: value}, the same for the same ``seed``."""
        points = S.monte_carlo(self.independent, n, seed) if self.independent else \
            [{} for _ in range(n)]
        for i, (names, mean, cov) in enumerate(self.groups, start=1):
            draws = np.random.default_rng([seed, i]).multivariate_normal(mean, cov, int(n))
            for point, row in zip(points, draws):
                point.update({k: float(v) for k, v in zip(names, row)})
        return points

    def describe(self) -> dict:
        """{name: distribution, mean, sd} for reports."""
        out = {k: {"distribution": type(d).__name__.lower(), "mean": self.centre(k),
                   "sd": self.sd(k)} for k, d in self.independent.items()}
        for names, mean, _ in self.groups:
            out.update({k: {"distribution": "normal (fitted covariance)", "mean": m,
                            "sd": self.sd(k)} for k, m in zip(names, mean)})
        return out


def nominal(problem, point: dict, name: str) -> float:
    """The value of parameter ``name`` in the circuit built at ``point``: a ``.param``,
    an element parameter or a valve-model parameter (``X1.pclose``)."""
    full = dict(problem.fixed, **point)
    if name in full:
        return float(full[name])
    if "." not in name:
        deck = problem.build.deck(full) if isinstance(problem.build, S.NetlistBuilder) else None
        if deck is None or name not in deck.params:
            raise ParameterError(f"spread of {name}: no .param {name!r}",
                                 hint=name_hint(name, deck.params if deck else {},
                                                      ".params") +
                                 "; an element parameter is ELEMENT.PARAM, e.g. X1.pclose")
        return float(deck.params[name])
    element, param = name.rsplit(".", 1)
    circuit = S.apply_overrides(problem.build(full), full)
    if element not in circuit.elements:
        raise ParameterError(f"spread of {name}: no element {element!r}",
                             hint=name_hint(element, circuit.elements, "elements"))
    spec = circuit.elements[element]
    model = spec.params.get("model")
    value = spec.params.get(param, getattr(model, param, None))
    if not isinstance(getattr(value, "level", value), (int, float)):
        known = [k for k, v in spec.params.items() if isinstance(v, (int, float))] + \
            (list(model.as_dict()) if hasattr(model, "as_dict") else [])
        raise ParameterError(f"spread of {name}: {element} has no parameter {param!r}",
                             hint=name_hint(param, known, "parameters"))
    return float(getattr(value, "level", value))


def from_tolerances(problem, point: dict, tolerances, dist: str = "uniform") -> Spread:
    """A Spread of stated tolerances (strings ``X1.pclose=±5kPa`` or Tolerances) around
    the values at ``point``."""
    spread = Spread()
    for tol in tolerances:
        tol = tol if isinstance(tol, Tolerance) else parse_tolerance(tol)
        for name in expand(problem, point, tol.name):
            centre = nominal(problem, point, name)
            spread.independent[name] = S.tolerance(centre, tol.amount(centre), dist)
    return spread


def expand(problem, point: dict, name: str) -> list:
    """``name``, or for ``ELEMENT.PARAM`` with ``*``/``?`` in ELEMENT (``*.pclose``: every
    valve printed separately) the matching elements that have PARAM."""
    import fnmatch

    element, _, param = name.rpartition(".")
    if not any(c in element for c in "*?"):
        return [name]
    full = dict(problem.fixed, **point)
    circuit = S.apply_overrides(problem.build(full), full)
    names = [f"{k}.{param}" for k, spec in circuit.elements.items()
             if fnmatch.fnmatchcase(k, element) and
             (param in spec.params or hasattr(spec.params.get("model"), param))]
    if not names:
        raise ParameterError(f"spread of {name}: no element matching {element!r} has a "
                             f"parameter {param!r}", hint="elements: " +
                             ", ".join(circuit.elements))
    return names


def from_fit(problem, point: dict, element: str, fit) -> Spread:
    """A correlated normal group for the valve ``element`` from a fit: the JSON of
    ``pneunet fit --json`` (a path or dict) or a :class:`~pneunet.truth.valves.identify.fit.ValveFit`;
    centred on the circuit's values, parameters without a variance left out."""
    data = _fit_json(fit)
    params = data.get("params") or {}
    cov = data.get("covariance")
    names = [k for k, v in params.items()
             if v.get("stderr") and (cov is None or (cov.get(k) or {}).get(k))]
    if not names:
        raise DataError(f"the fit for {element} has no parameter uncertainty",
                        hint="rerun pneunet fit with --bootstrap 100, or state a tolerance "
                             "such as --tolerance X1.pclose=±5kPa")
    matrix = np.array([[cov[a][b] or 0.0 for b in names] for a in names]) if cov else \
        np.diag([params[k]["stderr"] ** 2 for k in names])
    full = [f"{element}.{k}" for k in names]
    mean = np.array([nominal(problem, point, n) for n in full])
    spread = Spread(groups=[(full, mean, matrix)])
    far = [k for k, m in zip(names, mean)
           if abs(params[k]["value"] - m) > 3 * params[k]["stderr"]]
    if far:
        spread.notes.append(f"{element}: the circuit's {', '.join(far)} differ from the fit's "
                            "values by more than 3 standard errors; the spread is centred on "
                            "the circuit's values")
    sd = np.sqrt(np.diag(matrix))
    r = matrix / np.outer(sd, sd) - np.eye(len(names))
    i, j = np.unravel_index(np.argmax(np.abs(r)), r.shape)
    if abs(r[i, j]) > 0.5:
        spread.notes.append(f"{element}: the fitted parameters are correlated (r = "
                            f"{r[i, j]:+.2f} between {names[i]} and {names[j]}): the "
                            "sensitivities move one parameter at a time, and the effects of "
                            "correlated parameters partly cancel in the samples")
    if cov is None:
        spread.notes.append(f"{element}: the fit has no covariance (older pneunet fit): "
                            "parameters taken as independent")
    return spread


def no_uncertainty(build) -> str:
    """The message when a yield is asked without a spread: the valves' models carry none."""
    circuit = build({})
    valves = [f"{name} ({_model_name(spec.params.get('model'))})"
              for name, spec in circuit.elements.items() if spec.kind == "valve"]
    return ("a yield needs a spread, and the .model cards carry no uncertainty"
            + (f" (valves: {', '.join(valves)})" if valves else ""))


def spread_hint() -> str:
    return ("state a tolerance, e.g. --tolerance X1.pclose=±5kPa, or give a fitted "
            "covariance: pneunet fit DATA.csv --json > fit.json, then --fit X1=fit.json")


def _model_name(model) -> str:
    from ..physics.valve_params import PAPER_VALVES

    return next((k for k, v in PAPER_VALVES.items() if v == model), "a .model card")


def combined(problem, point: dict, tolerances=(), fits=(), dist: str = "uniform") -> Spread:
    """One Spread of stated ``tolerances`` and ``fits`` ((element, fit) pairs)."""
    return merge(from_tolerances(problem, point, tolerances, dist),
                 *(from_fit(problem, point, element, fit) for element, fit in fits))


def merge(*spreads: Spread) -> Spread:
    out = Spread()
    for s in spreads:
        out.independent.update(s.independent)
        out.groups += s.groups
        out.notes += s.notes
    twice = [n for n in set(out.names) if out.names.count(n) > 1]
    if twice:
        raise ParameterError(f"{twice[0]} has two spreads (a tolerance and a fit)",
                             hint="give each parameter one spread")
    return out


def _fit_json(fit) -> dict:
    if hasattr(fit, "to_json"):
        return fit.to_json()
    if isinstance(fit, dict):
        return fit
    path = Path(fit)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise DataError(f"cannot read the fit {path}: {err.strerror}", where=str(path)) from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise DataError("not the JSON of pneunet fit", where=str(path),
                        hint="write it with: pneunet fit DATA.csv --json > fit.json") from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise DataError("not the JSON of pneunet fit (no 'params')", where=str(path),
                        hint="write it with: pneunet fit DATA.csv --json > fit.json")
    return data
