"""Tables in a netlist: inline ``TABLE(x y …)``, or data files (a pressure–volume table,
a recorded source) found and allowed by the include policy (:mod:`.includes`: relative to
the naming file, then the search path; never outside those folders) and read by
:func:`pneunet.tables.read_table`."""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import DataError
from .located import error_at as _err
from .syntax import Pair, Str, Word


def inline_table(call, slots, number):
    """``TABLE(x1 y1 x2 y2 …)``: the pairs as two arrays, each value read by
    ``number(item, slot)`` in its slot's unit."""
    args = call.args
    if any(isinstance(a, Pair) for a in args) or len(args) < 4 or len(args) % 2:
        raise _err(f"TABLE needs two or more pairs of values, got {len(args)} value(s)", call,
                   "e.g. table=TABLE(100kPa 20mL 200kPa 30mL)")
    return ([number(a, slots[0]) for a in args[0::2]], [number(a, slots[1]) for a in args[1::2]])


def read_data_file(item, policy, slots, options, label, *, strict):
    """The two columns of the CSV file ``item`` names, in the internal units of ``slots``;
    an error at ``item`` (with the file's line for a problem inside it)."""
    from ..tables import read_table

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
