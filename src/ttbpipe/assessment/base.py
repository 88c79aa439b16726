"""What a profile is and what it returns: :class:`Profile`, :class:`Row`, the result columns.

A profile (one module per standard, registered by :mod:`ttbpipe.assessment.registry`) has a name,
the standard it implements, its options with their defaults (the one home of each default) and
``evaluate(run, options) -> list[Row]``. A :class:`Row` is one index at its governing location
(largest utilisation over the wheels, wheelsets, cars or spans), with the clause it implements,
the processed value, the raw counterpart (the registry index of the run's summary, so nothing is
lost), the limit and where it comes from, and the processing parameters.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Callable, Mapping

import numpy as np
import pandas as pd

NAN = float("nan")

#: Result columns, in order. Values, raw values and limits are in ``unit``; the
#: ``filter_*_hz``, ``window_m`` and ``step_m`` columns carry their own units.
COLUMNS = ("standard", "profile", "clause", "index", "unit", "where", "location",
           "processed_value", "raw_index", "raw_value", "limit", "utilisation", "category",
           "limit_source", "filter", "filter_low_hz", "filter_high_hz", "filter_order",
           "window_m", "step_m", "statistic", "notes")

#: Row categories: a safety or serviceability limit, a quality grade boundary, or a value
#: reported without a limit.
CATEGORIES = ("limit", "grade", "info")


@dataclass
class Row:
    """One assessed index (see the module docstring); NaN where a field does not apply."""

    clause: str
    index: str
    unit: str
    where: str                 # wheel | wheelset | car | span | section | structure
    location: str
    processed_value: float
    limit: float
    limit_source: str
    category: str = "limit"
    raw_index: str = ""        # registry name of the raw counterpart ("" when none)
    raw_value: float = NAN
    filter: str = ""
    filter_low_hz: float = NAN
    filter_high_hz: float = NAN
    filter_order: float = NAN
    window_m: float = NAN
    step_m: float = NAN
    statistic: str = ""
    notes: str = ""

    def __post_init__(self):
        if self.category not in CATEGORIES:
            raise ValueError(f"row {self.index}: category {self.category!r} not in {CATEGORIES}")

    @property
    def utilisation(self) -> float:
        """processed / limit (NaN without a limit)."""
        if not np.isfinite(self.limit) or self.limit == 0:
            return NAN
        return float(self.processed_value) / float(self.limit)

    def with_filter(self, filt) -> "Row":
        """This row with the description and edges of a :class:`~.processing.Butterworth`."""
        self.filter = filt.describe()
        self.filter_low_hz = filt.low_hz
        self.filter_high_hz = filt.high_hz
        self.filter_order = float(filt.order)
        return self


@dataclass(frozen=True)
class Profile:
    """A standard's evaluation: ``evaluate(run, options)`` with ``options`` the defaults updated
    by the caller's (unknown keys are an error)."""

    name: str
    standard: str
    title: str
    defaults: Mapping[str, Any]
    evaluate: Callable[..., list[Row]]

    def resolve_options(self, options: Mapping[str, Any] | None) -> dict[str, Any]:
        given = dict(options or {})
        unknown = sorted(set(given) - set(self.defaults))
        if unknown:
            raise ValueError(f"profile {self.name!r}: unknown option(s) {unknown}; known: "
                             f"{sorted(self.defaults)}")
        return {**self.defaults, **given}


def governing(values: np.ndarray, limits: np.ndarray | float,
              labels: list[str]) -> tuple[int, float, float]:
    """(index, value, limit) of the largest utilisation value / limit over locations; with no
    finite positive limit, of the largest value."""
    v = np.asarray(values, dtype=float)
    lim = np.broadcast_to(np.asarray(limits, dtype=float), v.shape)
    if len(labels) != v.size:
        raise ValueError(f"{v.size} values for {len(labels)} locations")
    ok = np.isfinite(lim) & (lim > 0)
    score = np.where(ok, v / np.where(ok, lim, 1.0), v) if ok.any() else v
    i = int(np.nanargmax(score))
    return i, float(v[i]), float(lim[i])


#: Result columns that hold numbers (floats, NaN where they do not apply).
FLOAT_COLUMNS = ("processed_value", "raw_value", "limit", "utilisation", "filter_low_hz",
                 "filter_high_hz", "filter_order", "window_m", "step_m")


def speed_band_value(bands: tuple[tuple[float, float], ...], speed_kmh: float) -> float:
    """The value of the speed band ``speed_kmh`` falls in: ``bands`` are ``(upper speed km/h,
    value)`` in increasing speed, the last with an infinite upper speed (a standard's table)."""
    return next(value for upper, value in bands if speed_kmh <= upper + 1e-9)


def speed_bands_text(bands: tuple[tuple[float, float], ...], scale: float, unit: str) -> str:
    """A band table in words, as a limit source: ``4.5 / 3 / 1.5 mm for V <= 120 / 120-200 /
    > 200 km/h`` (values times ``scale`` in ``unit``)."""
    uppers = [upper for upper, _ in bands[:-1]]
    ranges = [f"<= {uppers[0]:g}", *(f"{a:g}-{b:g}" for a, b in zip(uppers, uppers[1:])),
              f"> {uppers[-1]:g}"]
    return (" / ".join(f"{value * scale:g}" for _, value in bands) + f" {unit} for V "
            + " / ".join(ranges) + " km/h")


def rows_to_records(profile: Profile, rows: list[Row]) -> list[dict[str, Any]]:
    """The result records of one profile (keys :data:`COLUMNS`, numbers as floats): the rows
    of :func:`rows_to_frame` without the DataFrame, for code that reads a few fields of every
    row (a study assesses every sample; building the frame cost more than reading it)."""
    records = []
    for row in rows:
        rec = asdict(row)
        rec.update(standard=profile.standard, profile=profile.name, utilisation=row.utilisation)
        for c in FLOAT_COLUMNS:
            rec[c] = float(rec[c])
        records.append({c: rec[c] for c in COLUMNS})
    return records


def records_to_frame(records: list[dict[str, Any]]) -> pd.DataFrame:
    """The result table (columns :data:`COLUMNS`) of :func:`rows_to_records` records."""
    df = pd.DataFrame.from_records(records, columns=list(COLUMNS))
    for c in FLOAT_COLUMNS:
        df[c] = df[c].astype(float)
    return df


def rows_to_frame(profile: Profile, rows: list[Row]) -> pd.DataFrame:
    """The result table of one profile (columns :data:`COLUMNS`)."""
    return records_to_frame(rows_to_records(profile, rows))
