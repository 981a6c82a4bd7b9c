"""Two-column tables from CSV files: a pressure–volume curve, a recorded source.

The file is read by :mod:`pneunet.common.csvdata` (every format problem is a DataError naming the
file and line).  Its two columns are named ``<quantity>_<unit>``, the unit after the first
``_`` with further ``_`` read as ``/``: ``time_s``, ``p_kPa``, ``p_barg`` (gauge),
``V_mL``, ``mdot_L_min`` (normal litres, see :mod:`pneunet.physics.units`).  Values are converted
to internal units; the first column must not decrease (``strict``: must increase; None:
the first or the second must increase, as a curve whose pressure is not monotone).
"""
from __future__ import annotations

import numpy as np

from ..common.csvdata import TRACE_MAX_ROWS, nonfinite_rows, open_csv
from ..common.errors import DataError, ParameterError
from .units import GAUGE_UNITS, SLOTS, pretty, to_internal


def read_table(path, slots: tuple[str, str], *, ambient_kpa: float, gas,
               strict: bool | None = False,
               source: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The two columns of ``path`` in the internal units of ``slots`` (e.g. ('time',
    'pressure')), as float arrays of at least two rows; messages name ``source`` (default
    ``path``)."""
    csv = open_csv(path, source)
    if len(csv.columns) != 2:
        raise DataError(f"a table has two columns, found {len(csv.columns)}: "
                        + ", ".join(csv.columns), where=csv.source,
                        hint=f"e.g. a header {_example(slots)}")
    table = csv.read(numeric=csv.columns, max_rows=TRACE_MAX_ROWS)
    if table.stride > 1:
        raise DataError(f"more than {TRACE_MAX_ROWS} rows ({table.rows_in_file})",
                        where=csv.source, hint="thin the table before using it")
    frame = table.frame
    column, bad = nonfinite_rows(frame, csv.columns)
    if column is not None:
        line = int(frame["line"].to_numpy()[bad][0])
        raise DataError(f"column {column} is not a finite number", where=f"{csv.source}:{line}")
    if len(frame) < 2:
        raise DataError("a table needs at least two rows", where=csv.source)
    x, y = (_convert(frame[name].to_numpy(float), name, slot, csv.source, ambient_kpa, gas)
            for name, slot in zip(csv.columns, slots))
    step = np.diff(x)
    wrong = np.flatnonzero(step <= 0 if strict or strict is None else step < 0)
    if wrong.size and strict is None and np.all(np.diff(y) > 0):
        return x, y  # y increases: a curve x(y) (a balloon's pressure over its volume)
    if wrong.size:
        line = int(frame["line"].to_numpy()[wrong[0] + 1])
        either = f" (or, for a curve whose {csv.columns[0]} is not monotone, column " \
                 f"{csv.columns[1]})" if strict is None else ""
        raise DataError(f"column {csv.columns[0]} must {'not decrease' if strict is False else 'increase'}"
                        f" from row to row{either}", where=f"{csv.source}:{line}")
    return x, y


def _convert(values, name, slot, source, ambient_kpa, gas):
    unit = name.split("_", 1)[1].replace("_", "/") if "_" in name else ""
    if not unit:
        raise DataError(f"column {name} names no unit", where=source,
                        hint=f"name the columns <quantity>_<unit>: {_example((slot,))}")
    gauge = unit in GAUGE_UNITS
    try:
        return np.asarray(to_internal(values, unit[:-1] if gauge else unit, slot, gauge=gauge,
                                      ambient_kpa=ambient_kpa, gas=gas, name=name), dtype=float)
    except ParameterError as err:
        raise DataError(f"column {name}: {err.message}", where=source,
                        hint=f"a {slot} column in {pretty(SLOTS[slot])}: "
                             f"{_example((slot,))}") from None


def _example(slots):
    names = {"time": "time_s", "pressure": "p_kPa", "volume": "V_mL", "flow": "mdot_mg_s"}
    return ",".join(names.get(s, s) for s in slots)
