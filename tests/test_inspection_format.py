"""Inspection campaign files: reading and the bad-input suite.

Every bad file must raise :class:`InspectionError` whose message names the file, the data row
(1-based, as in the file) and the column, and says what is wrong. The row numbers asserted here
follow from how each test corrupts the file (documented next to each case), so the tests fail if
the reported row is off by one. Source of the format: docs/inspection_format.md.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import INSPECTION_COLUMNS, SPECTRAL_CHANNELS, inspection_columns_from_spectral
from ttbpipe.inspection import (InspectionError, campaign_date, check_campaign, clean_campaign,
                                read_campaign)
from ttbpipe.irregularity.synthesis import synthesize_profiles


def good_frame(length_m: float = 500.0, seed: int = 3) -> pd.DataFrame:
    """A clean TB/T 3352 campaign (per-rail channels from the four spectral channels)."""
    p = synthesize_profiles("tbt3352", length_m, 0.25, seed=seed)
    columns = inspection_columns_from_spectral(
        *(p[f"{channel}_mm"].to_numpy() for channel in SPECTRAL_CHANNELS))
    return pd.DataFrame({"chainage_m": p["chainage_m"].to_numpy(), **columns})


def write_csv(frame: pd.DataFrame, tmp_path, name: str = "2023-01-15.csv"):
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


def expect_error(path, *, row, column, words):
    """Read and clean ``path``; the error must carry row/column and name them with ``words``."""
    with pytest.raises(InspectionError) as info:
        check_campaign(path)
    err = info.value
    message = str(err)
    assert err.file == str(path)
    assert err.row == row, message
    assert err.column == column, message
    assert str(path) in message
    assert (f"row {row}" if row is not None else "row n/a") in message
    assert (f"column {column}" if column is not None else "column n/a") in message
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"
    return err


def test_good_csv_and_parquet_read_and_clean(tmp_path):
    frame = good_frame()
    frame["speed_kmh"] = 80.0  # extra column: kept on reading, ignored by cleaning, reported
    csv_path = write_csv(frame, tmp_path)
    parquet_path = tmp_path / "2023-02-15.parquet"
    frame.to_parquet(parquet_path)
    for path in (csv_path, parquet_path):
        raw = read_campaign(path)
        assert list(raw.columns) == list(frame.columns)
        assert len(raw) == len(frame) == 2001
        clean, report = clean_campaign(raw, path)
        assert list(clean.columns) == ["chainage_m", *INSPECTION_COLUMNS]
        assert report.ignored_columns == ["speed_kmh"]
        assert report.sampling_interval_m == 0.25 and report.rows_out == 2001
        assert sum(report.total(k) for k in report.repairs) == 0
    assert campaign_date(parquet_path).isoformat() == "2023-02-15"


def test_error_is_value_error_naming_file_row_column():
    err = InspectionError("a/2023-01-15.csv", 7, "gauge_mm", "bad")
    assert isinstance(err, ValueError)
    assert str(err) == "a/2023-01-15.csv: row 7 (line 8), column gauge_mm: bad"
    err = InspectionError("a/2023-01-15.parquet", None, None, "bad")
    assert str(err) == "a/2023-01-15.parquet: row n/a, column n/a: bad"


def test_missing_column(tmp_path):
    path = write_csv(good_frame().drop(columns="gauge_mm"), tmp_path)
    expect_error(path, row=None, column="gauge_mm", words=["missing column 'gauge_mm'"])


def test_column_in_other_unit_names_expected_unit(tmp_path):
    frame = good_frame().rename(columns={"vertical_left_mm": "vertical_left_m"})
    frame["vertical_left_m"] /= 1000.0
    path = write_csv(frame, tmp_path)
    expect_error(path, row=None, column="vertical_left_m",
                 words=["metres", "'vertical_left_mm'", "millimetres",
                        "multiply the values by 1000"])
    frame = good_frame().rename(columns={"gauge_mm": "gauge_in"})
    path = write_csv(frame, tmp_path, "2023-01-16.csv")
    expect_error(path, row=None, column="gauge_in", words=["inches", "'gauge_mm'", "25.4"])


def test_non_monotonic_chainage(tmp_path):
    frame = good_frame()
    # swap data rows 101 and 102 (indices 100, 101): row 102 then steps back
    frame.iloc[[100, 101]] = frame.iloc[[101, 100]].to_numpy()
    path = write_csv(frame, tmp_path)
    expect_error(path, row=102, column="chainage_m", words=["not increasing", "25 m"])


def test_duplicate_chainage(tmp_path):
    frame = good_frame()
    frame.loc[200, "chainage_m"] = frame.loc[199, "chainage_m"]  # data row 201 repeats row 200
    path = write_csv(frame, tmp_path)
    expect_error(path, row=201, column="chainage_m", words=["duplicate chainage", "row 200"])


def test_nan_run_beyond_repair_limit(tmp_path):
    frame = good_frame()
    frame.loc[300:319, "vertical_right_mm"] = np.nan  # rows 301-320: 20 samples = 5 m > 2 m
    path = write_csv(frame, tmp_path)
    expect_error(path, row=301, column="vertical_right_mm",
                 words=["20 consecutive missing values", "5 m", "max_gap_m = 2 m"])


def test_text_in_number_column(tmp_path):
    frame = good_frame().astype({"cross_level_mm": object})
    frame.loc[50, "cross_level_mm"] = "abc"  # data row 51, file line 52
    frame.loc[60, "cross_level_mm"] = "xyz"
    path = write_csv(frame, tmp_path)
    expect_error(path, row=51, column="cross_level_mm",
                 words=["text 'abc' in a number column", "(line 52)"])
    # the same in a Parquet file (no header line: row only)
    parquet_path = tmp_path / "2023-03-01.parquet"
    frame.astype({"cross_level_mm": str}).to_parquet(parquet_path)
    err = expect_error(parquet_path, row=51, column="cross_level_mm", words=["'abc'"])
    assert "line" not in str(err)


def test_decimal_comma_hint(tmp_path):
    frame = good_frame().astype({"gauge_mm": object})
    frame.loc[9, "gauge_mm"] = "0,5"
    path = write_csv(frame, tmp_path)
    expect_error(path, row=10, column="gauge_mm", words=["decimal comma"])


def test_empty_files(tmp_path):
    empty = tmp_path / "2023-01-15.csv"
    empty.write_text("")
    expect_error(empty, row=None, column=None, words=["empty file"])
    header_only = tmp_path / "2023-01-16.csv"
    header_only.write_text("chainage_m," + ",".join(INSPECTION_COLUMNS) + "\n")
    expect_error(header_only, row=None, column=None, words=["empty file", "no data rows"])


def test_values_in_metres(tmp_path):
    frame = good_frame()
    frame["alignment_right_mm"] /= 1000.0  # the column is named mm but holds metres
    path = write_csv(frame, tmp_path)
    expect_error(path, row=None, column="alignment_right_mm",
                 words=["implausible magnitude", "in metres", "expected millimetres"])


def test_values_in_micrometres(tmp_path):
    frame = good_frame()
    frame["vertical_left_mm"] *= 1000.0
    path = write_csv(frame, tmp_path)
    expect_error(path, row=None, column="vertical_left_mm",
                 words=["implausible magnitude", "micrometres", "plausible_limit_mm = 60"])


def test_absolute_gauge(tmp_path):
    frame = good_frame()
    frame["gauge_mm"] += 1435.0
    path = write_csv(frame, tmp_path)
    expect_error(path, row=None, column="gauge_mm", words=["absolute gauge", "1435"])


def test_chainage_in_km(tmp_path):
    frame = good_frame()
    frame["chainage_m"] /= 1000.0
    path = write_csv(frame, tmp_path)
    expect_error(path, row=None, column="chainage_m", words=["implausible median sampling step"])


def test_chainage_jump(tmp_path):
    frame = good_frame()
    frame.loc[500:, "chainage_m"] += 0.1  # from data row 501 on, 0.4 step off the 0.25 m grid
    path = write_csv(frame, tmp_path)
    expect_error(path, row=501, column="chainage_m",
                 words=["jump in chainage", "(row 500)",
                        "is 0.35 m, not a multiple of the 0.25 m median step"])


def test_dropout_longer_than_limit(tmp_path):
    frame = good_frame().drop(index=range(400, 420)).reset_index(drop=True)  # 20 rows = 5 m
    path = write_csv(frame, tmp_path)
    expect_error(path, row=401, column="chainage_m",
                 words=["20 rows missing", "(row 400)", "exceeds max_gap_m = 2 m"])


def test_value_beyond_plausible_limit(tmp_path):
    frame = good_frame()
    frame.loc[700:703, "alignment_left_mm"] += 75.0  # 4 samples: too long for a spike
    path = write_csv(frame, tmp_path)
    expect_error(path, row=701, column="alignment_left_mm",
                 words=["exceeds plausible_limit_mm = 60 mm after the repairs"])


def test_bad_names_suffixes_and_unreadable_files(tmp_path):
    frame = good_frame(100.0)
    for name, words in [("campaign.csv", ["bad file name", "YYYY-MM-DD"]),
                        ("2023-02-30.csv", ["not a valid date"]),
                        ("2023-01-15.txt", ["unsupported file type '.txt'"])]:
        path = tmp_path / name
        frame.to_csv(path, index=False)
        with pytest.raises(InspectionError) as info:
            read_campaign(path)
        for word in words:
            assert word in str(info.value) and str(path) in str(info.value)
    broken = tmp_path / "2023-01-15.parquet"
    broken.write_bytes(b"this is not parquet")
    with pytest.raises(InspectionError, match=r"2023-01-15\.parquet: row n/a, column n/a: "
                                              r"cannot read the file"):
        read_campaign(broken)
    with pytest.raises(InspectionError, match="file not found"):
        read_campaign(tmp_path / "2024-01-01.csv")


def test_blank_lines(tmp_path):
    """Trailing blank lines are removed (logged); an interior one keeps its row number."""
    path = write_csv(good_frame(100.0), tmp_path)
    path.write_text(path.read_text() + "\n\n")
    raw = read_campaign(path)
    assert len(raw) == 401 and raw.attrs["trailing_blank_rows_removed"] == 2
    lines = path.read_text().splitlines()
    lines.insert(11, "")  # a blank line 12 = data row 11
    path.write_text("\n".join(lines) + "\n")
    expect_error(path, row=11, column="chainage_m", words=["missing chainage value"])


def test_error_survives_pickling():
    """Errors cross process boundaries (Snakemake jobs, dask workers) intact."""
    import pickle
    err = pickle.loads(pickle.dumps(InspectionError("f/2023-01-15.csv", 3, "gauge_mm", "bad")))
    assert (err.file, err.row, err.column) == ("f/2023-01-15.csv", 3, "gauge_mm")
    assert str(err) == "f/2023-01-15.csv: row 3 (line 4), column gauge_mm: bad"
