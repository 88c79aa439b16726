"""Inspection campaign files: naming, columns, units and reading.

One file per campaign, ``YYYY-MM-DD.csv`` or ``YYYY-MM-DD.parquet`` (the campaign date), with the
column ``chainage_m`` and the six per-rail channels of :data:`ttbpipe.channels.INSPECTION_COLUMNS`
in millimetres. The full format is described in ``docs/inspection_format.md``.

Files of inspection cars that name their channels or units their own way are read through a
mapping (config ``inspections.columns`` and ``inspections.units``, :func:`apply_mapping`): the
columns are renamed to ttbpipe's names and the values converted to ttbpipe's units, each step
logged and reported (a documented repair, never a silent one).

Every problem with a file raises :class:`InspectionError`, which names the file, the data row
(1-based, as in the file: row 1 is the first data row below the CSV header, blank lines counted)
and the column.
"""

from __future__ import annotations

import datetime as _dt
import logging
import re
from pathlib import Path, PurePath
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..channels import INSPECTION_COLUMNS
from ..dates import DATE_PATTERN  # the date of campaign file names; also importable from here

logger = logging.getLogger(__name__)

#: Chainage column (m, increasing along the direction of travel).
CHAINAGE_COLUMN = "chainage_m"

#: All required columns, in file order.
REQUIRED_COLUMNS: tuple[str, ...] = (CHAINAGE_COLUMN, *INSPECTION_COLUMNS)

#: Accepted file suffixes.
SUFFIXES: tuple[str, ...] = (".csv", ".parquet")

#: Typical sampling interval of an inspection car (m).
TYPICAL_SAMPLING_INTERVAL_M = 0.25

#: A valid campaign file name (the date still has to be a real calendar date).
CAMPAIGN_NAME = re.compile(rf"^({DATE_PATTERN})\.(csv|parquet)$")

# Dates written another way in a file name, for the rename hint: YYYY_MM_DD / YYYY.MM.DD and the
# compact YYYYMMDD, anywhere in the name.
_DATE_OTHER_SEPARATOR = re.compile(r"(?<!\d)(\d{4})([-_.])(\d{2})\2(\d{2})(?!\d)")
_DATE_COMPACT = re.compile(r"(?<!\d)(\d{4})(\d{2})(\d{2})(?!\d)")

#: Units a column may be declared in (config ``inspections.units``) and the factor that converts a
#: value in that unit to ttbpipe's unit: metres for the chainage, millimetres for the channels.
#: The foot (0.3048 m) and the inch (25.4 mm) are exact by definition (international yard and
#: pound agreement, 1959).
CHAINAGE_UNITS_TO_M: dict[str, float] = {"m": 1.0, "km": 1000.0, "ft": 0.3048}
CHANNEL_UNITS_TO_MM: dict[str, float] = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4,
                                         "um": 1e-3}

# Unit suffixes people use instead of the expected ones, with the factor that converts a value in
# that unit to the expected unit (mm for the channels, m for the chainage).
_LENGTH_UNITS_IN_M: dict[str, float] = {
    "km": 1e3, "m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6,
    "microns": 1e-6, "in": 0.0254, "inch": 0.0254, "inches": 0.0254, "ft": 0.3048,
}
_UNIT_NAMES = {"km": "kilometres", "m": "metres", "cm": "centimetres", "mm": "millimetres",
               "um": "micrometres", "µm": "micrometres", "micron": "micrometres",
               "microns": "micrometres", "in": "inches", "inch": "inches", "inches": "inches",
               "ft": "feet"}


# Other spellings of the units of CHAINAGE_UNITS_TO_M / CHANNEL_UNITS_TO_MM.
_UNIT_SPELLINGS = {"µm": "um", "micron": "um", "microns": "um", "inch": "in", "inches": "in"}


