"""Inspection campaign files: naming, columns, units and reading.

One file per campaign, ``YYYY-MM-DD.csv`` or ``YYYY-MM-DD.parquet`` (the campaign date), with the
column ``chainage_m`` and the six per-rail channels of :data:`ttbpipe.channels.INSPECTION_COLUMNS`
in millimetres. The full format is described in ``docs/inspection_format.md``.

Every problem with a file raises :class:`InspectionError`, which names the file, the data row
(1-based, as in the file: row 1 is the first data row below the CSV header, blank lines counted)
and the column.
"""

from __future__ import annotations

import datetime as _dt
import logging
import re
from pathlib import Path

import pandas as pd

from ..channels import INSPECTION_COLUMNS

logger = logging.getLogger(__name__)

#: Chainage column (m, increasing along the direction of travel).
CHAINAGE_COLUMN = "chainage_m"

#: All required columns, in file order.
REQUIRED_COLUMNS: tuple[str, ...] = (CHAINAGE_COLUMN, *INSPECTION_COLUMNS)

#: Accepted file suffixes.
SUFFIXES: tuple[str, ...] = (".csv", ".parquet")

#: Typical sampling interval of an inspection car (m).
TYPICAL_SAMPLING_INTERVAL_M = 0.25

CAMPAIGN_NAME = re.compile(r"^(\d{4}-\d{2}-\d{2})\.(csv|parquet)$")

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


def campaign_date(path: str | Path) -> _dt.date:
    """The campaign date encoded in a file name ``YYYY-MM-DD.csv|parquet``."""
    path = Path(path)
    match = CAMPAIGN_NAME.match(path.name)
    if path.suffix.lower() not in SUFFIXES:
        raise InspectionError(path, None, None,
                              f"unsupported file type {path.suffix!r}: campaign files are "
                              "YYYY-MM-DD.csv or YYYY-MM-DD.parquet")
    if not match:
        raise InspectionError(path, None, None,
                              f"bad file name {path.name!r}: campaign files are named by their "
                              "date, YYYY-MM-DD.csv or YYYY-MM-DD.parquet (e.g. 2023-01-15.csv)")
    try:
        return _dt.date.fromisoformat(match.group(1))
    except ValueError as exc:
        raise InspectionError(path, None, None,
                              f"bad file name {path.name!r}: {match.group(1)} is not a valid "
                              f"date ({exc})") from None


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
    return (f"column {column!r} is in {_UNIT_NAMES.get(unit.lower(), unit)}; ttbpipe expects "
            f"{expected!r} in {_UNIT_NAMES[expected_unit]}: multiply the values by {factor:g} "
            f"and rename the column to {expected!r}")


def read_campaign(path: str | Path, *, check_name: bool = True) -> pd.DataFrame:
    """Read one campaign file (CSV or Parquet, chosen by the suffix) without changing it.

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
    return frame
