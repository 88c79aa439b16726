"""Implausible inspection data is caught: wrong units, feet, dead and stuck sensors.

Every bad input is built from a valid synthetic campaign (:mod:`ttbpipe.inspection.synthetic`,
TB/T 3352, which passes the checks as it is) by the corruption a real file would carry: channels
in centimetres or inches, chainage in feet, a channel of zeros, a constant, a stuck run. Each
error must name the file, the column, the row where one applies, and the probable cause.

References: the band RMS of the standard spectra over 2-200 m, physics.md section 1 ([C]
values): TB/T 3352 1.220 mm vertical, 0.524 mm cross-level; German low 0.34 mm gauge. A per-rail
vertical profile is ``vertical + cross_level / 2`` (ttbpipe.channels), so its RMS is
``hypot(vertical, cross_level / 2)`` for independent channels. The foot is 0.3048 m and the inch
25.4 mm exactly (international yard and pound, 1959).
"""

from __future__ import annotations

import functools
import logging
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import INSPECTION_COLUMNS
from ttbpipe.inspection import InspectionError, check_campaign, clean_campaign
from ttbpipe.inspection.plausibility import PLAUSIBILITY_BAND_M, standard_band_rms_range
from ttbpipe.inspection.synthetic import synthetic_campaign_series
from ttbpipe.inspection.validate import CLEANING_DEFAULTS
from ttbpipe.irregularity.spectra import SPECTRUM_NAMES

FOOT_M, INCH_MM = 0.3048, 25.4
#: FRA classes 1-5 carry long waves beyond the default plausible_limit_mm (60 mm; documented in
#: docs/inspection_format.md): their campaigns are cleaned with this limit instead.
FRA_LIMIT_MM = 1000.0


@functools.lru_cache(maxsize=None)
def _campaign(spectrum: str = "tbt3352", months: int = 0) -> pd.DataFrame:
    dates = ["2023-01-15"] + ([f"{2023 + months // 12}-{months % 12 + 1:02d}-15"] if months else [])
    *_, campaign = synthetic_campaign_series(dates, spectrum=spectrum, length_km=2.0, seed=5)
    return campaign.table


def campaign(spectrum: str = "tbt3352", months: int = 0) -> pd.DataFrame:
    """A valid synthetic campaign (2 km at 0.25 m, with noise, dropouts and spikes): a copy."""
    return _campaign(spectrum, months).copy()


def write(frame: pd.DataFrame, tmp_path, name: str = "2023-01-15.csv"):
    path = tmp_path / name
    frame.to_csv(path, index=False, float_format="%.10g")
    return path


def expect_error(path, *, row, column, words, **options):
    with pytest.raises(InspectionError) as info:
        check_campaign(path, **options)
    err, message = info.value, str(info.value)
    assert err.file == str(path) and str(path) in message
    assert err.row == row, message
    assert err.column == column, message
    assert (f"row {row}" if row is not None else "row n/a") in message
    assert f"column {column}" in message
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"
    return message


def measured_rms(message: str) -> float:
    return float(re.search(r"band RMS over [\d.]+-[\d.]+ m is ([\d.e+-]+) mm", message).group(1))


def test_valid_campaign_passes_and_reports_band_rms(tmp_path):
    """The starting point of every corruption below is accepted as it is."""
    path = write(campaign(), tmp_path)
    _, report = check_campaign(path)
    assert report.band_rms_band_m == list(PLAUSIBILITY_BAND_M)
    ranges = standard_band_rms_range()
    margin = CLEANING_DEFAULTS["band_rms_margin"]
    for column in INSPECTION_COLUMNS:
        low, high = ranges[column].accepted(margin)
        assert low <= report.band_rms_mm[column] <= high, column
    assert "band RMS 2-200 m" in report.summary()


def test_range_comes_from_the_standard_spectra():
    """Best and worst class per column, against the published band RMS (physics.md section 1)."""
    ranges = standard_band_rms_range((2.0, 200.0))
    vertical = ranges["vertical_left_mm"]
    assert (vertical.low_spectrum, vertical.high_spectrum) == ("tbt3352", "fra_class1")
    assert vertical.low_mm == pytest.approx(math.hypot(1.220, 0.524 / 2), rel=1e-3)
    assert ranges["cross_level_mm"].low_mm == pytest.approx(0.524, rel=1e-3)
    gauge = ranges["gauge_mm"]
    assert gauge.low_spectrum == "german_low" and gauge.low_mm == pytest.approx(0.34, rel=0.02)
    right = ranges["vertical_right_mm"]
    assert (right.low_mm, right.high_mm) == (vertical.low_mm, vertical.high_mm)
    low, high = vertical.accepted(3.0)
    assert (low, high) == (vertical.low_mm / 3.0, vertical.high_mm * 3.0)


