"""Recorded circuit transients (time_s, p_<node>_kPa, mdot_<element>_mg_s): reading
with checks that name the file, the column and what to do; which samples are compared
(jumping signals); the split into fitted and held-out cycles."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import DataError

#: a sample step larger than this fraction of the signal's range (and than 8 typical
#: steps) is a jump of an algebraic node (p_out at a fold)
JUMP_FRACTION = 0.25
#: samples left out on each side of a recorded jump
JUMP_HALF_WIDTH = 2


def read_trace(path_or_frame, signals=None):
    """A recorded transient as a DataFrame: ``time_s`` then ``p_<node>_kPa`` /
    ``mdot_<element>_mg_s`` columns (``signals``: only these); ``#`` lines are comments.

    Raises :class:`DataError` naming the file and column for: a missing file or
    ``time_s``, no signal column, a requested column missing, NaN or non-numeric
    values, times that do not increase strictly, fewer than 5 rows."""
    import pandas as pd

    if isinstance(path_or_frame, pd.DataFrame):
        df = path_or_frame.copy()
        where = "trace"
    else:
        where = str(path_or_frame)
        if not Path(where).exists():
            raise DataError(f"no such file: {where}", hint="give the path of a CSV recording")
        try:
            df = pd.read_csv(where, comment="#")
        except (ValueError, pd.errors.ParserError) as err:
            raise DataError(f"cannot read the recording as CSV: {err}", where=where) from None
    if "time_s" not in df.columns:
        raise DataError("a transient recording needs a time_s column", where=where,
                        hint="columns found: " + ", ".join(map(str, df.columns))
                        + "; rename the time column to time_s (seconds)")
    cols = [c for c in df.columns if c != "time_s"]
    known = [c for c in cols if (c.startswith("p_") and c.endswith("_kPa"))
             or (c.startswith("mdot_") and c.endswith("_mg_s"))]
    if not known:
        raise DataError("no signal columns named p_<node>_kPa or mdot_<element>_mg_s",
                        where=where, hint="columns found: " + ", ".join(map(str, cols)))
    if signals:
        missing = [s for s in signals if s not in df.columns]
        if missing:
            raise DataError(f"column {missing[0]} is not in the recording", where=where,
                            hint="recorded signal columns: " + ", ".join(known))
        known = list(signals)
    df = df[["time_s"] + known]
    for c in df.columns:
        v = pd.to_numeric(df[c], errors="coerce")
        bad = np.flatnonzero(~np.isfinite(v.to_numpy(float)))
        if bad.size:
            rows = ", ".join(str(i + 1) for i in bad[:3]) + (" …" if bad.size > 3 else "")
            raise DataError(f"column {c} has {bad.size} missing or non-numeric value(s) "
                            f"(data rows {rows})", where=where,
                            hint="remove those rows, or fill them (e.g. interpolate) before "
                                 "fitting")
        df[c] = v.astype(float)
    t = df["time_s"].to_numpy()
    if len(t) < 5:
        raise DataError(f"only {len(t)} rows; a recording needs many samples per cycle",
                        where=where)
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        what = "repeats" if step[i] == 0 else "goes back"
        raise DataError(f"column time_s {what} at data row {i + 2} (t = {t[i + 1]:g} s after "
                        f"{t[i]:g} s)", where=where,
                        hint="sort the rows by time and drop duplicated time stamps")
    return df.reset_index(drop=True)


def signal_of_column(col: str) -> str:
    """``p_tank_kPa`` → ``p_tank`` (the Solution signal name)."""
    if col.endswith("_kPa"):
        return col[:-4]
    if col.endswith("_mg_s"):
        return col[:-5]
    return col


def jump_samples(y) -> np.ndarray:
    """Indices i where the recorded signal jumps between sample i and i+1."""
    d = np.abs(np.diff(np.asarray(y, float)))
    if not len(d):
        return np.empty(0, int)
    typical = float(np.median(d))
    return np.flatnonzero((d > JUMP_FRACTION * np.ptp(y)) & (d > 8 * typical))


def compared_samples(y, half_width: int = JUMP_HALF_WIDTH) -> np.ndarray:
    """Boolean mask of the samples compared with the model: all but those within
    ``half_width`` samples of a recorded jump (there a few ms of timing would decide
    the error; the jump's timing is compared through the storage nodes)."""
    keep = np.ones(len(y), bool)
    for i in jump_samples(y):
        keep[max(0, i - half_width + 1):i + half_width + 1] = False
    return keep


def rising_crossings(t, y):
    """Times the signal rises through the middle of its range (cycle starts)."""
    from ..analysis.oscillation import _rising_crossings

    y = np.asarray(y, float)
    return _rising_crossings(np.asarray(t, float), y, 0.5 * (np.min(y) + np.max(y)))


def split_by_cycles(data, node: str, train_fraction: float = 0.5, where: str = "trace"):
    """(train, test) windows: the first cycles (``train_fraction`` of the full cycles,
    at least 2) and the remainder.  DataError when the record holds fewer than two full
    cycles at ``node`` (nothing would be left to test on)."""
    df = read_trace(data)
    col = f"p_{node}_kPa"
    if col not in df:
        raise DataError(f"column {col} (the node whose cycles split the record) is not in "
                        "the recording", where=where,
                        hint="pick the cycle node with --node; columns: "
                        + ", ".join(c for c in df.columns if c != "time_s"))
    t = df["time_s"].to_numpy()
    rises = rising_crossings(t, df[col].to_numpy())
    if len(rises) < 3:
        raise DataError(f"column {col} holds {max(len(rises) - 1, 0)} full cycle(s); a "
                        "diagnosis needs at least two (fit on the first, test on the rest)",
                        where=where, hint="record longer (8 cycles or more is best)")
    k = max(1, int(round(train_fraction * (len(rises) - 1))))
    cut = rises[min(k, len(rises) - 2)]
    return (float(t[0]), float(cut)), (float(cut), float(t[-1]))