class InspectionError(ValueError):
    """A problem with an inspection file, naming the file, the data row and the column.

    ``row`` is the 1-based data row as in the file (row 1 is the first data row below the header;
    for a CSV file the line number is ``row + 1``) or ``None`` when the problem is not tied to one
    row; ``column`` is the column name or ``None``. The message always names all three.
    """

    def __init__(self, file: str | Path | None, row: int | None, column: str | None,
                 reason: str) -> None:
        self.file = str(file) if file is not None else None
        self.row = int(row) if row is not None else None
        self.column = column
        self.reason = reason
        row_text = "n/a" if row is None else str(row)
        if row is not None and self.file is not None and self.file.lower().endswith(".csv"):
            row_text += f" (line {row + 1})"
        super().__init__(
            f"{self.file or '<no file>'}: row {row_text}, column {column or 'n/a'}: {reason}")

    def __reduce__(self):  # picklable across processes (Snakemake, dask)
        return (type(self), (self.file, self.row, self.column, self.reason))


def diagnose_campaign_name(name: str) -> tuple[str, str | None] | None:
    """Why ``name`` is not a usable campaign file name, and the name it should have.

    Returns ``None`` for a valid name (``YYYY-MM-DD.csv|parquet`` with a real calendar date), else
    ``(cause, suggestion)``: ``cause`` lists every problem found (an unsupported or upper-case
    suffix, text around the date, a date with other separators or in the compact ``YYYYMMDD``
    form, no date, an impossible date) and ``suggestion`` is the corrected name, or ``None`` when
    it cannot be guessed (no date, or an impossible one). Used for the error of
    :func:`campaign_date` and for the folder scan of :mod:`ttbpipe.inspection.discover`, so that
    both say the same.
    """
    path = PurePath(name)
    match = CAMPAIGN_NAME.match(path.name)
    if match:
        try:
            _dt.date.fromisoformat(match.group(1))
            return None
        except ValueError as exc:
            return f"{match.group(1)} is not a valid date ({exc})", None
    causes: list[str] = []
    suffix, stem = path.suffix, path.stem
    if suffix.lower() in SUFFIXES:
        target_suffix = suffix.lower()
        if suffix != target_suffix:
            causes.append(f"upper-case suffix {suffix!r}")
    else:
        target_suffix = ".csv"
        causes.append(f"unsupported file type {suffix or '(none)'!r}: save it as CSV or Parquet")
    date_parts: tuple[str, str, str] | None = None
    if re.fullmatch(DATE_PATTERN, stem):
        date_parts = (stem[:4], stem[5:7], stem[8:10])
    else:
        found = _DATE_OTHER_SEPARATOR.search(stem)
        if found:
            date_parts = (found.group(1), found.group(3), found.group(4))
            if found.group(2) != "-":
                causes.append(f"date written with {found.group(2)!r} instead of '-'")
        else:
            found = _DATE_COMPACT.search(stem)
            if found:
                date_parts = (found.group(1), found.group(2), found.group(3))
                causes.append("compact date (YYYYMMDD)")
        if found:
            before, after = stem[:found.start()], stem[found.end():]
            if before or after:
                around = " and ".join(f"{text!r} {where}" for text, where in
                                      ((before, "before"), (after, "after")) if text)
                causes.append(f"text around the date ({around} it)")
    if date_parts is None:
        causes.append("no date in the name")
        return "; ".join(causes), None
    iso = "-".join(date_parts)
    try:
        _dt.date.fromisoformat(iso)
    except ValueError as exc:
        causes.append(f"{iso} is not a valid date ({exc})")
        return "; ".join(causes), None
    return "; ".join(causes), f"{iso}{target_suffix}"


def campaign_date(path: str | Path) -> _dt.date:
    """The campaign date encoded in a file name ``YYYY-MM-DD.csv|parquet``."""
    path = Path(path)
    problem = diagnose_campaign_name(path.name)
    if problem is None:
        return _dt.date.fromisoformat(CAMPAIGN_NAME.match(path.name).group(1))
    cause, suggestion = problem
    hint = f"; rename it to {suggestion}" if suggestion else ""
    if path.suffix.lower() not in SUFFIXES:
        raise InspectionError(path, None, None,
                              f"unsupported file type {path.suffix!r}: campaign files are "
                              f"YYYY-MM-DD.csv or YYYY-MM-DD.parquet{hint}")
    raise InspectionError(path, None, None,
                          f"bad file name {path.name!r}: {cause} (campaign files are named by "
                          f"their date, YYYY-MM-DD.csv or YYYY-MM-DD.parquet, e.g. "
                          f"2023-01-15.csv){hint}")