def test_all_channels_in_centimetres(tmp_path):
    frame = campaign()
    frame[list(INSPECTION_COLUMNS)] /= 10.0
    path = write(frame, tmp_path)
    vertical = standard_band_rms_range()["vertical_left_mm"]
    low, high = vertical.accepted(3.0)
    message = expect_error(path, row=None, column="vertical_left_mm",
                           words=["implausible magnitude", "band RMS over 2-200 m",
                                  f"below the {low:.3g}-{high:.3g} mm expected", "tbt3352",
                                  "fra_class1", "band_rms_margin = 3",
                                  "values look like centimetres or inches",
                                  "convert to mm or declare the unit in inspections.units"])
    assert measured_rms(message) < low


def test_one_channel_in_inches(tmp_path):
    frame = campaign()
    frame["gauge_mm"] /= INCH_MM
    path = write(frame, tmp_path)
    low = standard_band_rms_range()["gauge_mm"].accepted(3.0)[0]
    message = expect_error(path, row=None, column="gauge_mm",
                           words=["band RMS", "german_low", "centimetres or inches"])
    assert measured_rms(message) < low


def test_channels_in_metres_still_named_as_metres(tmp_path):
    frame = campaign()
    frame[list(INSPECTION_COLUMNS)] /= 1000.0
    path = write(frame, tmp_path)
    expect_error(path, row=None, column="vertical_left_mm",
                 words=["implausible magnitude", "in metres", "inspections.units"])


def test_too_large_band_rms(tmp_path):
    """Micrometres, with the absolute limits raised out of the way: the band RMS still fails."""
    frame = campaign()
    frame["alignment_left_mm"] *= 1000.0
    path = write(frame, tmp_path)
    high = standard_band_rms_range()["alignment_left_mm"].accepted(3.0)[1]
    message = expect_error(path, row=None, column="alignment_left_mm",
                           words=["above the", "unit smaller than mm", "inspections.units"],
                           plausible_limit_mm=1e5, spike_threshold_mm=1e4)
    assert measured_rms(message) > high


def test_band_rms_margin_is_configurable(tmp_path):
    frame = campaign()
    frame[list(INSPECTION_COLUMNS)] /= 10.0
    path = write(frame, tmp_path)
    with pytest.raises(InspectionError):
        check_campaign(path, band_rms_margin=3.0)
    _, report = check_campaign(path, band_rms_margin=50.0)
    assert report.settings["band_rms_margin"] == 50.0
    with pytest.raises(ValueError, match="band_rms_margin"):
        check_campaign(path, band_rms_margin=0.5)


@pytest.mark.parametrize("spectrum", SPECTRUM_NAMES)
@pytest.mark.parametrize("months", [0, 24])
def test_every_standard_class_passes(spectrum, months):
    """Synthetic campaigns of the best to the worst class, new and after two years, pass."""
    frame = campaign(spectrum, months)
    limit = FRA_LIMIT_MM if spectrum.startswith("fra_class") else CLEANING_DEFAULTS[
        "plausible_limit_mm"]
    _, report = clean_campaign(frame, "2023-01-15.parquet", plausible_limit_mm=limit)
    assert set(report.band_rms_mm) == set(INSPECTION_COLUMNS)


@pytest.mark.parametrize("spectrum, factor", [
    ("tbt3352", 10.0), ("tbt3352", INCH_MM), ("german_low", 10.0), ("german_low", INCH_MM),
    ("german_high", 10.0), ("german_high", INCH_MM), ("fra_class6", INCH_MM)])
def test_good_track_in_cm_or_inches_fails(spectrum, factor):
    """The same campaigns as above in cm or inches: caught for the best classes.

    (Poor track, FRA classes 1-5, in cm lies within the range of real track: such files must
    declare their unit; docs/inspection_format.md.)
    """
    frame = campaign(spectrum)
    frame[list(INSPECTION_COLUMNS)] /= factor
    with pytest.raises(InspectionError, match="centimetres or inches"):
        clean_campaign(frame, "2023-01-15.parquet", plausible_limit_mm=FRA_LIMIT_MM)


def test_chainage_in_feet(tmp_path):
    frame = campaign()
    frame["chainage_m"] = np.round(frame["chainage_m"] / FOOT_M, 3)  # a feet chainage to 1/1000 ft
    path = write(frame, tmp_path)
    expect_error(path, row=None, column="chainage_m",
                 words=["chainage looks like feet", "0.820", "0.25 m in feet",
                        "multiply by 0.3048", "inspections.units: {chainage: ft}"])


