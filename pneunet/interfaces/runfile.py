"""A whole run in one self-describing file: every signal with its unit, the solver's
statistics, the circuit as netlist text, its options and the versions that made it.

``save_run(path, solution, circuit)`` writes JSON (``.json``: text, for small runs) or a
compressed numpy archive (``.npz``: binary columns plus the same JSON header, for large
ones; no pickles).  Floats are written exactly (JSON uses the shortest repr that reads
back to the same double; NaN and ±inf as ``NaN``/``Infinity``).  ``read_run(path)``
gives a :class:`Run` whose ``solution`` equals the saved one: same times, signals,
units, title, branch jumps and statistics (statistics that are not numbers, text,
lists or mappings are stored as their text).
"""
from __future__ import annotations

import json
import platform
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from pathlib import Path
from zipfile import BadZipFile

import numpy as np

from ..common.errors import DataError, ParameterError

FORMAT = "pneunet-run"
VERSION = 1
_PACKAGES = ("pneunet", "numpy", "scipy", "scikit-sundae")


@dataclass(frozen=True)
class Run:
    """A loaded run: the :class:`~pneunet.engine.solution.Solution` and how it was made."""

    solution: object
    netlist: str | None
    options: dict
    versions: dict
    created: str


def save_run(path, solution, circuit=None) -> Path:
    """Write ``solution`` (and ``circuit``'s netlist text and options) to ``path``
    (``.json`` or ``.npz``); returns the path."""
    path = Path(path)
    if path.suffix not in (".json", ".npz"):
        raise ParameterError(f"a run file ends in .json or .npz, got {path.name!r}")
    header = {"format": FORMAT, "version": VERSION, "title": solution.title,
              "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
              "versions": _versions(), "netlist": _netlist(circuit),
              "options": asdict(circuit.options) if circuit is not None else {},
              "stats": _plain(dict(solution.stats)), "jumps": list(solution.jumps),
              "units": dict(solution.units)}
    names = list(solution.signals)
    if path.suffix == ".json":
        header["t"] = solution.t.tolist()
        header["signals"] = {k: solution.signals[k].tolist() for k in names}
        path.write_text(json.dumps(header))
    else:
        arrays = {f"signal_{i}": solution.signals[k] for i, k in enumerate(names)}
        header["signals"] = names
        np.savez_compressed(path, header=np.array(json.dumps(header)), t=solution.t, **arrays)
    return path


def read_run(path) -> Run:
    """The run saved in ``path`` by :func:`save_run`."""
    from ..engine.solution import Solution

    path = Path(path)
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                header = _header(json.loads(str(data["header"])), path)
                t = data["t"]
                signals = {k: data[f"signal_{i}"] for i, k in enumerate(header["signals"])}
        else:
            header = _header(json.loads(path.read_text()), path)
            t = np.array(header["t"], dtype=float)
            signals = {k: np.array(v, dtype=float) for k, v in header["signals"].items()}
        solution = Solution(t, signals, header["units"], header["stats"], header["title"],
                            tuple(header["jumps"]))
        return Run(solution, header["netlist"], header["options"], header["versions"],
                   header["created"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError, BadZipFile) as err:
        raise DataError(f"cannot read a run file: {type(err).__name__} {err}",
                        where=str(path), hint="a file written by save_run (.json or .npz)") \
            from None


def _header(header, path) -> dict:
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise DataError("not a pneunet run file", where=str(path),
                        hint=f'its header has no "format": "{FORMAT}"')
    return header


def _versions() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    found = {"python": platform.python_version()}
    for name in _PACKAGES:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found


def _netlist(circuit):
    if circuit is None:
        return None
    from ..common.errors import PneunetError
    from ..netlist import print_circuit

    try:
        return print_circuit(circuit)
    except PneunetError:  # a function source has no netlist text
        return None


def _plain(value):
    """``value`` as JSON data: numbers, text, lists and mappings; anything else as text."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (bool, str)) or value is None:
        return value
    if isinstance(value, (int, float, np.integer, np.floating)):
        return value.item() if isinstance(value, np.generic) else value
    return str(value)
