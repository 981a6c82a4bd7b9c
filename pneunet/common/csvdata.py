"""Read a measurement CSV with checks: the one reader behind ``fit``, ``diagnose`` and
``fit-trace`` (bench data in :mod:`pneunet.truth.valves.identify.data`, recordings in
:mod:`pneunet.truth.circuits.data`).

:func:`open_csv` reads only the comment lines and the header, so a command can check
its columns before any work; :meth:`CsvFile.read` then streams the rows block by block
(bounded memory whatever the file size) and keeps every ``stride``-th row when the file
holds more than ``max_rows`` data rows (a notice says so).  Every problem is a
:class:`~pneunet.common.errors.DataError` naming the file, the line (and column) and what to
do: a missing or empty file, bytes that are not UTF-8 (Latin-1, UTF-16), no header, a
header of numbers or of another separator, unnamed or repeated column names, a row with
too many or too few fields, text in a number column.  NaN and inf cells are kept as
such for the caller's own rules (:func:`nonfinite_rows`).
"""
from __future__ import annotations

import csv
import difflib
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import DataError

#: bytes read per block (whole lines); the memory of a read is a few blocks + max_rows
BLOCK_BYTES = 4 << 20
#: default row caps (``--max-rows``): bench data (11x the paper's 4410-point protocol)
#: and circuit recordings; longer files are thinned evenly with a notice
BENCH_MAX_ROWS = 50_000
TRACE_MAX_ROWS = 200_000
UTF8_HINT = ("save the file as UTF-8 CSV ('CSV UTF-8' in a spreadsheet's Save as, or "
             "'iconv -f latin1 -t utf-8 in.csv > out.csv'; -f utf-16 for UTF-16)")


@dataclass
class Table:
    """Rows read from a CSV: ``frame`` with the file's columns (the number columns as
    float) and ``row`` (1-based data row) and ``line`` (1-based file line) columns."""

    frame: object
    source: str
    rows_in_file: int
    stride: int = 1
    notes: list[str] = field(default_factory=list)


def _at(path, line, column=None) -> str:
    return f"{path}:{line}" if column is None else f"{path}:{line}:{column}"


