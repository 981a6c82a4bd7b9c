"""Recorded circuit transients (time_s, p_<node>_kPa, mdot_<element>_mg_s and every other
signal ``pneunet run`` writes, contraction_<muscle>_mm …): reading with checks that name
the file, the column and what to do; which samples are compared (jumping signals); the
split into fitted and held-out cycles."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...common.csvdata import TRACE_MAX_ROWS, column_unit, missing_column, nonfinite_rows, open_csv
from ...common.errors import DataError

#: element signals besides pressures and flows (the columns ``pneunet run`` writes,
#: ``<quantity>_<element>_<unit>``), by quantity: the unit slot of :mod:`pneunet.physics.units`
#: (its unit is the signal's); the dimensionless ones have no unit suffix
ELEMENT_SIGNALS = {"contraction": "length", "force": "force", "volume": "volume",
                   "T": "temperature", "dp": "pressure_difference",
                   "opening": "dimensionless", "Re": "dimensionless"}


@dataclass(frozen=True)
class ElementColumn:
    """A column of an element signal read as quantity slot, stem and unit:
    ``contraction_M1_cm`` → length, ``contraction_M1``, ``cm`` (canonical
    ``contraction_M1_mm``)."""

    kind: str  # the unit slot
    stem: str
    unit: str
    gauge: bool = False

    @property
    def canonical(self) -> str:
        from ...physics.units import SLOTS

        return f"{self.stem}_{SLOTS[self.kind]}" if SLOTS[self.kind] else self.stem

    @property
    def pint_unit(self) -> str:
        return self.unit

    @property
    def is_canonical(self) -> bool:
        from ...physics.units import SLOTS

        return self.unit == SLOTS[self.kind]


def element_column(name: str) -> ElementColumn | None:
    """An element signal's column (see :data:`ELEMENT_SIGNALS`) read, else None; a
    DataError naming the column for a missing unit or one of another quantity."""
    from ...common.errors import ParameterError
    from ...physics.units import SLOTS, example, to_internal

    quantity, _, rest = name.partition("_")
    slot = ELEMENT_SIGNALS.get(quantity)
    if slot is None or not rest:
        return None
    if slot == "dimensionless":
        return ElementColumn(slot, name, "")
    element, _, unit = rest.rpartition("_")
    if not element or not unit:
        raise DataError(f"column {name}: a {slot.replace('_', ' ')} needs its unit",
                        hint=f"name it {name}_{SLOTS[slot]} (or another {slot} unit, "
                             f"e.g. {example(slot)})")
    try:
        to_internal(np.ones(1), unit, slot, name=name)
    except ParameterError as err:
        raise DataError(f"column {name}: {unit!r} is not a {slot.replace('_', ' ')} unit",
                        hint=f"{err.message}; e.g. {quantity}_{element}_{SLOTS[slot]}") \
            from None
    return ElementColumn(slot, f"{quantity}_{element}", unit)

#: a sample step larger than this fraction of the signal's range (and than 8 typical
#: steps) is a jump of an algebraic node (p_out at a fold); so is a run of steep steps of
#: one sign that moves this fraction in all (:func:`jump_spans`)
JUMP_FRACTION = 0.25
#: samples left out on each side of a recorded jump
JUMP_HALF_WIDTH = 2


def read_trace(path_or_frame, signals=None, *, max_rows: int | None = TRACE_MAX_ROWS,
               ambient_kpa: float | None = None):
    """A recorded transient as a DataFrame: ``time_s`` then ``p_<node>_kPa`` /
    ``mdot_<element>_mg_s`` columns (``signals``: only these); ``#`` lines are comments.
    Gauge columns (``p_tank_kPag``, ``_barg``, ``_psig``) are made absolute with
    ``ambient_kpa`` (the barometric pressure, kPa), which they need.

    Read by :mod:`pneunet.common.csvdata` (file:line errors, streamed, thinned past
    ``max_rows`` rows).  Columns named in another unit (``p_tank_bar``, ``p_tank_kpa``,
    ``mdot_R1_g_s``, ``time_ms``) are converted; a recording that does not start at
    t = 0 is shifted to start there, its first time stamp kept in
    ``df.attrs["time_origin"]`` (s: the clock of a driven circuit's sources).  Each
    conversion and shift is listed in ``df.attrs["notes"]``; ``df.attrs["source"]``
    names the file.  Raises :class:`DataError` naming the file, the column and the
    line for: a missing file or time column, a column that is not a signal, a
    requested signal missing, gauge pressures, NaN/inf or text cells, times that do
    not increase strictly, fewer than 5 rows."""
    import os

    import pandas as pd

    if hasattr(path_or_frame, "signals") and hasattr(path_or_frame, "table"):  # a Solution
        path_or_frame = pd.DataFrame(path_or_frame.table(
            lambda c: c == "time_s" or c.startswith(("p_", "mdot_"))))
    elif not isinstance(path_or_frame, (str, os.PathLike, pd.DataFrame)):
        raise DataError(f"a recording is a CSV file, a DataFrame or a Solution, got "
                        f"{type(path_or_frame).__name__}", hint="the format: docs/data-format.md")
    if isinstance(path_or_frame, pd.DataFrame):
        where = path_or_frame.attrs.get("source", "trace")
        notes = list(path_or_frame.attrs.get("notes", []))
        rename, units = _plan(list(path_or_frame.columns), signals, where, notes,
                              ambient_kpa)
        wanted = ["time_s"] + [c for c in units if c != "time_s"]
        df = path_or_frame.rename(columns=rename)[wanted].copy()
        df.insert(0, "row", np.arange(1, len(df) + 1))
        for c in wanted:
            values = pd.to_numeric(df[c], errors="coerce")
            text = values.isna() & df[c].notna()
            if text.any():
                raise DataError(f"column {c}: {df[c][text].iloc[0]!r} is not a number "
                                f"(data row {int(df['row'][text].iloc[0])})", where=where,
                                hint="only numbers in data columns")
            df[c] = values.astype(float)
    else:
        notes = []
        csv_file = open_csv(path_or_frame)
        where = csv_file.source
        rename, units = _plan(csv_file.columns, signals, where, notes, ambient_kpa)
        wanted = ["time_s"] + [c for c in units if c != "time_s"]
        inverse = {new: old for old, new in rename.items()}
        table = csv_file.read([inverse.get(c, c) for c in wanted], max_rows=max_rows,
                              what="samples")
        notes.extend(table.notes)
        df = table.frame.rename(columns=rename)[["row", "line"] + wanted]
    _convert(df, units, where, ambient_kpa)
    _check_values(df, wanted, where, {new: old for old, new in rename.items()})
    t = df["time_s"].to_numpy()
    origin = float(path_or_frame.attrs.get("time_origin", 0.0)) \
        if isinstance(path_or_frame, pd.DataFrame) else 0.0
    if t[0] != 0:
        notes.append(f"time_s starts at {t[0]:g} s: counted from the first sample (a driven "
                     "circuit's sources keep the file's clock)")
        origin += float(t[0])
        df["time_s"] = t - t[0]
    out = df[wanted].reset_index(drop=True)
    out.attrs.update(source=where, notes=notes, time_origin=origin)
    return out


def _plan(columns, signals, where, notes, ambient_kpa=None):
    """A recording's header read: ({file name: canonical name}, {canonical name:
    ColumnUnit} of time_s and the signals used); DataError for a missing time column,
    a column that is no signal, a requested signal missing, a gauge column without
    ``ambient_kpa``."""
    rename, units, other = {}, {}, []
    for name in map(str, columns):
        try:
            cu = column_unit(name) or element_column(name)
        except DataError as err:
            raise DataError(err.message, where=where, hint=err.hint) from None
        if cu is None or cu.stem in ("p", "mdot"):
            other.append(name)
            continue
        if cu.gauge and ambient_kpa is None:
            raise DataError(f"column {name} holds gauge pressures and no barometric pressure "
                            "was given", where=where,
                            hint=f"give it (CLI --ambient KPA), or add it to the values and "
                                 f"name the column {cu.canonical}")
        if cu.gauge:
            notes.append(f"column {name} made absolute with the barometric pressure "
                         f"{ambient_kpa:g} kPa")
        if cu.canonical in units:
            first = next((k for k, v in rename.items() if v == cu.canonical), cu.canonical)
            raise DataError(f"columns {first} and {name} both hold {cu.canonical}", where=where,
                            hint="keep one of them (or rename the other)")
        if name != cu.canonical:
            rename[name] = cu.canonical
            notes.append(f"column {name} read as {cu.canonical} (unit {cu.pint_unit})")
        units[cu.canonical] = cu
    if "time_s" not in units:
        raise missing_column(where, "time_s", columns,
                             hint="rename the time column to time_s (seconds)")
    known = [c for c in units if c != "time_s"]
    if not known:
        raise DataError("no signal columns named p_<node>_kPa, mdot_<element>_mg_s or "
                        "another signal pneunet run writes (contraction_<muscle>_mm …)",
                        where=where, hint="columns found: " + ", ".join(map(str, columns)))
    if signals:
        chosen = [rename.get(s, s) for s in signals]
        for s, c in zip(signals, chosen):
            if c not in units:
                raise missing_column(where, s, known, hint="recorded signal columns: "
                                     + ", ".join(known))
        return rename, {c: units[c] for c in ["time_s"] + chosen}
    if other:
        raise DataError(f"column {other[0]} is not a signal (p_<node>_<pressure unit>, "
                        f"mdot_<element>_<flow unit> or <quantity>_<element>_<unit> with a "
                        f"quantity of {', '.join(ELEMENT_SIGNALS)})", where=where,
                        hint="rename it (units: kPa, bar, psi, Pa, MPa; mg_s, g_s, L_min; mm, "
                             "N, mL, K), delete it, or pick the fitted columns with --signal")
    return rename, {"time_s": units["time_s"], **{c: units[c] for c in known}}


def _convert(df, units, where, ambient_kpa=None) -> None:
    from ...common.errors import ParameterError
    from ...physics.units import to_internal

    for c, cu in units.items():
        if not cu.is_canonical:
            try:  # a value that overflows becomes inf, which _check_values reports
                with np.errstate(over="ignore"):
                    df[c] = to_internal(df[c].to_numpy(), cu.pint_unit, cu.kind, name=c,
                                        gauge=cu.gauge, ambient_kpa=ambient_kpa or 0.0)
            except ParameterError as err:
                raise DataError(err.message, where=where, hint=err.hint) from None


#: a recorded node pressure at or below this (kPa absolute) is no absolute pressure: the
#: simulator stops there too (engine.single_rate.VACUUM_KPA)
ABSOLUTE_MIN_KPA = 0.1


def _check_values(df, columns, where, names) -> None:
    """NaN/inf cells, a node pressure at or below vacuum, too few rows, times that do not
    increase: DataError at the line naming the column as the file does (``names``:
    canonical -> file name)."""
    at = "line" if "line" in df else "row"

    def place(i):
        return f"{'line' if at == 'line' else 'data row'} {int(df[at].iloc[i])}"

    column, bad = nonfinite_rows(df, columns)
    if column is not None:
        i = np.flatnonzero(bad)
        more = f" and {i.size - 1} more" if i.size > 1 else ""
        raise DataError(f"column {names.get(column, column)} has a missing, NaN or infinite "
                        f"value at {place(i[0])}{more}", where=where,
                        hint="remove those rows, or fill them (e.g. interpolate) before fitting")
    for c in columns:  # a node pressure is absolute: at or below vacuum it is a gauge reading
        if c.startswith("p_") and c.endswith("_kPa"):
            low = df[c].to_numpy() <= ABSOLUTE_MIN_KPA
            if low.any():
                i = int(np.flatnonzero(low)[0])
                name = names.get(c, c)
                raise DataError(f"column {name}: {float(df[c].iloc[i]):g} kPa at {place(i)} is "
                                f"no absolute pressure (at or below {ABSOLUTE_MIN_KPA:g} kPa)",
                                where=where, hint=f"gauge readings? name the column "
                                f"{c[:-4]}_kPag (made absolute with the barometric pressure, "
                                "--ambient), or check the sensor's unit and offset")
    t = df["time_s"].to_numpy()
    if len(t) < 5:
        raise DataError(f"only {len(t)} rows; a recording needs many samples per cycle",
                        where=where, hint="record at least 5 samples (many per cycle)")
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        what = "repeats" if step[i] == 0 else "goes back"
        raise DataError(f"column time_s {what} at {place(i + 1)} (t = {float(t[i + 1])!r} s after "
                        f"{float(t[i])!r} s)", where=where,
                        hint="sort the rows by time and drop duplicated time stamps")


def signal_of_column(col: str) -> str:
    """``p_tank_kPa`` → ``p_tank``, ``contraction_M1_mm`` → ``contraction_M1`` (the
    Solution signal name of a canonical column)."""
    from ...physics.units import SLOTS

    if col.endswith("_kPa"):
        return col[:-4]
    if col.endswith("_mg_s"):
        return col[:-5]
    unit = SLOTS.get(ELEMENT_SIGNALS.get(col.partition("_")[0], ""), "")
    if unit and col.endswith("_" + unit):
        return col[:-len(unit) - 1]
    return col


def signal_unit(signal: str) -> str:
    """The unit of a Solution signal name (``p_tank`` kPa, ``mdot_R1`` mg/s,
    ``contraction_M1`` mm, ``opening_X1`` '')."""
    from ...physics.units import SLOTS

    if signal.startswith("p_"):
        return "kPa"
    if signal.startswith("mdot_"):
        return "mg/s"
    return SLOTS.get(ELEMENT_SIGNALS.get(signal.partition("_")[0], ""), "")


def jump_samples(y) -> np.ndarray:
    """Indices i where the recorded signal jumps between sample i and i+1."""
    d = np.abs(np.diff(np.asarray(y, float)))
    if not len(d):
        return np.empty(0, int)
    typical = float(np.median(d))
    return np.flatnonzero((d > JUMP_FRACTION * np.ptp(y)) & (d > 8 * typical))


def jump_spans(y) -> list[tuple[int, int]]:
    """(i, j) of the core of each recorded jump (samples i to j, j > i).  A run of steps
    of one sign, each larger than 8 typical steps, has a core: the steps around its
    largest that are at least half of it.  The core is a jump when it moves the signal
    more than :data:`JUMP_FRACTION` of its range, or when it carries more than half of
    the run and the run moves that much: an algebraic node's jump within one sample at
    a slow logger, over several at a fast one; a slow relaxation behind a small step (a
    junction following an actuator's filling) is none."""
    d = np.diff(np.asarray(y, float))
    if not len(d):
        return []
    steep = np.abs(d) > 8 * float(np.median(np.abs(d)))
    least = JUMP_FRACTION * float(np.ptp(y))
    spans, i = [], 0
    while i < len(d):
        j = i + 1
        while steep[i] and j < len(d) and steep[j] and np.sign(d[j]) == np.sign(d[i]):
            j += 1
        if steep[i]:
            top = i + int(np.argmax(np.abs(d[i:j])))
            a, b = top, top + 1
            while a > i and abs(d[a - 1]) >= 0.5 * abs(d[top]):
                a -= 1
            while b < j and abs(d[b]) >= 0.5 * abs(d[top]):
                b += 1
            core, run = abs(float(d[a:b].sum())), abs(float(d[i:j].sum()))
            if core > least or (core > 0.5 * run and run > least):
                spans.append((a, b))
        i = j
    return spans


def compared_samples(y, half_width: int = JUMP_HALF_WIDTH, *, whole_edges: bool = False
                     ) -> np.ndarray:
    """Boolean mask of the samples compared with the model: all but those within
    ``half_width`` samples of a recorded jump (there a few ms of timing would decide
    the error; the jump's timing is compared through the storage nodes).  A jump is a
    step within one sample (:func:`jump_samples`); with ``whole_edges`` it is the core
    of an edge however many samples it spans (:func:`jump_spans`), and as many samples
    as the core spans are left out on each side (at least ``half_width`` − 1): a node
    the model makes jump, recorded by a logger fast enough to see its edge, is left out
    over about the same time as at a slow one (the oscillator's valve output at 50 Hz, a
    3.4 mL dead volume there: its falling edges, 125 kPa over three samples, none of
    them 25 % of the range, were compared sample by sample, and a 0.5 % change of
    R_vent moved p_out's rms misfit from 0.61 to 3.35 kPa)."""
    spans = jump_spans(y) if whole_edges else [(i, i + 1) for i in jump_samples(y)]
    keep = np.ones(len(y), bool)
    for i, j in spans:
        flank = max(half_width - 1, j - i)
        keep[max(0, i - flank):j + flank + 1] = False
    return keep


#: a record oscillates when its swing (1st to 99th percentile over its second half)
#: exceeds this many noise standard deviations (second differences) and it has two
#: full cycles: mid-level crossings of a steady record's noise are no cycles
SWING_SIGMAS = 20.0


def swings(y) -> bool:
    """Whether the recorded signal ``y`` moves by more than its noise (second
    differences, at least its rounding to a logger's grid) over its second half (see
    :data:`SWING_SIGMAS`)."""
    from ..core.noise import difference_sigma, rounding_sigma

    y = np.asarray(y, float)
    half = y[len(y) // 2:]
    if len(half) < 5:
        return False
    swing = float(np.percentile(half, 99) - np.percentile(half, 1))
    sigma = max(difference_sigma(y), rounding_sigma(y))
    return swing > SWING_SIGMAS * (sigma if sigma > 0 else 0.0)


def oscillates(t, y) -> bool:
    """Whether the recorded signal ``y(t)`` oscillates: it swings (:func:`swings`)
    through two full cycles."""
    return swings(y) and len(rising_crossings(t, y)) >= 3


#: hysteresis of a recorded signal's level crossings, in its noise σ
CROSSING_SIGMAS = 4.0


def crossing_band(y) -> float:
    """Hysteresis of the level crossings of a sampled signal ``y`` (its unit):
    :data:`CROSSING_SIGMAS` × its noise (:func:`~pneunet.truth.core.noise.record_sigma`; 0 for
    a simulated one).  Noise riding on a slope near the level then adds no crossing."""
    from ..core.noise import record_sigma

    sigma = record_sigma(y)
    return CROSSING_SIGMAS * sigma if np.isfinite(sigma) else 0.0


def rising_crossings(t, y):
    """Times the signal rises through the middle of its range (cycle starts)."""
    from ...engine.oscillation import rising_crossings as crossings_at

    y = np.asarray(y, float)
    return crossings_at(np.asarray(t, float), y, 0.5 * (np.min(y) + np.max(y)),
                        crossing_band(y))


def split_by_cycles(data, node: str, train_fraction: float = 0.5, where: str = "trace",
                    driven: bool = False):
    """(train, test) windows: the first cycles (``train_fraction`` of the full cycles,
    at least 2) and the remainder; for a record that does not oscillate at ``node``
    (:func:`oscillates`: a steady state, a slow drift) the first ``train_fraction`` of
    its duration and the rest.  DataError when an oscillating record holds fewer than
    two full cycles at ``node`` (nothing would be left to test on), unless the circuit
    is ``driven`` by its sources (a single inflation and deflation): then the whole
    record is both windows.  Split in time, its inflation would be fitted alone and its
    deflation held out: a control-line tube's delay of the in-valve is then taken up by
    the logger's clock (the amplifier inflated once, from 1.5 s: 340 ms, 6.45× the floor
    held out), and an effect's published form fitted on one half predicts the other to
    1.6×."""
    df = read_trace(data)
    col = f"p_{node}_kPa"
    if col not in df:
        raise DataError(f"column {col} (the node whose cycles split the record) is not in "
                        "the recording", where=where,
                        hint="pick the cycle node with --node; columns: "
                        + ", ".join(c for c in df.columns if c != "time_s"))
    t = df["time_s"].to_numpy()
    y = df[col].to_numpy()
    if not swings(y):  # a steady record: its later part is held out
        cut = float(t[0] + train_fraction * (t[-1] - t[0]))
        return (float(t[0]), cut), (cut, float(t[-1]))
    rises = rising_crossings(t, y)
    if driven and len(rises) < 3:
        whole = (float(t[0]), float(t[-1]))
        return whole, whole
    if len(rises) < 3:
        raise DataError(f"column {col} holds {max(len(rises) - 1, 0)} full cycle(s); a "
                        "diagnosis needs at least two (fit on the first, test on the rest)",
                        where=where, hint="record longer (8 cycles or more is best)")
    k = max(1, int(round(train_fraction * (len(rises) - 1))))
    cut = rises[min(k, len(rises) - 2)]
    return (float(t[0]), float(cut)), (float(cut), float(t[-1]))
