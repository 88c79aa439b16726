"""Repairs of :func:`clean_campaign`: counted, logged, and close to the truth.

Accuracy references (independent of the implementation):

* the linear-interpolation error theorem: for a gap of length L between two known samples,
  ``|f(x) - p(x)| <= L**2 / 8 * max|f''|`` on the gap (any numerical-analysis text, e.g.
  Burden & Faires, Numerical Analysis, Thm 3.3); ``max|f''|`` is taken from the true profile
  by second differences, with a 1.2 margin for the O(h^2) error of that estimate;
* ``numpy.interp`` on the known samples (a second implementation of the same repair);
* ``numpy.polyfit`` for the removed linear trend.
"""

from __future__ import annotations

import json
import logging

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import INSPECTION_COLUMNS, SPECTRAL_CHANNELS, inspection_columns_from_spectral
from ttbpipe.cli import main
from ttbpipe.inspection import clean_campaign
from ttbpipe.io import read_provenance, read_table
from ttbpipe.irregularity.synthesis import synthesize_profiles

DX = 0.25


def truth_frame(length_m: float = 500.0, seed: int = 11) -> pd.DataFrame:
    """A clean TB/T 3352 campaign (per-rail channels from the four spectral channels)."""
    p = synthesize_profiles("tbt3352", length_m, DX, seed=seed)
    columns = inspection_columns_from_spectral(
        *(p[f"{channel}_mm"].to_numpy() for channel in SPECTRAL_CHANNELS))
    return pd.DataFrame({"chainage_m": p["chainage_m"].to_numpy(), **columns})


def interpolation_bound(values: np.ndarray, first: int, last: int) -> float:
    """Error bound of linear interpolation over samples first..last (known: first-1, last+1)."""
    gap = (last - first + 2) * DX
    window = values[first - 2:last + 3]
    second_derivative = np.abs(np.diff(window, 2)) / DX ** 2
    return gap ** 2 / 8.0 * second_derivative.max() * 1.2


def test_short_nan_runs_interpolated_and_counted():
    truth = truth_frame()
    frame = truth.copy()
    frame.loc[400:404, "gauge_mm"] = np.nan          # 5 samples = 1.25 m <= max_gap_m
    frame.loc[900, "vertical_left_mm"] = np.nan
    frame.loc[0:2, "alignment_right_mm"] = np.nan    # at the start: first valid value held
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    assert report.repairs["nan_interpolated"]["gauge_mm"] == 5
    assert report.repair_runs["nan_interpolated"]["gauge_mm"] == 1
    assert report.repairs["nan_interpolated"]["vertical_left_mm"] == 1
    assert report.repairs["nan_interpolated"]["alignment_right_mm"] == 3
    assert report.total("nan_interpolated") == 9
    x = truth["chainage_m"].to_numpy()
    for column, first, last in [("gauge_mm", 400, 404), ("vertical_left_mm", 900, 900)]:
        g = truth[column].to_numpy()
        known = np.ones(len(g), bool)
        known[first:last + 1] = False
        reference = np.interp(x[first:last + 1], x[known], g[known])
        repaired = clean[column].to_numpy()[first:last + 1]
        np.testing.assert_allclose(repaired, reference, rtol=0, atol=1e-12)
        assert np.max(np.abs(repaired - g[first:last + 1])) <= interpolation_bound(g, first, last)
    np.testing.assert_array_equal(clean["alignment_right_mm"].to_numpy()[:3],
                                  truth["alignment_right_mm"].to_numpy()[3])
    repaired_rows = [0, 1, 2, *range(400, 405), 900]
    pd.testing.assert_frame_equal(clean.drop(index=repaired_rows),
                                  truth.drop(index=repaired_rows))  # nothing else changed


