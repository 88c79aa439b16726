"""EN 1990 A2 profile (ttbpipe.assessment.en1990), its modal frequencies and its monitors.

* Band rule (A2.4.4.2.1): with given f0, f3 the deck filter's cut-off is max(30, 1.5 f0, f3) and
  a 35 Hz girder acceleration of amplitude A comes out as A |H(35 Hz)|^2 of that zero-phase
  Butterworth (closed form in tests/test_assessment_processing.py); tolerance 1e-3.
* Twist (A2.4.4.2.2): rails at section a moving +-d/2 in antiphase, section b at rest, give
  t = d; limits 1.5 / 3.0 / 4.5 mm by speed. Deflection (A2.4.4.2.3): a midspan history of peak
  delta gives delta against L/600. Exact (1e-12).
* Modal analysis of a girder-only structure with pinned supports: the span's f0 and f3 are the
  Euler-Bernoulli frequencies j^2 pi/(2 L^2) sqrt(EI/m), j = 1, 3 (Blevins, Formulas for Natural
  Frequency and Mode Shape, 1979, table 8-1), for spans of 32 and 24 m; tolerance 0.1 % (as
  tests/test_structure_modal.py, 32 elements per span).
* The study's once-per-study span-frequency record (rule study_span_frequencies): through its
  JSON file, the options it gives the batches are the analysis's numbers exactly, and a deck
  assessment with them equals the one that analyses the structure itself (DataFrame.equals); a
  record of another structure is refused.
* deck_check_monitors: valid monitor specs (they compile), pairs 3 m apart, one per span start,
  middle and end and per joint.
"""

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from test_assessment_processing import lowpass_power
from ttbpipe.assessment import assess
from ttbpipe.assessment.en1990 import band_cutoff_hz, twist_limit_m
from ttbpipe.assessment.modal import span_frequencies, span_frequency_record, span_options
from ttbpipe.assessment.study import (needs_span_frequencies, resolve_assessment,
                                      with_span_frequencies)
from ttbpipe.assessment.monitors import deck_check_monitors, twist_sections
from ttbpipe.structure import build_structure
from ttbpipe.structure.monitors import compile_monitors, default_monitors

GIRDER = dict(E=3.45e10, m=2.972e4, Iy=12.744)


def bending(j, length):
    return j * j * np.pi / (2 * length ** 2) * np.sqrt(GIRDER["E"] * GIRDER["Iy"] / GIRDER["m"])


def twist_columns(t, d_m):
    z = 0.5e3 * d_m * np.sin(2 * np.pi * 1.0 * t)      # mm
    return {"twist_span1_mid_a_left_z_disp_mm": z, "twist_span1_mid_a_right_z_disp_mm": -z,
            "twist_span1_mid_b_left_z_disp_mm": 0 * t, "twist_span1_mid_b_right_z_disp_mm": 0 * t}


def deck_run(acc, speed_kmh=300.0, delta_m=1.2e-3, twist_m=1.0e-3):
    t = 1e-3 * np.arange(4000)
    cols = {"girder_span1_mid_z_acc_m_s2": acc(t),
            "girder_span1_mid_z_disp_mm": -1e3 * delta_m * np.sin(np.pi * t / 4.0) ** 2,
            **twist_columns(t, twist_m)}
    return synthetic_run(cols, speed_kmh=speed_kmh)


def row(df, index):
    out = df[df["index"] == index]
    assert len(out) == 1
    return out.iloc[0]


@pytest.mark.parametrize("f0, f3, cutoff", [(4.0, 20.0, 30.0), (25.0, 30.0, 37.5), (5.6, 42.0, 42.0)])
def test_band_rule_sets_the_cutoff_and_the_35_hz_response(f0, f3, cutoff):
    assert band_cutoff_hz(f0, f3) == cutoff
    a = 0.8
    table, summary = deck_run(lambda t: a * np.sin(2 * np.pi * 35.0 * t))
    df = assess(table, summary, "en1990",
                options={"f0_hz": f0, "f3_hz": f3, "span_lengths_m": 32.0})
    r = row(df, "deck_vertical_acc_m_s2")
    assert r["filter_high_hz"] == cutoff and r["filter_order"] == 4
    assert r["processed_value"] == pytest.approx(a * lowpass_power(35.0, cutoff, 4), rel=1e-3)
    assert r["limit"] == 5.0                                     # ballastless (direct fastening)
    ballasted = assess(table, summary, "en1990", options={
        "f0_hz": f0, "f3_hz": f3, "span_lengths_m": 32.0, "deck_track_type": "ballasted"})
    assert row(ballasted, "deck_vertical_acc_m_s2")["limit"] == 3.5


@pytest.mark.parametrize("speed, limit", [(300.0, 1.5e-3), (160.0, 3.0e-3), (100.0, 4.5e-3)])
def test_twist_and_deflection_closed_forms(speed, limit):
    table, summary = deck_run(lambda t: 0 * t, speed_kmh=speed)
    df = assess(table, summary, "en1990", options={"f0_hz": 5.0, "f3_hz": 40.0,
                                                   "span_lengths_m": 32.0})
    tw = row(df, "deck_twist_m")
    assert tw["processed_value"] == pytest.approx(1.0e-3, rel=1e-12)
    assert tw["limit"] == twist_limit_m(speed) == limit and tw["location"] == "span1_mid"
    de = row(df, "vertical_deflection_m")
    assert de["processed_value"] == pytest.approx(1.2e-3, rel=1e-12)
    assert de["limit"] == pytest.approx(32.0 / 600.0, rel=1e-12)
    assert row(df, "span_to_deflection_ratio")["processed_value"] == pytest.approx(32.0 / 1.2e-3)


