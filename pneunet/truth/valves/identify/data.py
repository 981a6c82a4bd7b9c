"""Read and check static valve measurements (the CSV layout of docs/identify.md).

:func:`load_measurements` accepts the canonical CSV (or a DataFrame), maps other
column names, converts other units (bar, psi, L/min normal ...) and gauge
pressures, optionally removes the flow-sensor bias as the paper did (subtract the
smallest reading), and checks the data.  Whole-file problems (missing columns,
gauge values passed as absolute, non-numeric cells) always raise a
:class:`~pneunet.common.errors.DataError`; row problems (NaN, negative absolute pressure,
p_in ≤ p_out, duplicate rows) raise by default and, with ``on_invalid="exclude"``,
are dropped and listed in :attr:`Measurements.excluded` — never silently.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ....common.csvdata import BENCH_MAX_ROWS, column_unit, missing_column, open_csv
from ....common.errors import DataError, ParameterError
from ....common.reprs import Summarized

PRESSURES = ("p_in_kPa", "p_out_kPa", "p_ctrl_kPa")
REQUIRED = ("time_s",) + PRESSURES + ("mdot_mg_s",)
OPTIONAL = ("sweep", "valve", "h_seat_mm", "T_K")
#: lowest absolute pressure (kPa) a valve bench plausibly sees; below it the
#: numbers look like gauge readings passed as absolute
GAUGE_SUSPECT_KPA = 30.0


@dataclass(repr=False)
class Measurements(Summarized):
    """Checked measurements in canonical units.

    ``frame``: canonical columns (``time_s, p_in_kPa, p_out_kPa, p_ctrl_kPa,
    mdot_mg_s`` + optional ones) with a ``row`` column giving the data row number
    in the source (1-based, header excluded) and ``line`` the file line when read
    from a file.  ``excluded``: dropped rows with the same columns and a ``reason``.
    """

    frame: pd.DataFrame
    excluded: pd.DataFrame
    source: str = "<DataFrame>"
    bias_mg_s: float = 0.0
    ambient_kpa: float | None = None
    notes: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.frame)

    def _summary(self):
        rows = [("points", str(len(self.frame))), ("excluded", str(len(self.excluded))),
                ("columns", ", ".join(c for c in self.frame.columns if c not in ("row", "line")))]
        return self.source, rows, ".frame, .excluded, .summary()"

    def summary(self) -> str:
        lines = [f"{self.source}: {len(self.frame)} points used, {len(self.excluded)} excluded"]
        if len(self.excluded):
            for reason, group in self.excluded.groupby("reason", sort=False):
                lines.append(f"  excluded {len(group)} ({reason}): rows "
                             + _rows_text(group["row"].to_numpy()))
        lines.extend(f"  {note}" for note in self.notes)
        return "\n".join(lines)


def _rows_text(rows, limit=12) -> str:
    rows = [int(r) for r in rows]
    text = ", ".join(str(r) for r in rows[:limit])
    return text + (f", … ({len(rows) - limit} more)" if len(rows) > limit else "")


#: limits of plausible bench values (canonical units): beyond them a cell is a
#: logging error (1e308, a sensor's overflow code), not a measurement
MAX_PRESSURE_KPA = 1e5
MAX_FLOW_MG_S = 1e7
#: fewest valid rows a fit or diagnosis can use (a few sweeps)
MIN_ROWS = 20
#: default cap on the rows read from a file; longer files are thinned evenly with a
#: notice (``max_rows``, CLI ``--max-rows``)
DEFAULT_MAX_ROWS = BENCH_MAX_ROWS


def _unit_for(column: str, units: dict) -> str | None:
    if column in units:
        return units[column]
    stem = column.rsplit("_", 1)[0] if column != "time_s" else "time"
    if stem in units:
        return units[stem]
    if column in PRESSURES:
        return units.get("pressure")
    if column == "mdot_mg_s":
        return units.get("flow")
    return None


def _resolve_columns(names, source, columns, units, notes) -> tuple[dict, set]:
    """Renames {file name: canonical} for the column mapping and for canonical stems
    with another unit (``p_in_bar``, ``p_in_kpa``, ``mdot_g_s``, ``time_ms``: the unit
    goes into ``units``); the gauge columns {canonical: file name}; DataError for a missing column."""
    rename, gauge_cols = {}, {}
    for old, new in (columns or {}).items():
        if old not in names:
            raise DataError(f"the column mapping names {old}, which is not in the data",
                            where=source, hint="columns found: " + ", ".join(map(str, names)))
        rename[old] = new
    present = {rename.get(n, n) for n in names}
    for name in names:
        if name in rename or not isinstance(name, str):
            continue
        try:
            cu = column_unit(name)
        except DataError as err:
            raise DataError(err.message, where=source, hint=err.hint) from None
        if cu is None or cu.canonical not in REQUIRED or cu.canonical in present \
                or (cu.is_canonical and name == cu.canonical):
            continue
        rename[name] = cu.canonical
        present.add(cu.canonical)
        units.setdefault(cu.canonical, cu.pint_unit)
        if cu.gauge:
            gauge_cols[cu.canonical] = name
        notes.append(f"column {name} read as {cu.canonical} (unit {cu.pint_unit}"
                     f"{', gauge' if cu.gauge else ''})")
    for c in REQUIRED:
        if c not in present:
            raise missing_column(source, c, names, taken=present & set(REQUIRED),
                                 hint="rename it or pass a column mapping (columns={'Pin': "
                                      "'p_in_kPa'}, CLI --map Pin=p_in_kPa)")
    return rename, gauge_cols


def _numeric(frame, source) -> None:
    """Number columns of a DataFrame given by the caller as float (a file's are already)."""
    for column in REQUIRED + tuple(c for c in ("sweep", "h_seat_mm", "T_K") if c in frame):
        values = pd.to_numeric(frame[column], errors="coerce")
        bad = values.isna() & frame[column].notna()
        if bad.any():
            rows = frame.loc[bad, "row"].to_numpy()
            raise DataError(f"column {column} holds text that is not a number in "
                            f"row(s) {_rows_text(rows)} (e.g. {frame.loc[bad, column].iloc[0]!r})",
                            where=source,
                            hint="use '.' as decimal point and only numbers in data columns")
        frame[column] = values.astype(float)


def _convert_units(frame, source, units, gauge, gauge_cols, ambient_kpa) -> None:
    from ....physics.units import to_internal

    if (gauge or gauge_cols) and ambient_kpa is None:
        what = "gauge pressures" if gauge else "the gauge column(s) " + ", ".join(
            sorted(gauge_cols.values()))
        raise DataError(f"{what} need the ambient (barometric) pressure",
                        hint="pass ambient_kpa (CLI --ambient), e.g. 96 kPa at 480 m as in "
                             "the paper, 101.325 kPa at sea level", where=source)
    try:  # a value that overflows becomes inf, which the row checks report
        with np.errstate(over="ignore"):
            for column in PRESSURES:
                frame[column] = to_internal(frame[column].to_numpy(),
                                            _unit_for(column, units) or "kPa", "pressure",
                                            gauge=gauge or column in gauge_cols,
                                            ambient_kpa=ambient_kpa or 0.0, name=column)
            for column, slot in (("mdot_mg_s", "flow"), ("time_s", "time")):
                unit = _unit_for(column, units)
                if unit:
                    frame[column] = to_internal(frame[column].to_numpy(), unit, slot,
                                                name=column)
    except ParameterError as exc:
        raise DataError(exc.message, where=source, hint=exc.hint) from None


def _row_problems(frame):
    """(mask, reason) for each kind of invalid row, each row under its first reason."""
    problems = []
    invalid = np.zeros(len(frame), bool)

    def add(mask, reason):
        nonlocal invalid
        mask = np.asarray(mask, bool) & ~invalid
        problems.append((mask, reason))
        invalid |= mask

    for column in REQUIRED:
        values = frame[column].to_numpy(float)
        add(np.isnan(values), f"NaN in {column}")
        add(np.isinf(values), f"inf in {column}")
    for column in PRESSURES:
        add((frame[column] <= 0).to_numpy(), f"negative absolute pressure in {column}")
        add((frame[column] > MAX_PRESSURE_KPA).to_numpy(),
            f"implausible pressure in {column} (over {MAX_PRESSURE_KPA:g} kPa)")
    add((frame["mdot_mg_s"].abs() > MAX_FLOW_MG_S).to_numpy(),
        f"implausible flow in mdot_mg_s (over {MAX_FLOW_MG_S:g} mg/s)")
    add((frame["p_in_kPa"] <= frame["p_out_kPa"]).to_numpy(),
        "p_in <= p_out (no forward pressure difference)")
    add(frame.duplicated(subset=[c for c in frame.columns if c not in ("row", "line")],
                         keep="first").to_numpy(), "duplicate of an earlier row")
    times = frame["time_s"].to_numpy(float)
    add(pd.Series(np.where(invalid, np.nan, times)).duplicated(keep="first").to_numpy()
        & ~np.isnan(times), "repeated time stamp")
    return problems


_HINTS = {"p_in ": "the input port must be the higher-pressure port; swap the columns for "
                   "backward flow, or exclude these rows",
          "dupli": "remove the repeated rows",
          "repea": "each held point needs its own time stamp; remove or fix the repeated ones",
          "NaN i": "fill the gaps",
          "inf i": "an infinite value is a logging error; fix or remove these rows",
          "impla": "a logging error or a wrong unit (--pressure-unit, --flow-unit)",
          "negat": "check the sensor or the units; gauge data needs --gauge"}


def _exclude(frame, source, lines, on_invalid):
    """Frame without the invalid rows and the excluded rows with their reason (or a
    DataError naming the rows and file lines of the first kind of invalid row)."""
    parts, drop = [], np.zeros(len(frame), bool)
    for mask, reason in _row_problems(frame):
        if not mask.any():
            continue
        rows = frame.loc[mask, "row"].to_numpy()
        where = _rows_text(rows)
        if lines:
            where += " (file lines " + _rows_text(frame.loc[mask, "line"].to_numpy()) + ")"
        if on_invalid == "raise":
            raise DataError(f"{mask.sum()} row(s) with {reason}: data row(s) {where}",
                            hint=_HINTS[reason[:5]] + "; or pass on_invalid='exclude' (CLI "
                                 "--exclude-invalid) to drop them with a report", where=source)
        part = frame.loc[mask].copy()
        part["reason"] = reason
        parts.append(part)
        drop |= mask
    excluded = (pd.concat(parts, ignore_index=True) if parts
                else pd.DataFrame(columns=list(frame.columns) + ["reason"]))
    return frame.loc[~drop], excluded


def _time_order(frame, source, notes):
    """Rows in time order: a file written backwards is reversed with a notice; any
    other step back in time is a DataError at its line."""
    t = frame["time_s"].to_numpy(float)
    step = np.diff(t)
    if not len(step) or np.all(step > 0):
        return frame
    if np.all(step < 0):
        notes.append("rows are in reverse time order: reversed (the order defines the sweeps)")
        return frame.iloc[::-1]
    i = int(np.flatnonzero(step <= 0)[0])
    at = frame.iloc[i + 1]
    where = f"line {int(at['line'])}" if "line" in frame else f"data row {int(at['row'])}"
    raise DataError(f"column time_s goes back at {where} (t = {t[i + 1]:g} s after "
                    f"{t[i]:g} s)", hint="sort the rows by time_s; a file joining several runs "
                                         "needs times that continue from run to run", where=source)


def _read_file(path, columns, units, notes, max_rows):
    """A bench CSV read with its columns checked first; (frame, renames, gauge columns)."""
    csv_file = open_csv(path)
    rename, gauge_cols = _resolve_columns(csv_file.columns, csv_file.source, columns, units,
                                          notes)
    numeric = [old for old, new in rename.items() if new in REQUIRED] + [
        c for c in csv_file.columns if c in REQUIRED + ("sweep", "h_seat_mm", "T_K")]
    table = csv_file.read(numeric, max_rows=max_rows, what="data rows")
    notes.extend(table.notes)
    return table.frame.rename(columns=rename), gauge_cols


def load_measurements(path_or_df, *, ambient_kpa=None, gauge=False, units=None, columns=None,
                      flow_bias=None, on_invalid="raise", valve=None,
                      check_gauge=True, max_rows=DEFAULT_MAX_ROWS) -> Measurements:
    """Load bench data into canonical units and check it.

    Parameters
    ----------
    path_or_df : str, Path or DataFrame
        A CSV file (layout: docs/identify.md, section 1) or a DataFrame.
    ambient_kpa : float
        Barometric pressure (kPa); required with ``gauge=True`` (paper: 96 kPa).
    gauge : bool
        The pressure columns hold gauge pressures.
    units : dict
        Units of columns not in canonical units, by canonical column name
        (``{"p_in_kPa": "bar"}``), by stem (``{"p_in": "bar"}``) or by kind
        (``{"pressure": "psi", "flow": "L/min"}``; a volume flow means normal litres).
        A file column named with another unit (``p_in_bar``, ``mdot_g_s``) is read in it.
    columns : dict
        Column mapping ``{"name in file": "canonical name"}``.
    flow_bias : None, "min" or float
        Flow-sensor bias removal: ``"min"`` subtracts the smallest reading (the
        paper's method), a number subtracts that many mg/s, None leaves the flow.
    on_invalid : "raise" or "exclude"
        What to do with invalid rows (NaN or inf, negative or implausible values,
        p_in ≤ p_out, duplicated rows or time stamps): raise a DataError naming them,
        or drop and report them.
    valve : optional
        Keep only rows whose ``valve`` column equals this id.
    check_gauge : bool
        Refuse absolute pressures below 30 kPa (they look like gauge readings).
    max_rows : int or None
        A file with more data rows is thinned to every k-th row (k a power of two) with
        a notice; memory stays bounded (None: no cap).
    """
    if on_invalid not in ("raise", "exclude"):
        raise ParameterError(f"on_invalid must be 'raise' or 'exclude', got {on_invalid!r}")
    units, notes = dict(units or {}), []
    if isinstance(path_or_df, pd.DataFrame):
        source, lines = "<DataFrame>", False
        rename, gauge_cols = _resolve_columns(list(path_or_df.columns), source, columns, units,
                                              notes)
        raw = path_or_df.rename(columns=rename)
        if "row" not in raw:  # a frame loaded before keeps its source row numbers
            raw.insert(0, "row", np.arange(1, len(raw) + 1))
    else:
        source, lines = str(path_or_df), True
        raw, gauge_cols = _read_file(path_or_df, columns, units, notes, max_rows)
    keep = list(REQUIRED) + [c for c in OPTIONAL if c in raw.columns]
    frame = raw[keep + [c for c in raw.columns if c not in keep]].copy()
    frame = _select_valve(frame, source, valve)
    _numeric(frame, source)
    _convert_units(frame, source, units, gauge, gauge_cols, ambient_kpa)
    if check_gauge and not gauge:
        _check_not_gauge(frame, source)
    frame, excluded = _exclude(frame, source, lines, on_invalid)
    if len(frame) < MIN_ROWS:
        raise DataError(f"{len(frame)} valid row(s); a fit needs at least {MIN_ROWS} "
                        f"(several sweeps of held points)",
                        where=source,
                        hint="see the excluded rows" if len(excluded) else "measure more points")
    frame = _time_order(frame, source, notes)
    bias = _remove_bias(frame, flow_bias, notes)
    frame = frame.reset_index(drop=True)
    return Measurements(frame=frame, excluded=excluded, source=source, bias_mg_s=bias,
                        ambient_kpa=ambient_kpa, notes=notes)


def _select_valve(frame, source, valve):
    if valve is not None:
        if "valve" not in frame:
            raise DataError(f"valve={valve!r} given but the data has no 'valve' column",
                            where=source)
        chosen = frame["valve"].astype(str) == str(valve)
        if not chosen.any():
            raise DataError(f"no rows for valve {valve!r}",
                            where=source, hint="valves in the file: "
                            + ", ".join(sorted(frame["valve"].astype(str).unique())))
        return frame[chosen]
    if "valve" in frame and frame["valve"].nunique(dropna=True) > 1:
        ids = sorted(frame["valve"].astype(str).unique())
        raise DataError(f"the file holds {len(ids)} valves ({', '.join(ids[:8])})",
                        hint="choose one with valve=ID (CLI --valve ID)", where=source)
    return frame


def _check_not_gauge(frame, source) -> None:
    """Gauge readings passed as absolute: many values below GAUGE_SUSPECT_KPA."""
    for column in PRESSURES:
        values = frame[column].to_numpy()
        low = values < GAUGE_SUSPECT_KPA
        if np.count_nonzero(low) > max(2, 0.01 * len(values)):
            raise DataError(
                f"{column} has {np.count_nonzero(low)} values below "
                f"{GAUGE_SUSPECT_KPA:g} kPa absolute (lowest {np.nanmin(values):.3g} kPa): "
                f"these look like gauge pressures passed as absolute",
                where=source, hint="pass gauge=True with ambient_kpa (CLI --gauge --ambient 96); "
                                   "the model needs absolute pressures")


def _remove_bias(frame, flow_bias, notes) -> float:
    if flow_bias is None:
        return 0.0
    if isinstance(flow_bias, str):
        if flow_bias != "min":
            raise ParameterError(f"flow_bias must be None, 'min' or a number, got {flow_bias!r}")
        bias = float(frame["mdot_mg_s"].min())
        notes.append(f"flow-sensor bias removed: {bias:.4g} mg/s (smallest reading, as the paper)")
    else:
        bias = float(flow_bias)
        notes.append(f"flow-sensor bias removed: {bias:.4g} mg/s (given)")
    frame["mdot_mg_s"] = frame["mdot_mg_s"] - bias
    return bias


def as_frame(data, **load_options) -> tuple[pd.DataFrame, Measurements | None]:
    """Canonical DataFrame from a Measurements, DataFrame or path (loaded and checked)."""
    if isinstance(data, Measurements):
        return data.frame, data
    measurements = load_measurements(data, **load_options)
    return measurements.frame, measurements