def unit_mismatch(column: str) -> tuple[str, str, float] | None:
    """For a column like ``vertical_left_m``: (expected name, unit found, factor to expected).

    Returns None when ``column`` is not a required column written with another length unit.
    """
    for expected in REQUIRED_COLUMNS:
        base, _, expected_unit = expected.rpartition("_")
        if not column.lower().startswith(base + "_"):
            continue
        unit = column[len(base) + 1:]
        unit_key = unit.lower()
        if unit_key == expected_unit or unit_key not in _LENGTH_UNITS_IN_M:
            continue
        factor = _LENGTH_UNITS_IN_M[unit_key] / _LENGTH_UNITS_IN_M[expected_unit]
        return expected, unit, factor
    return None


def unit_error_message(column: str) -> str | None:
    """A clear message for a required column given in the wrong unit, else None."""
    mismatch = unit_mismatch(column)
    if mismatch is None:
        return None
    expected, unit, factor = mismatch
    expected_unit = expected.rpartition("_")[2]
    message = (f"column {column!r} is in {_UNIT_NAMES.get(unit.lower(), unit)}; ttbpipe expects "
               f"{expected!r} in {_UNIT_NAMES[expected_unit]}: multiply the values by "
               f"{factor:g} and rename the column to {expected!r}")
    declared = _UNIT_SPELLINGS.get(unit.lower(), unit.lower())
    accepted = CHAINAGE_UNITS_TO_M if expected == CHAINAGE_COLUMN else CHANNEL_UNITS_TO_MM
    if declared in accepted:
        unit_key = "chainage" if expected == CHAINAGE_COLUMN else expected
        message += (f", or map it in the configuration (inspections.columns: "
                    f"{{{column}: {expected}}}, inspections.units: {{{unit_key}: {declared}}})")
    return message


_NA_TEXT = re.compile(r"^\s*(|nan|na|n/a|null|none|-nan|<na>)\s*$", re.IGNORECASE)


def numeric_column(series: pd.Series, source: str | Path, column: str) -> np.ndarray:
    """Column as float64; text that is not a number is an error naming its first row.

    Spelled-out missing values (empty, ``NaN``, ``NA``, ``null``, ...) become NaN; a number with a
    decimal comma gets a hint.
    """
    if pd.api.types.is_bool_dtype(series.dtype):
        raise InspectionError(source, None, column, "boolean column; expected numbers")
    if pd.api.types.is_numeric_dtype(series.dtype):
        return series.to_numpy(dtype=float, na_value=np.nan)
    converted = pd.to_numeric(series, errors="coerce")
    bad = converted.isna().to_numpy() & ~series.isna().to_numpy()
    if bad.any():
        texts = series.astype(str).to_numpy()
        for i in np.flatnonzero(bad):
            if _NA_TEXT.match(texts[i]):
                continue  # a spelled-out missing value: handled as NaN
            hint = ""
            if re.fullmatch(r"\s*[-+]?\d+,\d+\s*", texts[i]):
                hint = " (decimal comma? use a point)"
            raise InspectionError(source, int(i) + 1, column,
                                  f"text {texts[i]!r} in a number column{hint}")
    return converted.to_numpy(dtype=float, na_value=np.nan)


