"""Calendar arithmetic of inspection campaigns and forecast horizons.

Campaigns are named by their ISO 8601 date (``YYYY-MM-DD``); forecasts and synthetic series step
in calendar months. The one home of the date pattern and of the month arithmetic used by the
inspection, TIPM and study stages and by the workflow's campaign list (workflow/rules/common.smk).
"""

from __future__ import annotations

import calendar
import datetime as _dt

__all__ = ["DATE_PATTERN", "MEAN_DAYS_PER_MONTH", "add_months", "months_between"]

#: A campaign date as written in file names and wildcards, ``YYYY-MM-DD`` (ISO 8601): the
#: workflow's ``{date}`` wildcard, campaign file names and the dated scenarios of the study and
#: statistics stages. A match still has to be a real calendar date (``date.fromisoformat``).
DATE_PATTERN = r"\d{4}-\d{2}-\d{2}"

#: Mean length of a month in days, 365.25 / 12 (the Julian year of 365.25 days, IAU), for
#: expressing a day difference in months.
MEAN_DAYS_PER_MONTH = 365.25 / 12.0


def add_months(date: str | _dt.date, months: float) -> str:
    """ISO date ``months`` calendar months after ``date`` (before it if negative).

    ``months`` is rounded to whole months (Python's ``round``, half to even); the day of the month
    is kept and clamped to the last day of the target month (2025-08-31 + 6 -> 2026-02-28).
    ``date`` is an ISO date string or a ``datetime.date``.
    """
    base = date if isinstance(date, _dt.date) else _dt.date.fromisoformat(date)
    index = base.month - 1 + int(round(months))
    year, month = base.year + index // 12, index % 12 + 1  # floor division: negative months too
    return _dt.date(year, month, min(base.day, calendar.monthrange(year, month)[1])).isoformat()


def months_between(a: str, b: str) -> float:
    """Months from ISO date ``a`` to ISO date ``b``: the whole calendar months plus the day
    difference in :data:`MEAN_DAYS_PER_MONTH` (negative when ``b`` is before ``a``)."""
    da, db = _dt.date.fromisoformat(a), _dt.date.fromisoformat(b)
    whole_months = (db.year - da.year) * 12 + (db.month - da.month)
    return whole_months + (db.day - da.day) / MEAN_DAYS_PER_MONTH