class CsvFile:
    """A CSV file whose header has been read: ``columns`` (names stripped),
    ``header_line`` (1-based), ``source`` (the path as given)."""

    def __init__(self, path, source: str | None = None):
        self.path = Path(path)
        self.source = str(path) if source is None else source
        if not self.path.exists():
            raise DataError("no such file", where=self.source, hint="check the path")
        if not self.path.is_file():
            raise DataError("not a regular file", where=self.source, hint="give a CSV file")
        try:
            with self.path.open("rb") as fh:
                head = fh.read(BLOCK_BYTES)
        except OSError as err:
            raise DataError(f"cannot read the file: {err.strerror or err}", where=self.source,
                            hint="check its permissions") from None
        if not head.strip():
            raise DataError("the file is empty", where=self.source,
                            hint="a CSV needs a header row (time_s,...) and data rows")
        if head[:2] in (b"\xff\xfe", b"\xfe\xff") or b"\x00" in head:
            kind = "UTF-16 text" if head[:2] in (b"\xff\xfe", b"\xfe\xff") else \
                "NUL bytes (UTF-16 text or a binary file)"
            line = head[:max(head.find(b"\x00"), 0)].count(b"\n") + 1
            raise DataError(f"the file holds {kind}, not UTF-8", where=_at(self.source, line),
                            hint=UTF8_HINT)
        self._skip = 3 if head.startswith(b"\xef\xbb\xbf") else 0
        number = 0
        for raw in head[self._skip:].split(b"\n"):
            number += 1
            text = _decode(raw, self.source, number)
            if text.strip() and not text.lstrip().startswith("#"):
                break
        else:
            raise DataError("no header row (only comments or blank lines)", where=self.source,
                            hint="add a header row such as time_s,p_in_kPa,...")
        self.header_line = number
        self.columns = _header(text, self.source, number)

    def read(self, numeric=(), *, max_rows: int | None = None, what: str = "rows") -> Table:
        """All data rows, ``numeric`` columns as float; more than ``max_rows`` rows are
        thinned to every ``stride``-th row (stride a power of two) with a notice."""

        import pandas as pd

        numeric = [c for c in numeric if c in self.columns]
        if max_rows is not None and max_rows < 2:
            raise DataError(f"max_rows must be at least 2, got {max_rows}")
        parts, kept, stride, total = [], 0, 1, 0
        for frame in self._blocks(numeric):
            total += len(frame)
            if stride > 1:
                frame = frame[(frame["row"].to_numpy() - 1) % stride == 0]
            parts.append(frame)
            kept += len(frame)
            while max_rows is not None and kept > max_rows:
                stride *= 2
                whole = pd.concat(parts, ignore_index=True)
                parts = [whole[(whole["row"].to_numpy() - 1) % stride == 0]]
                kept = len(parts[0])
        if total == 0:
            raise DataError(f"a header (line {self.header_line}) but no data rows",
                            where=self.source, hint="the file ends after its header")
        frame = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
        frame = frame.reset_index(drop=True)
        notes = []
        if stride > 1:
            notes.append(f"{self.source} holds {total} {what}, more than the limit of "
                         f"{max_rows}: every {stride}th row is used ({len(frame)} rows); "
                         f"raise the limit with --max-rows to use more")
        return Table(frame, self.source, total, stride, notes)

    def _blocks(self, numeric):
        """DataFrames of consecutive data lines, checked (fields, numbers)."""
        import numpy as np

        line_base, row = 0, 0
        for text in self._texts():
            body, numbers = self._data_lines(text, line_base)
            line_base += text.count("\n")
            if not len(numbers):
                continue
            frame = _parse(body, numbers, self.columns, numeric, self.source)
            frame.insert(0, "row", np.arange(row + 1, row + len(frame) + 1))
            frame.insert(1, "line", numbers)
            row += len(frame)
            yield frame

    def _texts(self):
        """The file after its byte-order mark as decoded blocks of whole lines."""
        tail, line_base = b"", 0
        with self.path.open("rb") as fh:
            fh.read(self._skip)
            while True:
                block = fh.read(BLOCK_BYTES)
                data = tail + block
                if block:
                    cut = data.rfind(b"\n") + 1
                    data, tail = data[:cut], data[cut:]
                    if not data:
                        continue
                elif not data:
                    return
                else:
                    data, tail = data + b"\n", b""  # a last line without its newline
                yield _decode(data, self.source, line_base + 1).replace("\r\n", "\n")
                line_base += data.count(b"\n")
                if not block:
                    return

    def _data_lines(self, text: str, line_base: int):
        """(data text, file line numbers) of a block: header, comment and blank lines
        left out (the common block of plain data lines is passed on as it is)."""
        import numpy as np

        start = 0
        for _ in range(max(0, self.header_line - line_base)):  # comments and the header
            start = text.find("\n", start) + 1
            if not start:  # the header is in a later block
                return "", np.empty(0, dtype=np.int64)
        body = text[start:]
        first = line_base + text.count("\n", 0, start) + 1
        if "#" not in body and not _BLANK.search("\n" + body):
            return body, np.arange(first, first + body.count("\n"), dtype=np.int64)
        lines = body.split("\n")[:-1]
        keep = [i for i, s in enumerate(lines) if s.strip() and not s.lstrip().startswith("#")]
        return ("\n".join(lines[i] for i in keep) + "\n",
                np.asarray(keep, dtype=np.int64) + first)


#: an empty or blank line (the text is prefixed with a newline before searching)
_BLANK = re.compile(r"\n[ \t]*(\n|$)")


def _parse(body: str, numbers, columns, numeric, source):
    """Data lines as a DataFrame, ``numeric`` columns as float; DataError at the first
    line with a wrong number of fields or text in a number column."""
    import pandas as pd

    n_fields = len(columns)
    if '"' in body:
        _check_quotes(body.split("\n")[:-1], numbers, source)
    if body.count(",") != len(numbers) * (n_fields - 1):
        _check_fields(body.split("\n")[:-1], numbers, n_fields, source)
    try:
        return pd.read_csv(io.StringIO(body), header=None, names=columns, lineterminator="\n",
                           skipinitialspace=True, dtype={c: "float64" for c in numeric})
    except pd.errors.ParserError as err:  # quoted commas, or a long row beside a short one
        m = re.search(r"in line (\d+), saw (\d+)", str(err))
        line = numbers[int(m.group(1)) - 1] if m else numbers[0]
        raise DataError(f"{m.group(2) + ' fields, the header has ' + str(n_fields) if m else err}",
                        where=_at(source, line),
                        hint="every row needs one value per column (a ragged or cut row; fix "
                             "or delete it)") from None
    except (ValueError, TypeError):
        frame = pd.read_csv(io.StringIO(body), header=None, names=columns, lineterminator="\n",
                            skipinitialspace=True, dtype={c: str for c in numeric})
        lines = body.split("\n")
        for c in numeric:
            frame[c] = _numbers(frame[c], c, numbers, source, columns.index(c), lines)
        return frame