def check_mapping(columns: Mapping[str, str] | None = None,
                  units: Mapping[str, str] | None = None
                  ) -> tuple[dict[str, str], dict[str, str]]:
    """Validate a column and unit mapping; return ``(columns, units per ttbpipe column)``.

    ``columns`` maps a source column name to one of :data:`REQUIRED_COLUMNS`. ``units`` has the
    keys ``chainage`` (one of :data:`CHAINAGE_UNITS_TO_M`), ``channels`` (one of
    :data:`CHANNEL_UNITS_TO_MM`, for all six channels) and any ttbpipe column name (overrides
    ``channels`` for that column). Raises ``ValueError`` naming the configuration key for an
    unknown target, two sources mapped to one target, an unknown key or an unknown unit.
    """
    mapped: dict[str, str] = {}
    for source_name, target in dict(columns or {}).items():
        source_name, target = str(source_name).strip(), str(target).strip()
        if target not in REQUIRED_COLUMNS:
            raise ValueError(f"inspections.columns: {source_name!r} maps to {target!r}, which is "
                             f"not a ttbpipe column; use one of {', '.join(REQUIRED_COLUMNS)}")
        if target in mapped.values():
            other = next(k for k, v in mapped.items() if v == target)
            raise ValueError(f"inspections.columns: {other!r} and {source_name!r} both map to "
                             f"{target!r}; map one column of the file to each ttbpipe column")
        mapped[source_name] = target
    per_column: dict[str, str] = {}
    declared = {str(k).strip(): str(v).strip().lower() for k, v in dict(units or {}).items()}
    for key in declared:
        if key not in ("chainage", "channels", *REQUIRED_COLUMNS):
            raise ValueError(f"inspections.units: unknown key {key!r}; use chainage, channels or "
                             f"a column name ({', '.join(REQUIRED_COLUMNS)})")
    if "chainage" in declared and CHAINAGE_COLUMN in declared:
        raise ValueError(f"inspections.units: give the chainage unit once (chainage or "
                         f"{CHAINAGE_COLUMN}), not both")
    chainage_unit = declared.get(CHAINAGE_COLUMN, declared.get("chainage"))
    if chainage_unit is not None:
        if chainage_unit not in CHAINAGE_UNITS_TO_M:
            raise ValueError(f"inspections.units: chainage unit {chainage_unit!r} is not one of "
                             f"{', '.join(CHAINAGE_UNITS_TO_M)}")
        per_column[CHAINAGE_COLUMN] = chainage_unit
    for column in INSPECTION_COLUMNS:
        unit = declared.get(column, declared.get("channels"))
        if unit is None:
            continue
        if unit not in CHANNEL_UNITS_TO_MM:
            key = column if column in declared else "channels"
            raise ValueError(f"inspections.units: {key} unit {unit!r} is not one of "
                             f"{', '.join(CHANNEL_UNITS_TO_MM)}")
        per_column[column] = unit
    return mapped, per_column


def apply_mapping(frame: pd.DataFrame, source: str | Path, *,
                  columns: Mapping[str, str] | None = None,
                  units: Mapping[str, str] | None = None) -> pd.DataFrame:
    """Rename the file's columns to ttbpipe's names and convert declared units (logged).

    ``columns`` and ``units`` as in :func:`check_mapping`. A mapped source column that is not in
    the file is accepted when the file already has the ttbpipe column (logged: such a file needs
    no mapping); otherwise it is an error naming the file and the column, as is a file that has
    both the source column and its target. Units are converted on the values after renaming
    (text cells are errors naming their row, as in the cleaning). Returns a new frame whose
    ``attrs`` carry ``renamed_columns`` (source -> ttbpipe name) and ``unit_conversions``
    (ttbpipe column -> ``{"unit", "factor"}``) for the cleaning report.
    """
    mapped, per_column = check_mapping(columns, units)
    if frame.attrs.get("mapping_applied"):
        raise ValueError(f"{source}: the column and unit mapping was already applied to this "
                         "table (by read_campaign); pass it once")
    attrs = dict(frame.attrs)
    present = [str(c) for c in frame.columns]
    renames: dict[str, str] = {}
    for source_name, target in mapped.items():
        if source_name == target:
            continue
        if source_name not in present:
            if target in present:
                logger.info("%s: column %r of inspections.columns is not in the file, which has "
                            "%r already: not renamed", source, source_name, target)
                continue
            raise InspectionError(source, None, source_name,
                                  f"column {source_name!r} (mapped to {target!r} by "
                                  f"inspections.columns) is not in the file (found: "
                                  f"{', '.join(present)})")
        if target in present:
            raise InspectionError(source, None, source_name,
                                  f"the file has both {source_name!r} (mapped to {target!r} by "
                                  f"inspections.columns) and {target!r}; drop one of them or "
                                  "the mapping")
        renames[source_name] = target
    out = frame.rename(columns=renames)
    for source_name, target in renames.items():
        logger.info("%s: column %r read as %r (inspections.columns)", source, source_name, target)
    conversions: dict[str, dict[str, Any]] = {}
    for column, unit in per_column.items():
        if column not in out.columns:
            continue  # the schema check names the missing column
        factor = (CHAINAGE_UNITS_TO_M if column == CHAINAGE_COLUMN else CHANNEL_UNITS_TO_MM)[unit]
        if factor == 1.0:
            logger.debug("%s: %s declared in %s: no conversion", source, column, unit)
            continue
        label = next((k for k, v in renames.items() if v == column), column)
        out[column] = numeric_column(out[column], source, label) * factor
        target_unit = column.rpartition("_")[2]
        conversions[column] = {"unit": unit, "factor": factor}
        logger.info("%s: %s converted from %s to %s (x %g, inspections.units)", source, column,
                    _UNIT_NAMES.get(unit, unit), _UNIT_NAMES[target_unit], factor)
    out.attrs = {**attrs, "renamed_columns": renames, "unit_conversions": conversions,
                 "mapping_applied": bool(mapped or per_column)}
    return out


