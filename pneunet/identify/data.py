"""Read and check static valve measurements (the CSV layout of docs/identify.md).

:func:`load_measurements` accepts the canonical CSV (or a DataFrame), maps other
column names, converts other units (bar, psi, L/min normal ...) and gauge
pressures, optionally removes the flow-sensor bias as the paper did (subtract the
smallest reading), and checks the data.  Whole-file problems (missing columns,
gauge values passed as absolute, non-numeric cells) always raise a
:class:`~pneunet.errors.DataError`; row problems (NaN, negative absolute pressure,
p_in ≤ p_out, duplicate rows) raise by default and, with ``on_invalid="exclude"``,
are dropped and listed in :attr:`Measurements.excluded` — never silently.
"""
from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import DataError, ParameterError

PRESSURES = ("p_in_kPa", "p_out_kPa", "p_ctrl_kPa")
REQUIRED = ("time_s",) + PRESSURES + ("mdot_mg_s",)
OPTIONAL = ("sweep", "valve", "h_seat_mm", "T_K")
#: lowest absolute pressure (kPa) a valve bench plausibly sees; below it the
#: numbers look like gauge readings passed as absolute
GAUGE_SUSPECT_KPA = 30.0


@dataclass
class Measurements:
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


def _read_csv(path: Path):
    """CSV with '#' comment lines; returns (frame, file line number of each data row)."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise DataError(f"no such file: {path}") from None
    except UnicodeDecodeError as exc:
        raise DataError(f"{path} is not UTF-8 text ({exc})",
                        hint="save the file as UTF-8 CSV") from None
    kept, line_numbers = [], []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        kept.append(line)
        line_numbers.append(number)
    if not kept:
        raise DataError(f"{path} holds no header row and no data")
    try:
        frame = pd.read_csv(io.StringIO("\n".join(kept)), skipinitialspace=True)
    except pd.errors.ParserError as exc:
        raise DataError(f"{path}: cannot parse as CSV: {exc}",
                        hint="comma-separated, '#' comments, one header row") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    return frame, np.asarray(line_numbers[1:], dtype=int)


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


def load_measurements(path_or_df, *, ambient_kpa=None, gauge=False, units=None, columns=None,
                      flow_bias=None, on_invalid="raise", valve=None,
                      check_gauge=True) -> Measurements:
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
    columns : dict
        Column mapping ``{"name in file": "canonical name"}``.
    flow_bias : None, "min" or float
        Flow-sensor bias removal: ``"min"`` subtracts the smallest reading (the
        paper's method), a number subtracts that many mg/s, None leaves the flow.
    on_invalid : "raise" or "exclude"
        What to do with invalid rows (NaN, negative absolute pressure, p_in ≤ p_out,
        duplicated rows): raise a DataError naming them, or drop and report them.
    valve : optional
        Keep only rows whose ``valve`` column equals this id.
    check_gauge : bool
        Refuse absolute pressures below 30 kPa (they look like gauge readings).
    """
    if on_invalid not in ("raise", "exclude"):
        raise ParameterError(f"on_invalid must be 'raise' or 'exclude', got {on_invalid!r}")
    if isinstance(path_or_df, pd.DataFrame):
        raw, source = path_or_df.copy(), "<DataFrame>"
        lines = None
    else:
        path = Path(path_or_df)
        raw, lines = _read_csv(path)
        source = str(path)
    if columns:
        unknown = [k for k in columns if k not in raw.columns]
        if unknown:
            raise DataError(f"{source}: column mapping names columns not in the data: "
                            f"{unknown}", hint=f"columns found: {list(raw.columns)}")
        raw = raw.rename(columns=dict(columns))
    missing = [c for c in REQUIRED if c not in raw.columns]
    if missing:
        raise DataError(
            f"{source}: missing column(s) {', '.join(missing)}",
            hint=f"found columns {list(raw.columns)}; rename them or pass a column mapping "
                 f"(columns={{'Pin': 'p_in_kPa'}}, CLI --map Pin=p_in_kPa)")
    keep = list(REQUIRED) + [c for c in OPTIONAL if c in raw.columns]
    extra = [c for c in raw.columns if c not in keep]
    frame = raw[keep + extra].copy()
    if "row" not in frame:  # a frame loaded before keeps its source row numbers
        frame.insert(0, "row", np.arange(1, len(frame) + 1))
    if lines is not None and "line" not in frame:
        frame.insert(1, "line", lines[:len(frame)])
    if valve is not None:
        if "valve" not in frame:
            raise DataError(f"{source}: valve={valve!r} given but the data has no 'valve' column")
        chosen = frame["valve"].astype(str) == str(valve)
        if not chosen.any():
            raise DataError(f"{source}: no rows for valve {valve!r}",
                            hint=f"valves in the file: {sorted(frame['valve'].astype(str).unique())}")
        frame = frame[chosen]
    elif "valve" in frame and frame["valve"].nunique(dropna=True) > 1:
        ids = sorted(frame["valve"].astype(str).unique())
        raise DataError(f"{source}: the file holds {len(ids)} valves ({', '.join(ids[:8])})",
                        hint="choose one with valve=ID (CLI --valve ID)")
    # numbers
    for column in REQUIRED + tuple(c for c in ("sweep", "h_seat_mm", "T_K") if c in frame):
        values = pd.to_numeric(frame[column], errors="coerce")
        bad = values.isna() & frame[column].notna()
        if bad.any():
            rows = frame.loc[bad, "row"].to_numpy()
            raise DataError(f"{source}: column {column} holds text that is not a number in "
                            f"row(s) {_rows_text(rows)} (e.g. {frame.loc[bad, column].iloc[0]!r})",
                            hint="use '.' as decimal point and only numbers in data columns")
        frame[column] = values.astype(float)
    # units
    units = dict(units or {})
    if gauge and ambient_kpa is None:
        raise DataError("gauge pressures need the ambient (barometric) pressure",
                        hint="pass ambient_kpa (CLI --ambient), e.g. 96 kPa at 480 m as in "
                             "the paper, 101.325 kPa at sea level")
    from ..units import to_internal

    for column in PRESSURES:
        unit = _unit_for(column, units)
        try:
            frame[column] = to_internal(frame[column].to_numpy(), unit or "kPa", "pressure",
                                        gauge=gauge, ambient_kpa=ambient_kpa or 0.0,
                                        name=column)
        except ParameterError as exc:
            raise DataError(f"{source}: {exc.message}", hint=exc.hint) from None
    unit = _unit_for("mdot_mg_s", units)
    if unit:
        try:
            frame["mdot_mg_s"] = to_internal(frame["mdot_mg_s"].to_numpy(), unit, "flow",
                                             name="mdot_mg_s")
        except ParameterError as exc:
            raise DataError(f"{source}: {exc.message}", hint=exc.hint) from None
    # whole-file check: gauge readings passed as absolute
    if check_gauge and not gauge:
        for column in PRESSURES:
            values = frame[column].to_numpy()
            low = values < GAUGE_SUSPECT_KPA
            if np.count_nonzero(low) > max(2, 0.01 * len(values)):
                raise DataError(
                    f"{source}: {column} has {np.count_nonzero(low)} values below "
                    f"{GAUGE_SUSPECT_KPA:g} kPa absolute (lowest {np.nanmin(values):.3g} kPa): "
                    f"these look like gauge pressures passed as absolute",
                    hint="pass gauge=True with ambient_kpa (CLI --gauge --ambient 96); the model "
                         "needs absolute pressures")
    # row checks, in order; each reason lists its rows
    problems = []
    nan = frame[list(REQUIRED)].isna()
    for column in REQUIRED:
        problems.append((nan[column].to_numpy(), f"NaN in {column}"))
    invalid = nan.any(axis=1).to_numpy().copy()
    for column in PRESSURES:
        negative = (frame[column] <= 0).to_numpy() & ~invalid
        problems.append((negative, f"negative absolute pressure in {column}"))
        invalid |= negative
    reverse = (frame["p_in_kPa"] <= frame["p_out_kPa"]).to_numpy() & ~invalid
    problems.append((reverse, "p_in <= p_out (no forward pressure difference)"))
    invalid |= reverse
    duplicated = frame.duplicated(subset=[c for c in frame.columns if c not in ("row", "line")],
                                  keep="first").to_numpy() & ~invalid
    problems.append((duplicated, "duplicate of an earlier row"))
    excluded_parts = []
    for mask, reason in problems:
        if not mask.any():
            continue
        rows = frame.loc[mask, "row"].to_numpy()
        where = _rows_text(rows)
        if lines is not None:
            where += " (file lines " + _rows_text(frame.loc[mask, "line"].to_numpy()) + ")"
        if on_invalid == "raise":
            hint = {"p_in ": "the input port must be the higher-pressure port; swap the columns "
                            "for backward flow, or exclude these rows",
                    "dupli": "remove the repeated rows",
                    "NaN i": "fill the gaps",
                    "negat": "check the sensor or the units; gauge data needs --gauge"}[reason[:5]]
            raise DataError(f"{source}: {mask.sum()} row(s) with {reason}: data row(s) {where}",
                            hint=hint + "; or pass on_invalid='exclude' (CLI --exclude-invalid) "
                                        "to drop them with a report")
        part = frame.loc[mask].copy()
        part["reason"] = reason
        excluded_parts.append(part)
        frame = frame.loc[~mask]
        # keep masks aligned with the shrinking frame
        problems = [(m[~mask], r) for m, r in problems]
    excluded = (pd.concat(excluded_parts, ignore_index=True) if excluded_parts
                else pd.DataFrame(columns=list(frame.columns) + ["reason"]))
    if len(frame) == 0:
        raise DataError(f"{source}: no valid rows left", hint="see the excluded rows")
    notes = []
    bias = 0.0
    if flow_bias is not None:
        if isinstance(flow_bias, str):
            if flow_bias != "min":
                raise ParameterError(f"flow_bias must be None, 'min' or a number, got "
                                     f"{flow_bias!r}")
            bias = float(frame["mdot_mg_s"].min())
            notes.append(f"flow-sensor bias removed: {bias:.4g} mg/s (smallest reading, as the "
                         f"paper)")
        else:
            bias = float(flow_bias)
            notes.append(f"flow-sensor bias removed: {bias:.4g} mg/s (given)")
        frame["mdot_mg_s"] = frame["mdot_mg_s"] - bias
    frame = frame.reset_index(drop=True)
    return Measurements(frame=frame, excluded=excluded, source=source, bias_mg_s=bias,
                        ambient_kpa=ambient_kpa, notes=notes)


def as_frame(data, **load_options) -> tuple[pd.DataFrame, Measurements | None]:
    """Canonical DataFrame from a Measurements, DataFrame or path (loaded and checked)."""
    if isinstance(data, Measurements):
        return data.frame, data
    measurements = load_measurements(data, **load_options)
    return measurements.frame, measurements
