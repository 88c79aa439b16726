"""Campaign calendar arithmetic (ttbpipe.dates).

Exact checks (dates are integers): hand-worked cases of the Gregorian calendar, and numpy's
datetime64 month arithmetic as an independent second method for the year/month rollover.
"""

import datetime as dt
import re

import numpy as np
import pytest

from ttbpipe.dates import DATE_PATTERN, MEAN_DAYS_PER_MONTH, add_months, months_between


@pytest.mark.parametrize("date, months, expected", [
    ("2025-08-31", 6, "2026-02-28"),     # clamped to the end of February
    ("2024-01-31", 1, "2024-02-29"),     # leap year (2024 divisible by 4)
    ("1900-01-31", 1, "1900-02-28"),     # 1900 is no leap year (divisible by 100, not 400)
    ("2000-01-31", 1, "2000-02-29"),     # 2000 is one (divisible by 400)
    ("2023-01-31", 3, "2023-04-30"),     # 30-day month
    ("2023-11-15", 3, "2024-02-15"),     # year rollover
    ("2023-12-15", 1, "2024-01-15"),
    ("2023-01-15", 36, "2026-01-15"),
    ("2023-01-15", 0, "2023-01-15"),
    ("2024-03-31", -1, "2024-02-29"),    # negative: back into a leap February
    ("2024-01-15", -1, "2023-12-15"),    # negative year rollover
    ("2024-01-15", -25, "2021-12-15"),
])
def test_add_months_hand_worked(date, months, expected):
    assert add_months(date, months) == expected
    assert add_months(dt.date.fromisoformat(date), months) == expected


def test_add_months_rounds_to_whole_months():
    """Horizons come as floats (6.0); Python's round: half to even."""
    assert add_months("2025-12-15", 6.0) == "2026-06-15"
    assert add_months("2025-12-15", 5.6) == "2026-06-15"
    assert add_months("2025-12-15", 0.5) == "2025-12-15"
    assert add_months("2025-12-15", 1.5) == "2026-02-15"


@pytest.mark.parametrize("start", ["2023-01-31", "2024-02-29", "1999-12-30", "2025-06-15"])
def test_add_months_agrees_with_numpy_month_arithmetic(start):
    """Year and month from numpy's datetime64[M] arithmetic, the day clamped to the month's
    length measured as the distance to the next month's first day."""
    base = dt.date.fromisoformat(start)
    for months in range(-40, 41):
        month = np.datetime64(start[:7], "M") + months
        length = int((np.datetime64(month + 1, "D") - np.datetime64(month, "D")).astype(int))
        expected = f"{month}-{min(base.day, length):02d}"
        assert add_months(start, months) == expected, months


def test_months_between():
    assert months_between("2023-01-15", "2023-01-15") == 0.0
    assert months_between("2023-01-15", "2024-07-15") == 18.0
    assert months_between("2024-07-15", "2023-01-15") == -18.0
    assert months_between("2023-01-15", "2023-02-14") == pytest.approx(1 - 1 / MEAN_DAYS_PER_MONTH,
                                                                       rel=1e-15)
    assert MEAN_DAYS_PER_MONTH == pytest.approx(30.4375, rel=1e-15)
    # whole months after a day that exists in every month: add_months inverts it exactly
    for months in range(-30, 31):
        assert months_between("2023-05-28", add_months("2023-05-28", months)) == months


def test_date_pattern():
    assert re.fullmatch(DATE_PATTERN, "2023-01-15")
    for text in ("2023-1-15", "20230115", "2023_01_15", "2023-01-15x"):
        assert not re.fullmatch(DATE_PATTERN, text)