def test_one_foot_sampling_in_metres_is_not_feet(tmp_path):
    """A car sampling every foot, chainage properly in metres (step 0.3048 m): accepted."""
    frame = campaign()
    frame["chainage_m"] = frame["chainage_m"] * (FOOT_M / 0.25)
    _, report = check_campaign(write(frame, tmp_path))
    assert report.sampling_interval_m == pytest.approx(FOOT_M)


def test_chainage_in_km_points_to_the_units_setting(tmp_path):
    frame = campaign()
    frame["chainage_m"] /= 1000.0
    expect_error(write(frame, tmp_path), row=None, column="chainage_m",
                 words=["implausible median sampling step", "inspections.units"])


def test_dead_channel(tmp_path):
    frame = campaign()
    frame["gauge_mm"] = 0.0
    path = write(frame, tmp_path)
    expect_error(path, row=1, column="gauge_mm",
                 words=["dead sensor", f"all {len(frame)} values are exactly 0"])


def test_channel_stuck_at_a_constant(tmp_path):
    frame = campaign()
    frame["cross_level_mm"] = 1.5
    path = write(frame, tmp_path)
    expect_error(path, row=1, column="cross_level_mm",
                 words=["stuck sensor", "exactly 1.5 mm", "zero variance"])


def test_stuck_run(tmp_path):
    frame = campaign()
    # data rows 1001-1200: 200 samples = 50 m at one value found nowhere else (0.001 mm off the
    # 0.01 mm resolution of the file)
    frame.loc[1000:1199, "vertical_right_mm"] = 2.345
    path = write(frame, tmp_path)
    expect_error(path, row=1001, column="vertical_right_mm",
                 words=["stuck sensor", "200 consecutive samples", "rows 1001-1200", "50 m",
                        "exactly 2.345 mm", "max_constant_run_m = 20 m"])
    _, report = check_campaign(path, max_constant_run_m=60.0)  # configurable
    assert report.settings["max_constant_run_m"] == 60.0


def test_run_of_zeros_is_a_dead_sensor(tmp_path):
    frame = campaign()
    frame.loc[3000:3099, "alignment_left_mm"] = 0.0  # rows 3001-3100: 25 m of zeros
    path = write(frame, tmp_path)
    expect_error(path, row=3001, column="alignment_left_mm",
                 words=["dead sensor", "100 consecutive samples", "exactly 0 mm",
                        "missing values written as 0"])


def test_constant_run_at_the_limit_passes(tmp_path):
    """80 samples = 20 m is not longer than max_constant_run_m = 20 m; 81 samples are."""
    frame = campaign()
    frame.loc[1000:1079, "gauge_mm"] = 0.123
    _, report = check_campaign(write(frame, tmp_path))
    assert report.rows_out == len(frame)
    frame.loc[1080, "gauge_mm"] = 0.123
    expect_error(write(frame, tmp_path, "2023-01-16.csv"), row=1001, column="gauge_mm",
                 words=["81 consecutive samples", "20.25 m"])


def test_short_records_use_the_band_they_resolve(caplog):
    """The band ends at half the record; records under 20 m are not checked (logged)."""
    frame = campaign().iloc[:1201]  # 300 m
    _, report = clean_campaign(frame, "x/2023-01-15.csv")
    assert report.band_rms_band_m == [2.0, 150.0]
    short = campaign().iloc[:61]  # 15 m
    with caplog.at_level(logging.WARNING, logger="ttbpipe.inspection.plausibility"):
        _, report = clean_campaign(short, "x/2023-01-15.csv")
    assert report.band_rms_band_m is None and report.band_rms_mm == {}
    assert "too short for the band RMS plausibility check" in caplog.text


def test_documented_range_table_matches_the_spectra():
    """The table in docs/inspection_format.md is the computed range, rounded."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "inspection_format.md").read_text()
    ranges = standard_band_rms_range()
    rows = [line for line in doc.splitlines()
            if re.match(r"\s*\| `\w+_mm`.* mm \(\w+\) \|", line)]
    assert len(rows) == 4
    for row in rows:
        column = re.search(r"`(\w+_mm)`", row).group(1)
        expected = ranges[column]
        (best, _), (worst, _) = re.findall(r"\| ([\d.]+) mm \((\w+)\)", row)
        best, worst = float(best), float(worst)
        assert f"({expected.low_spectrum})" in row and f"({expected.high_spectrum})" in row
        # three significant digits
        assert best == pytest.approx(expected.low_mm, rel=5e-3), row
        assert worst == pytest.approx(expected.high_mm, rel=5e-3), row
        low, high = (float(v) for v in re.search(r"\| ([\d.]+)-([\d.]+) mm \|\s*$", row).groups())
        accepted = expected.accepted(3.0)
        assert low == pytest.approx(accepted[0], rel=5e-3), row
        assert high == pytest.approx(accepted[1], rel=5e-3), row