def open_csv(path, source: str | None = None) -> CsvFile:
    """The CSV at ``path`` with its header read and checked (see :class:`CsvFile`);
    messages name ``source`` (default ``path``)."""
    return CsvFile(path, source)


def _decode(data: bytes, source, first_line: int) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        line = first_line + before.count(b"\n")
        column = exc.start - (before.rfind(b"\n") + 1) + 1
        byte = data[exc.start:exc.start + 1].hex().upper()
        raise DataError(f"byte 0x{byte} at character {column} is not UTF-8 (Latin-1 or "
                        f"Windows-1252 text?)", where=_at(source, line), hint=UTF8_HINT) from None


def _header(text: str, source, line: int) -> list[str]:
    where = _at(source, line)
    try:
        names = [c.strip() for c in next(csv.reader([text.rstrip("\r")]))]
    except csv.Error as err:  # a bare carriage return inside the line
        raise DataError(f"cannot read the header: {err}", where=where,
                        hint="one header line of comma-separated names") from None
    if len(names) == 1 and any(sep in names[0] for sep in (";", "\t")):
        sep = "semicolons" if ";" in names[0] else "tabs"
        raise DataError(f"the header is separated by {sep}, not commas", where=where,
                        hint="save as comma-separated CSV with '.' as decimal point")
    if all(_is_number(n) for n in names):
        raise DataError("the first line that is not a comment holds numbers, not column names",
                        where=where, hint="add a header row such as time_s,p_in_kPa,...")
    for i, name in enumerate(names):
        if not name:
            raise DataError(f"header field {i + 1} has no name", where=where,
                            hint="name every column (a trailing comma makes an empty one)")
        if names.index(name) != i:
            raise DataError(f"column {name} appears twice in the header", where=where,
                            hint="give every column its own name")
    return names


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_fields(body, numbers, n_fields, source) -> None:
    import numpy as np

    counts = np.fromiter((s.count(",") for s in body), dtype=np.int64, count=len(body)) + 1
    bad = np.flatnonzero(counts != n_fields)
    quoted = [i for i in bad if '"' in body[i]]  # quoted commas: pandas checks those
    bad = [i for i in bad if i not in quoted]
    if bad:
        i = bad[0]
        where = _at(source, numbers[i], _field_column(body[i], min(counts[i], n_fields + 1) - 1)
                    if counts[i] > n_fields else len(body[i]) + 1)
        raise DataError(f"{counts[i]} fields, the header has {n_fields}", where=where,
                        hint="every row needs one value per column (a ragged or cut row; fix "
                             "or delete it)")


def _check_quotes(body, numbers, source) -> None:
    """A DataError at the first line whose quotes do not close (a quoted cell holding a
    line break: each line is one row here)."""
    for i, text in enumerate(body):
        if text.count('"') % 2:
            raise DataError("a quoted cell is not closed on its line (a line break inside "
                            "quotes?)", where=_at(source, numbers[i], text.rfind('"') + 1),
                            hint="one row per line: remove the line break and the quotes")


def _field_column(text: str, index: int) -> int:
    """1-based character column where field ``index`` (0-based) of a line starts."""
    return len(",".join(text.split(",")[:index])) + (2 if index else 1)


def _numbers(values, column: str, numbers, source, index: int = 0, lines=()):
    """``values`` (strings) as float; DataError at the first text that is not a number
    (an empty cell or NA/NaN is NaN, inf and 1e999 are inf: the caller's rules), at its
    line and column (``index``: the column's field, ``lines``: the data lines)."""
    import numpy as np

    import pandas as pd

    out = pd.to_numeric(values, errors="coerce").astype(float)
    text = out.isna().to_numpy() & values.notna().to_numpy()
    if text.any():
        text &= ~np.isin(values.to_numpy(dtype=object), np.array(_NA_WORDS, dtype=object))
    if text.any():
        i = int(np.flatnonzero(text)[0])
        where = _at(source, numbers[i], _field_column(lines[i], index)) if len(lines) > i \
            else _at(source, numbers[i])
        raise DataError(f"column {column} (field {index + 1}): {values.iloc[i]!r} is not a "
                        "number", where=where,
                        hint="only numbers in data columns, '.' as decimal point, no units in "
                             "the cells")
    return out