def test_missing_twist_monitors_stop_the_check_unless_skipped():
    t = 1e-3 * np.arange(4000)
    table, summary = synthetic_run({"girder_span1_mid_z_acc_m_s2": 0.1 * np.sin(t)})
    opts = {"f0_hz": 5.0, "f3_hz": 40.0, "span_lengths_m": 32.0}
    with pytest.raises(ValueError, match="deck_check_monitors"):
        assess(table, summary, "en1990", options=opts)
    df = assess(table, summary, "en1990", options={**opts, "twist": False})
    assert "deck_twist_m" not in set(df["index"])


def test_span_frequencies_of_pinned_girders_are_euler_bernoulli():
    structure = {"layout": {"approach_length_m": 0.0, "spans_m": [32.0, 24.0],
                            "bridge_track": "none"}, "bearing": {"rigid": True}}
    spans = span_frequencies(structure)
    assert [s.length_m for s in spans] == [32.0, 24.0]
    for s in spans:
        assert s.f0_hz == pytest.approx(bending(1, s.length_m), rel=1e-3)
        assert s.f3_hz == pytest.approx(bending(3, s.length_m), rel=1e-3)
    assert span_frequencies(structure) is spans                 # cached per structure


def test_span_frequency_record_gives_the_analysis_numbers(tmp_path):
    import json

    structure = {"layout": {"approach_length_m": 0.0, "spans_m": [32.0, 24.0],
                            "bridge_track": "none"}, "bearing": {"rigid": True}}
    path = tmp_path / "span_frequencies.json"
    path.write_text(json.dumps(span_frequency_record(structure), indent=1))
    record = json.loads(path.read_text())
    spans = span_frequencies(structure)
    assert span_options(record, structure) == {"f0_hz": [s.f0_hz for s in spans],
                                               "f3_hz": [s.f3_hz for s in spans],
                                               "span_lengths_m": [32.0, 24.0]}
    other = {**structure, "layout": {**structure["layout"], "spans_m": [32.0, 32.0]}}
    with pytest.raises(ValueError, match="another structure"):
        span_options(record, other, str(path))

    assessment = resolve_assessment({"standard": ["en1990"],
                                     "options": {"en1990": {"twist": False}}})
    assert needs_span_frequencies(assessment)
    given = with_span_frequencies(assessment, record, structure, str(path))
    assert not needs_span_frequencies(given)
    t = 1e-3 * np.arange(4000)
    table, summary = synthetic_run({
        "girder_span1_mid_z_acc_m_s2": np.sin(2 * np.pi * 35.0 * t) + 0.3 * np.sin(2 * np.pi * 8 * t),
        "girder_span2_mid_z_acc_m_s2": 0.5 * np.sin(2 * np.pi * 45.0 * t),
        "girder_span1_mid_z_disp_mm": -1.2 * np.sin(np.pi * t / 4.0) ** 2,
        "girder_span2_mid_z_disp_mm": -0.8 * np.sin(np.pi * t / 4.0) ** 2})
    analysed = assess(table, summary, "en1990", options=assessment["options"]["en1990"],
                      config={"structure": structure})
    from_record = assess(table, summary, "en1990", options=given["options"]["en1990"],
                         config={"structure": structure})
    assert analysed.equals(from_record)
    # options given by the user, or EN 1990 not selected: nothing to take from the record
    fixed = resolve_assessment({"standard": ["en1990"], "options": {"en1990": {
        "f0_hz": 5.0, "f3_hz": 40.0, "span_lengths_m": 32.0, "twist": False}}})
    assert with_span_frequencies(fixed, record, other, str(path)) == fixed
    assert not needs_span_frequencies(resolve_assessment({"standard": ["en14363"]}))


def test_deck_check_monitors_compile_and_pair_sections_3_m_apart():
    model = build_structure({"layout": {"approach_length_m": 20.0, "spans_m": [32.0, 24.0]}})
    specs = deck_check_monitors(model)
    sections = twist_sections(model)
    assert [w for w, _ in sections] == ["span1_start", "span1_mid", "span1_end", "span2_start",
                                        "span2_mid", "span2_end", "joint0", "joint1", "joint2"]
    assert len(specs) == 4 * len(sections)
    monitors = compile_monitors(model, default_monitors(model) + specs)
    assert sum(n.startswith("twist_") for n in monitors.names) == len(specs)
    x = {s["name"]: s["x_m"] for s in specs}
    for where, xa in sections:
        assert x[f"twist_{where}_b_left"] - x[f"twist_{where}_a_left"] == pytest.approx(3.0)
        assert x[f"twist_{where}_a_right"] == x[f"twist_{where}_a_left"] == pytest.approx(xa)
    assert x["twist_joint1_a_left"] == pytest.approx(20.0 + 32.0 - 1.5)
