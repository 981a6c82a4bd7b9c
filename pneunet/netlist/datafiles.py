"""Tables in a netlist: inline ``TABLE(x y …)``, or data files (a pressure–volume table,
a recorded source) found and allowed by the include policy (:mod:`.includes`: relative to
the naming file, then the search path; never outside those folders) and read by
:func:`pneunet.physics.tables.read_table`."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..common.errors import DataError
from .located import error_at as _err
from .syntax import Pair, RawArgs, Str, Word
from .values import TINY, split


def inline_table(call, slots, number, convert):
    """``TABLE(x1 y1 x2 y2 …)``: the pairs as two arrays, each value read by
    ``number(item, slot)`` in its slot's unit; a body of plain numbers (:class:`RawArgs`)
    is read a column at a time, ``convert(magnitudes, unit, slot, span)`` once per unit."""
    args = call.args
    if len(args) < 4 or len(args) % 2 or (not isinstance(args, RawArgs)
                                           and any(isinstance(a, Pair) for a in args)):
        raise _err(f"TABLE needs two or more pairs of values, got {len(args)} value(s)", call,
                   "e.g. table=TABLE(100kPa 20mL 200kPa 30mL)")
    if isinstance(args, RawArgs):
        return tuple(column(args, k, slots[k], number, convert) for k in (0, 1))
    return ([number(a, slots[0]) for a in args[0::2]], [number(a, slots[1]) for a in args[1::2]])


def column(args: RawArgs, first: int, slot: str, number, convert) -> list:
    """Every second value of ``args`` from ``first``, as :func:`inline_table`'s ``number``
    reads them (the same errors at the same places), but a unit at a time."""
    texts = args.texts[first::2]
    magnitudes, units = np.empty(len(texts)), {}
    for i, text in enumerate(texts):
        parts = split(text)
        if parts is None:  # a parameter name: each value on its own
            return [number(args[k], slot) for k in range(first, len(args), 2)]
        magnitudes[i] = parts[0]
        units.setdefault(parts[1], []).append(i)
    values = np.empty(len(texts))
    for unit, rows in units.items():
        rows = np.array(rows)
        values[rows] = convert(magnitudes[rows], unit, slot,  # a bad unit: at its first use
                               args.span(first + 2 * rows[0]))
    for i in np.flatnonzero(~(np.isfinite(values) & (np.abs(values) >= TINY))):  # 0, NaN…
        values[i] = number(args[first + 2 * i], slot)  # a located error unless fine (0)
    return values.tolist()


def read_data_file(item, policy, slots, options, label, *, strict):
    """The two columns of the CSV file ``item`` names, in the internal units of ``slots``;
    an error at ``item`` (with the file's line for a problem inside it)."""
    from ..physics.tables import read_table

    if not isinstance(item, (Word, Str)):
        raise _err(f"{label} expects a file name", item, 'e.g. "curve.csv"')
    name = item.span.file
    base = Path(os.path.realpath(name)).parent if name != "<netlist>" else policy.roots[0]
    try:
        with policy.open(item, base) as opened:  # read as opened: never reopened by name
            return read_table(opened.reader, slots, source=str(opened.path),
                              ambient_kpa=options.ambient, gas=options.volume_flow_fluid,
                              strict=strict)
    except DataError as err:
        raise _err(f"{label}: {err.where}: {err.message}", item, err.hint) from None