#: cell texts pandas reads as "missing" (NaN), which the callers' NaN rules handle
_NA_WORDS = ("", "NA", "N/A", "NaN", "nan", "NAN", "-nan", "null", "NULL", "None", "#N/A",
             "n/a", "<NA>")


def missing_column(source, name: str, found, hint: str = "", taken=()) -> DataError:
    """The DataError for a required column ``name`` not among ``found`` (a did-you-mean
    from the columns not in ``taken``, those already used as something else)."""
    spare = [str(c) for c in found if c not in taken]
    close = difflib.get_close_matches(name, spare, n=1, cutoff=0.6)
    text = f"did you mean {close[0]}? " if close else ""
    return DataError(f"column {name} is missing", where=str(source),
                     hint=text + "columns found: " + ", ".join(map(str, found))
                     + (f"; {hint}" if hint else ""))


def nonfinite_rows(frame, columns):
    """(column, mask) of the first of ``columns`` holding NaN or ±inf, else (None, None)."""
    import numpy as np

    for c in columns:
        mask = ~np.isfinite(frame[c].to_numpy(float))
        if mask.any():
            return c, mask
    return None, None


#: unit suffixes of column names, by quantity (``_`` stands for ``/`` in flows)
_UNITS = {"pressure": ("kPa", "Pa", "hPa", "MPa", "bar", "mbar", "psi", "atm"),
          "flow": ("mg_s", "g_s", "kg_s", "kg_h", "g_min", "L_min", "mL_min", "slpm", "sccm"),
          "time": ("s", "ms", "us", "min", "h")}
_PREFIX = {"p_": "pressure", "mdot_": "flow"}
_SUFFIXES = sorted(((u + g, kind, u, bool(g)) for kind, units in _UNITS.items() for u in units
                    for g in (("", "g") if kind == "pressure" else ("",))),
                   key=lambda s: -len(s[0]))
_CANONICAL = {"pressure": "kPa", "flow": "mg_s", "time": "s"}


@dataclass(frozen=True)
class ColumnUnit:
    """A column name read as quantity, stem and unit: ``p_tank_bar`` → pressure,
    ``p_tank``, ``bar``; ``gauge`` for ``kPag``, ``barg``...; ``pint_unit`` as
    :func:`pneunet.physics.units.to_internal` reads it (``L_min`` → ``L/min``)."""

    kind: str
    stem: str
    unit: str
    gauge: bool = False

    @property
    def canonical(self) -> str:
        return f"{self.stem}_{_CANONICAL[self.kind]}"

    @property
    def pint_unit(self) -> str:
        return self.unit.replace("_", "/")

    @property
    def is_canonical(self) -> bool:
        return self.unit == _CANONICAL[self.kind] and not self.gauge


def column_unit(name: str) -> ColumnUnit | None:
    """Quantity and unit of a ``p_<x>_<unit>``, ``mdot_<x>_<unit>`` or ``time_<unit>``
    column (units match without regard to case: ``p_tank_kpa`` is kPa); None for other
    names or an unknown unit.  A unit of the wrong quantity (``p_tank_mg_s``) is a
    DataError naming the column."""
    kind = next((k for prefix, k in _PREFIX.items() if name.startswith(prefix)),
                "time" if name.startswith("time_") else None)
    if kind is None:
        return None
    low = name.lower()
    for suffix, unit_kind, unit, gauge in _SUFFIXES:
        if not low.endswith("_" + suffix.lower()):
            continue
        stem = name[:len(name) - len(suffix) - 1]
        if kind == "time" and stem != "time":
            continue
        if unit_kind != kind:
            examples = ", ".join(u.replace("_", "/") for u in _UNITS[kind])
            raise DataError(f"column {name}: a {kind} with the {unit_kind} unit "
                            f"{unit.replace('_', '/')}",
                            hint=f"a {kind} column ends in one of {examples} "
                                 f"(e.g. {stem}_{_CANONICAL[kind]})")
        return ColumnUnit(kind, stem, unit, gauge)
    return None