def read_campaign(path: str | Path, *, check_name: bool = True,
                  columns: Mapping[str, str] | None = None,
                  units: Mapping[str, str] | None = None) -> pd.DataFrame:
    """Read one campaign file (CSV or Parquet, chosen by the suffix) without changing it.

    With ``columns`` / ``units`` (config ``inspections.columns`` / ``inspections.units``) the
    file's columns are renamed to ttbpipe's names and the declared units converted to ttbpipe's
    (:func:`apply_mapping`, each step logged; the cleaning report lists them).

    The returned frame has one row per data row of the file, in file order (index ``i`` is data
    row ``i + 1``), all columns as stored (number columns that contain text stay text so that
    :func:`ttbpipe.inspection.validate.clean_campaign` can name the offending cell). Blank lines
    inside a CSV file are kept as empty rows (so that row numbers match the file); blank lines at
    its end are removed and logged. ``frame.attrs`` holds ``source`` and ``campaign_date``.

    Raises :class:`InspectionError` for a missing, empty or unreadable file, an unsupported
    suffix or a file name that is not a date (unless ``check_name=False``).
    """
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise InspectionError(path, None, None,
                              f"unsupported file type {path.suffix!r}: campaign files are "
                              "YYYY-MM-DD.csv or YYYY-MM-DD.parquet")
    date = campaign_date(path) if check_name else None
    if not path.is_file():
        raise InspectionError(path, None, None, "file not found (or not a regular file)")
    if path.stat().st_size == 0:
        raise InspectionError(path, None, None, "empty file (0 bytes): no header, no data")
    try:
        if path.suffix.lower() == ".csv":
            frame = pd.read_csv(path, skip_blank_lines=False, skipinitialspace=True)
        else:
            frame = pd.read_parquet(path)
    except pd.errors.EmptyDataError:
        raise InspectionError(path, None, None, "empty file: no header, no data") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise InspectionError(path, None, None, f"cannot parse the CSV file: {exc}") from None
    except Exception as exc:  # pyarrow and OS errors: corrupt Parquet, permissions, ...
        raise InspectionError(path, None, None,
                              f"cannot read the file ({type(exc).__name__}: {exc})") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    # Trailing blank lines are harmless; interior ones keep their row and are reported later.
    blank = frame.isna().all(axis=1).to_numpy()
    n_trailing = 0
    while n_trailing < len(blank) and blank[len(blank) - 1 - n_trailing]:
        n_trailing += 1
    if n_trailing:
        logger.info("%s: removed %d blank row(s) at the end of the file", path, n_trailing)
        frame = frame.iloc[:len(frame) - n_trailing]
    if len(frame) == 0:
        raise InspectionError(path, None, None,
                              "empty file: a header but no data rows")
    frame = frame.reset_index(drop=True)
    frame.attrs["source"] = str(path)
    frame.attrs["campaign_date"] = date.isoformat() if date else None
    frame.attrs["trailing_blank_rows_removed"] = n_trailing
    if columns or units:
        frame = apply_mapping(frame, path, columns=columns, units=units)
    return frame