def test_dropout_rows_reinserted_and_counted():
    truth = truth_frame()
    frame = truth.drop(index=range(1000, 1004)).reset_index(drop=True)  # 4 rows = 1 m missing
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    assert report.rows_in == len(truth) - 4 and report.rows_out == len(truth)
    np.testing.assert_array_equal(clean["chainage_m"].to_numpy(), truth["chainage_m"].to_numpy())
    for column in INSPECTION_COLUMNS:
        assert report.repairs["dropout_interpolated"][column] == 4
        assert report.repair_runs["dropout_interpolated"][column] == 1
        g = truth[column].to_numpy()
        error = np.abs(clean[column].to_numpy()[1000:1004] - g[1000:1004])
        assert error.max() <= interpolation_bound(g, 1000, 1003), column


def test_spikes_replaced_and_counted():
    truth = truth_frame()
    frame = truth.copy()
    frame.loc[700, "alignment_left_mm"] += 30.0       # an isolated spike
    frame.loc[1200:1201, "cross_level_mm"] -= 25.0    # a 2-sample spike (max_spike_run = 2)
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    assert report.repairs["spike_replaced"]["alignment_left_mm"] == 1
    assert report.repairs["spike_replaced"]["cross_level_mm"] == 2
    assert report.total("spike_replaced") == 3
    for column, first, last in [("alignment_left_mm", 700, 700), ("cross_level_mm", 1200, 1201)]:
        g = truth[column].to_numpy()
        error = np.abs(clean[column].to_numpy()[first:last + 1] - g[first:last + 1])
        assert error.max() <= interpolation_bound(g, first, last), column
    # nothing else changed
    others = np.ones(len(truth), bool)
    others[[700, 1200, 1201]] = False
    np.testing.assert_array_equal(clean.to_numpy()[others], truth.to_numpy()[others])


def test_long_excursion_is_kept_and_logged(caplog):
    """A 3-sample excursion is not a spike (max_spike_run = 2): kept as it is, with a warning."""
    frame = truth_frame()
    frame.loc[500:502, "vertical_right_mm"] += 20.0
    with caplog.at_level(logging.WARNING, logger="ttbpipe.inspection.validate"):
        clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    assert report.total("spike_replaced") == 0
    assert report.long_excursions_kept == {"vertical_right_mm": 1}
    np.testing.assert_array_equal(clean["vertical_right_mm"], frame["vertical_right_mm"])
    assert "kept as geometry" in caplog.text


def test_jitter_regridded_close_to_analytic_truth():
    """Chainage jitter of up to 8 % of the step: re-gridded onto the uniform 0.25 m grid."""
    wavelengths = np.array([3.0, 7.0, 19.0, 55.0])

    def profile(x):  # analytic, so that it can be evaluated at the jittered positions
        return sum(np.sin(2 * np.pi * x / lam + lam) for lam in wavelengths)

    grid = np.arange(0, 400.0 + DX / 2, DX)
    rng = np.random.default_rng(5)
    jitter = rng.uniform(-0.02, 0.02, grid.size)
    jitter[0] = jitter[-1] = 0.0
    positions = grid + jitter
    frame = pd.DataFrame({"chainage_m": positions,
                          **{c: profile(positions) for c in INSPECTION_COLUMNS}})
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    off_grid = int(np.sum(np.abs(jitter) > 0.01 * DX))
    assert report.repairs["regridded"]["gauge_mm"] == off_grid > 0
    assert abs(report.max_off_grid_m - np.abs(jitter).max()) < 1e-6
    np.testing.assert_allclose(clean["chainage_m"], grid, atol=1e-9)
    # interval <= 0.25 + 2 * 0.02 m; |f''| <= sum (2 pi / lambda)^2
    bound = (DX + 0.04) ** 2 / 8 * np.sum((2 * np.pi / wavelengths) ** 2)
    assert np.max(np.abs(clean["gauge_mm"] - profile(grid))) <= bound


