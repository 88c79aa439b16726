"""Assessed indices in the study: their columns, the utilisation table, the report's margins.

Checked against independent references:

* the column names of :mod:`ttbpipe.assessment.columns` follow the results schema's unit rule
  (:func:`ttbpipe.stats.schema.unit_of`) and read back to the same index, unit and section;
* the utilisation statistics of :func:`ttbpipe.study.utilisation.utilisation_table` equal
  numpy's inverted-CDF quantiles of the same values (equal weights, exact) and the maximum and
  its sample; P(utilisation > 1) is k/n with the Wilson interval of scipy's ``binomtest``
  (exact equality up to 1e-12: the same formula from another implementation);
* end to end through :func:`ttbpipe.study.outputs.aggregate_study` on synthetic batch files
  with the metadata in their provenance (as ``simulate_batch`` writes it): the summary names the
  largest utilisation and its sample, one utilisation figure per report section, and the
  convergence panels are not repeated for limits that no sample exceeds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from ttbpipe import io
from ttbpipe.assessment.base import Profile, Row, rows_to_frame
from ttbpipe.assessment.columns import (assessed_indices, extreme_columns, limit_column,
                                        row_metadata, utilisation_column)
from ttbpipe.stats.limits import limits_from_config
from ttbpipe.stats.reliability import assess_limits, convergence_curve
from ttbpipe.stats.schema import example_extremes, unit_of, validate_extremes
from ttbpipe.study import utilisation as U
from ttbpipe.study.outputs import _distinct_curves, aggregate_study

PROFILE = Profile("gb5599", "GB/T 5599-2019", "test", {}, lambda run, options: [])
EN14363 = Profile("en14363", "EN 14363:2016", "test", {}, lambda run, options: [])


def _table(unloading=0.1, sum_y=5e3, sum_y_limit=57.7e3):
    gb = rows_to_frame(PROFILE, [
        Row("9 (wheel unloading)", "wheel_unloading_ratio", "1", "wheel", "car1_ws1_left",
            unloading, 0.8, "0.8 above 160 km/h"),
        Row("9 (lateral wheelset force)", "lateral_wheelset_force_H_N", "N", "wheelset",
            "car1_ws1", 4e3, 62.7e3, "15 kN + P0/3")])
    en = rows_to_frame(EN14363, [
        Row("(sum Y)2m", "sum_Y_2m_N", "N", "wheelset", "car1_ws1", sum_y, sum_y_limit,
            "alpha (10 kN + P0/3)"),
        Row("b_v", "b_v_m_s2", "m/s^2", "car", "car1_front", 0.2, 1.0, "very good",
            category="grade")])
    return gb, en


def test_columns_follow_the_unit_rule_and_read_back():
    gb, en = _table()
    cols = {**extreme_columns(gb), **extreme_columns(en)}
    assert cols["gb5599_wheel_unloading_ratio"] == 0.1
    assert cols[utilisation_column("gb5599", "wheel_unloading_ratio")] == pytest.approx(0.125)
    assert limit_column("en14363", "sum_Y_2m_N") == "en14363_sum_Y_2m_limit_N"
    assert cols["en14363_sum_Y_2m_limit_N"] == 57.7e3
    units = {c: unit_of(c) for c in cols}
    assert units["en14363_sum_Y_2m_N"] == "N" and units["en14363_sum_Y_2m_utilisation"] == "1"
    assert units["gb5599_wheel_unloading_ratio_limit"] == "1"
    assert units["en14363_b_v_limit_m_s2"] == "m/s^2"
    found = assessed_indices(cols, row_metadata(gb) + row_metadata(en))
    by = {(a.profile, a.index): a for a in found}
    assert set(by) == {("gb5599", "wheel_unloading_ratio"), ("gb5599", "lateral_wheelset_force_H_N"),
                       ("en14363", "sum_Y_2m_N"), ("en14363", "b_v_m_s2")}
    assert by[("en14363", "sum_Y_2m_N")].unit == "N"
    assert by[("en14363", "sum_Y_2m_N")].limit == "en14363_sum_Y_2m_limit_N"
    assert by[("en14363", "b_v_m_s2")].category == "grade"
    assert by[("gb5599", "wheel_unloading_ratio")].section == "Running safety"
    # report order: running safety first (sum Y before the unloading ratio, as SECTIONS lists)
    assert [a.index for a in found][:3] == ["sum_Y_2m_N", "wheel_unloading_ratio",
                                            "lateral_wheelset_force_H_N"]


def _extremes(n=40, seed=0, exceed=(3, 17)):
    """Synthetic extremes with assessed columns: utilisations uniform on (0.2, 0.9) except the
    samples ``exceed`` of the unloading ratio, above 1."""
    rng = np.random.default_rng(seed)
    df = example_extremes(range(n), "C1", seed=seed)
    u = rng.uniform(0.2, 0.9, n)
    u[list(exceed)] = [1.05, 1.3][: len(exceed)]
    gb, en = _table()
    base = {**extreme_columns(gb), **extreme_columns(en)}
    for c, v in base.items():
        df[c] = np.full(n, v)
    df["gb5599_wheel_unloading_ratio_utilisation"] = u
    df["gb5599_wheel_unloading_ratio"] = 0.8 * u
    df["en14363_sum_Y_2m_limit_N"] = np.linspace(55e3, 60e3, n)
    return validate_extremes(df), row_metadata(gb) + row_metadata(en)


def test_utilisation_statistics_and_probability_against_numpy_and_scipy():
    df, meta = _extremes()
    indices = assessed_indices(df.columns, meta)
    limits = U.assessed_limits(indices)
    assert {lim.name for lim in limits} == {a.value for a in indices}
    table = assess_limits(df, limits)
    util = U.utilisation_table(df, indices, table)
    row = util[util["index"] == "wheel_unloading_ratio"].iloc[0]
    u = df["gb5599_wheel_unloading_ratio_utilisation"].to_numpy()
    assert row["median_utilisation"] == np.quantile(u, 0.5, method="inverted_cdf")
    assert row["p95_utilisation"] == np.quantile(u, 0.95, method="inverted_cdf")
    assert row["max_utilisation"] == 1.3 and row["max_sample_index"] == 17
    assert row["max_value"] == pytest.approx(0.8 * 1.3)
    ci = stats.binomtest(2, 40).proportion_ci(confidence_level=0.95, method="wilson")
    assert row["probability"] == pytest.approx(2 / 40, abs=1e-12)
    assert (row["ci_low"], row["ci_high"]) == pytest.approx((ci.low, ci.high), abs=1e-12)
    assert row["method"] == "wilson"
    sum_y = util[util["index"] == "sum_Y_2m_N"].iloc[0]
    assert (sum_y["limit_low"], sum_y["limit_high"]) == (55e3, 60e3)
    margins = U.margins(util)
    assert list(margins["index"]) == [a.index for a in indices if a.utilisation]


def test_convergence_panels_are_not_repeated():
    df, meta = _extremes()
    indices = assessed_indices(df.columns, meta)
    curves = [convergence_curve(df, lim, scenario="C1") for lim in U.assessed_limits(indices)]
    shown = _distinct_curves(curves)
    # one limit exceeded (the unloading ratio), three never: two panels, not four
    assert len(shown) == 2
    assert shown[0].attrs["limit"] == "gb5599_wheel_unloading_ratio"
    assert "3 limits without an exceeding sample" in shown[1].attrs["description"]
    assert _distinct_curves([c.iloc[:1] for c in curves]) == []   # one sample: no panel


def test_aggregate_study_leads_with_the_margins(tmp_path: Path):
    df, meta = _extremes()
    paths = [io.write_table(df.iloc[:20], tmp_path / "b" / "extremes_0.parquet", assessment=meta),
             io.write_table(df.iloc[20:], tmp_path / "b" / "extremes_1.parquet", assessment=meta)]
    config = {"study": {"name": "synthetic"}, "limits": {}}
    written = aggregate_study(paths, [], None, config, out=tmp_path / "out")
    main = written["summary_rst"].read_text()
    assert "**Largest utilisation 1.3**" in main and "sample 17" in main
    page = written["summary"].read_text()
    assert "Margins to the limits" in page and "wheel unloading ratio" in page
    figures = sorted(p.name for p in (tmp_path / "out" / "figures" / "utilisation").glob("*.png"))
    assert figures == ["1_running_safety.png", "4_ride_comfort.png"]
    reliability = pd.read_parquet(written["reliability"])
    raw = reliability[reliability["category"] == "raw"]
    assert set(raw["limit"]) == {lim.name for lim in limits_from_config({})[0]}
    unloading = reliability[reliability["limit"] == "gb5599_wheel_unloading_ratio"].iloc[0]
    assert int(unloading["n_exceed"]) == 2
