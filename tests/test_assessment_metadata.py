"""One limit source per assessed index for all of a study's samples.

A study keeps the assessed rows' metadata (clause, category, limit source) once, in its batches'
provenance, and the reliability table and report print it for every sample
(:func:`ttbpipe.assessment.columns.shared_row_metadata`). So a profile words each limit source as
the rule, and puts the run's own values (static load, speed, span length) in the row's notes and
in its limit. Checked on two synthetic runs that differ in every input a limit depends on: the
static wheel load (EN 14363 (sum Y)2m and Q, GB/T 5599 H) and the speed (EN 14363 Q's cap,
GB/T 5599 unloading ratio, EN 1990 deck twist). Their limits must differ (closed forms: 10 kN +
2 Q0/3, min(90 kN + Q0, speed cap), 15 kN + P0/3, 0.8 / 0.65 above / at most 160 km/h, 1.5 / 3.0
mm above / at most 200 km/h; tolerance 1e-9 relative), so that the test fails if a run's values
leave the limit; their metadata must be equal.
"""

import logging

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from test_assessment_en1990 import twist_columns
from ttbpipe.assessment import assess
from ttbpipe.assessment.columns import row_metadata, shared_row_metadata

#: (static wheel load N, speed km/h) of the two runs.
RUN_A, RUN_B = (70e3, 300.0), (85e3, 150.0)

#: index: (limit of run A, limit of run B), closed forms of the module docstring.
LIMITS = {
    ("en14363", "sum_Y_2m_N"): (10e3 + 2 * 70e3 / 3, 10e3 + 2 * 85e3 / 3),
    ("en14363", "Q_max_N"): (160e3, 175e3),
    ("gb5599", "lateral_wheelset_force_H_N"): (15e3 + 140e3 / 3, 15e3 + 170e3 / 3),
    ("gb5599", "wheel_unloading_ratio"): (0.8, 0.65),
    ("en1990", "deck_twist_m"): (1.5e-3, 3.0e-3),
}

EN1990_OPTIONS = {"f0_hz": 5.0, "f3_hz": 40.0, "span_lengths_m": 32.0}


def assessed(p0, speed_kmh, profile):
    t = 1e-3 * np.arange(4000)
    cols = {"girder_span1_mid_z_acc_m_s2": 0.3 * np.sin(2 * np.pi * 10.0 * t),
            "girder_span1_mid_z_disp_mm": -1.2 * np.sin(np.pi * t / 4.0) ** 2,
            **twist_columns(t, 1.0e-3)}
    table, summary = synthetic_run(cols, speed_kmh=speed_kmh, p0=p0)
    return assess(table, summary, profile,
                  options=EN1990_OPTIONS if profile == "en1990" else None)


@pytest.mark.parametrize("profile", ["en14363", "gb5599", "en1990", "en12299"])
def test_runs_with_other_loads_and_speeds_share_the_metadata(profile):
    a, b = assessed(*RUN_A, profile), assessed(*RUN_B, profile)
    for (name, index), (lim_a, lim_b) in LIMITS.items():
        if name == profile:
            row_a, row_b = (df[df["index"] == index].iloc[0] for df in (a, b))
            assert row_a["limit"] == pytest.approx(lim_a, rel=1e-9)
            assert row_b["limit"] == pytest.approx(lim_b, rel=1e-9)
    assert row_metadata(a) == row_metadata(b)


def test_the_runs_own_values_are_in_the_notes():
    a = assessed(*RUN_A, "en14363")
    assert "Q0 = 70000 N" in a.loc[a["index"] == "sum_Y_2m_N", "notes"].iloc[0]
    assert "at most 170 kN at 300 km/h" in a.loc[a["index"] == "Q_max_N", "notes"].iloc[0]
    g = assessed(*RUN_B, "gb5599")
    assert "P0 = 170000 N" in g.loc[g["index"] == "lateral_wheelset_force_H_N", "notes"].iloc[0]
    assert "0.65 at 150 km/h" in g.loc[g["index"] == "wheel_unloading_ratio", "notes"].iloc[0]
    e = assessed(*RUN_B, "en1990")
    assert "3 mm at 150 km/h" in e.loc[e["index"] == "deck_twist_m", "notes"].iloc[0]
    assert "L = 32 m" in e.loc[e["index"] == "vertical_deflection_m", "notes"].iloc[0]


def test_differing_metadata_is_logged_with_both_origins_and_the_first_kept(caplog):
    first = row_metadata(assessed(*RUN_A, "en14363"))
    other = [dict(m) for m in first]
    other[1]["limit_source"] = "another wording"
    with caplog.at_level(logging.WARNING, logger="ttbpipe.assessment.columns"):
        kept = shared_row_metadata([("batch A", None), ("batch B", first), ("batch C", other),
                                    ("batch D", first), ("batch E", other), ("batch F", other)])
    assert kept == first
    [record] = [r for r in caplog.records if r.name == "ttbpipe.assessment.columns"]  # one per index
    message = record.getMessage()
    assert "batch B" in message and "batch C and 2 more" in message
    assert "limit_source" in message and first[1]["index"] in message
    assert "another wording" in message
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="ttbpipe.assessment.columns"):
        assert shared_row_metadata([("batch B", first), ("batch C", first)]) == first
    assert not [r for r in caplog.records if r.name == "ttbpipe.assessment.columns"]
    assert shared_row_metadata([("batch A", None), ("batch B", [])]) == []


def test_metadata_with_other_keys_is_reported_not_a_crash(caplog):
    """A record that lacks a key the first one has (or adds one) differs too."""
    first = row_metadata(assessed(*RUN_A, "gb5599"))
    other = [dict(m) for m in first]
    del other[0]["standard"]
    with caplog.at_level(logging.WARNING, logger="ttbpipe.assessment.columns"):
        assert shared_row_metadata([("batch B", first), ("batch C", other)]) == first
    [record] = [r for r in caplog.records if r.name == "ttbpipe.assessment.columns"]
    assert "standard" in record.getMessage() and "batch C" in record.getMessage()