@pytest.mark.parametrize("kind", ["none", "constant", "linear"])
def test_detrend(kind):
    frame = truth_frame()
    x = frame["chainage_m"].to_numpy()
    for column in INSPECTION_COLUMNS:
        frame[column] += 2.0 + 5.0e-3 * x  # 2 mm offset, 5 mm/km
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend=kind)
    for column in INSPECTION_COLUMNS:
        raw = frame[column].to_numpy()
        out = clean[column].to_numpy()
        if kind == "none":
            np.testing.assert_array_equal(out, raw)
            assert report.trend_removed == {}
            continue
        slope, intercept = np.polyfit(x, raw, 1)
        if kind == "constant":
            np.testing.assert_allclose(out, raw - raw.mean(), atol=1e-12)
            assert report.trend_removed[column]["slope_mm_per_km"] == pytest.approx(0, abs=1e-9)
        else:
            np.testing.assert_allclose(out, raw - (intercept + slope * x), atol=1e-9)
            assert report.trend_removed[column]["slope_mm_per_km"] == pytest.approx(
                slope * 1000, rel=1e-9)
        assert report.trend_removed[column]["mean_mm"] == pytest.approx(raw.mean(), rel=1e-9)


def test_cross_level_is_not_forced_to_match_rail_difference():
    frame = truth_frame()
    independent = synthesize_profiles("tbt3352", 500.0, DX, seed=99)["cross_level_mm"]
    frame["cross_level_mm"] = independent.to_numpy()
    clean, report = clean_campaign(frame, "x/2023-01-15.csv", detrend="none")
    np.testing.assert_array_equal(clean["cross_level_mm"], frame["cross_level_mm"])
    difference = frame["cross_level_mm"] - (frame["vertical_left_mm"] - frame["vertical_right_mm"])
    slope, intercept = np.polyfit(frame["chainage_m"], difference, 1)
    residual = difference - (intercept + slope * frame["chainage_m"])
    assert report.cross_level_rms_difference_mm == pytest.approx(
        float(np.sqrt(np.mean(residual ** 2))), rel=1e-9)


def test_report_is_json_and_summary_lists_repairs():
    frame = truth_frame()
    frame.loc[100:102, "gauge_mm"] = np.nan
    frame.loc[300, "vertical_left_mm"] += 40.0
    clean, report = clean_campaign(frame, "x/2023-01-15.csv")
    doc = json.loads(json.dumps(report.to_dict()))
    assert doc["source"] == "x/2023-01-15.csv" and doc["campaign_date"] == "2023-01-15"
    assert doc["sampling_interval_m"] == 0.25 and doc["length_m"] == 500.0
    assert doc["repairs"]["nan_interpolated"]["gauge_mm"] == 3
    assert doc["repairs"]["spike_replaced"]["vertical_left_mm"] == 1
    assert doc["settings"]["max_gap_m"] == 2.0
    assert any("nan_interpolated: 3 samples" in n for n in doc["notes"])
    text = report.summary()
    assert "x/2023-01-15.csv" in text and len(text.splitlines()) < 25
    gauge_line = next(line for line in text.splitlines() if line.strip().startswith("gauge_mm"))
    assert "3 (  1)" in gauge_line


def test_cli_exit_codes(tmp_path, capsys):
    good = tmp_path / "2023-01-15.csv"
    frame = truth_frame()
    frame.loc[10, "gauge_mm"] = np.nan
    frame.to_csv(good, index=False)
    out, repairs = tmp_path / "clean.parquet", tmp_path / "repairs.json"
    assert main(["check-inspection", str(good), "--out", str(out), "--report", str(repairs)]) == 0
    captured = capsys.readouterr()
    assert captured.out.rstrip().endswith("OK") and "FAILED" not in captured.err
    assert "repaired samples" in captured.out and str(good) in captured.out
    assert read_provenance(out)["kind"] == "inspection_clean"
    assert len(read_table(out)) == len(frame)
    assert json.loads(repairs.read_text())["repairs"]["nan_interpolated"]["gauge_mm"] == 1

    bad = tmp_path / "2023-02-15.csv"
    frame.loc[300:319, "vertical_right_mm"] = np.nan
    frame.to_csv(bad, index=False)
    assert main(["check-inspection", str(bad), "--out", str(tmp_path / "bad.parquet")]) == 1
    err = capsys.readouterr().err
    assert "FAILED" in err and str(bad) in err
    assert "row 301" in err and "column vertical_right_mm" in err
    assert not (tmp_path / "bad.parquet").exists()
    # a looser limit from the command line repairs the same file
    assert main(["check-inspection", str(bad), "--max-gap-m", "6"]) == 0
