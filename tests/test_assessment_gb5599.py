"""GB/T 5599 profile (ttbpipe.assessment.gb5599) on synthetic runs with closed-form answers.

* Unloading P = P0 (1 - u sin(2 pi f t)), f = 2 Hz (passed by the 20 Hz low-pass), plus an 80 Hz
  part: the 99.85th percentile of the 2 m piece maxima of (P0 - P)/P0 is u (the top pieces hold
  the crest; sampling at 1 ms misses it by at most 1 - cos(2 pi f dt / 2) = 2e-5; tolerance 1e-3 u),
  while the raw maximum keeps the 80 Hz part.
* Lateral wheelset force limit 15 kN + P0/3 with P0 the static axle load (two wheel loads).
* Car body a = A cos(2 pi 25 t) at V = 100 m/s over whole periods: a 2 m piece is a half period,
  each piece's peak is a crest A G with G = |H(25 Hz)|^2 of the 0.4-40 Hz zero-phase band-pass
  (closed form of the digital Butterworth band-pass, tests/test_assessment_processing.py), so
  mean + 2.2 sigma = A G (sigma = 0); tolerance 1e-3. (A cosine over whole periods continues
  smoothly into the mirror-image padding of the band-pass: no start-up transient enters.)
* Sperling of a sinusoid of amplitude A at f (on a DFT bin of the 5 s windows):
  W = 3.57 (A^3 F(f) / f)^0.1 (physics.md section 4; the closed form of tests/test_comfort.py);
  tolerance 1e-9.
"""

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from test_assessment_processing import bandpass_power
from ttbpipe.assessment import assess
from ttbpipe.vehicle.comfort import sperling_weighting

P0 = 70e3


def row(df, index):
    out = df[df["index"] == index]
    assert len(out) == 1
    return out.iloc[0]


def test_unloading_of_a_2_hz_oscillation_is_its_amplitude_not_the_80_hz_peak():
    u = 0.3
    table, summary = synthetic_run({
        "car1_ws2_left_P_N": lambda t: P0 * (1 - u * np.sin(2 * np.pi * 2.0 * t))
        - 0.25 * P0 * np.sin(2 * np.pi * 80 * t)})
    df = assess(table, summary, "gb5599")
    r = row(df, "wheel_unloading_ratio")
    assert r["location"] == "car1_ws2_left"
    assert r["processed_value"] == pytest.approx(u, rel=1e-3)
    assert r["raw_value"] > u + 0.2
    assert r["limit"] == 0.8                              # above 160 km/h (stats.limits)
    slow = assess(*synthetic_run({"car1_ws2_left_P_N": lambda t: P0 * (1 - 0.1 * np.sin(t))},
                                 speed_kmh=120.0), "gb5599")
    assert row(slow, "wheel_unloading_ratio")["limit"] == 0.65
    qp = row(df, "derailment_coefficient_Q_P")
    assert qp["processed_value"] == 0.0 and qp["limit"] == 0.8


def test_steady_ratios_and_the_axle_load_limit_of_h():
    q, h = 14e3, 9e3
    table, summary = synthetic_run({"car1_ws1_right_Q_N": lambda t: q + 0 * t,
                                    "car1_ws1_H_N": lambda t: h + 0 * t})
    df = assess(table, summary, "gb5599")
    assert row(df, "derailment_coefficient_Q_P")["processed_value"] == pytest.approx(q / P0, rel=1e-9)
    r = row(df, "lateral_wheelset_force_H_N")
    assert r["processed_value"] == pytest.approx(h, rel=1e-9)
    assert r["limit"] == pytest.approx(15e3 + 2 * P0 / 3, rel=1e-12)
    assert r["utilisation"] == pytest.approx(h / (15e3 + 2 * P0 / 3))


def test_carbody_statistic_of_half_period_pieces_is_the_filtered_crest():
    a, f = 0.6, 25.0
    table, summary = synthetic_run({"car1_body_centre_az_m_s2": lambda t: a * np.cos(2 * np.pi * f * t)},
                                   duration_s=20.001, speed_kmh=360.0)
    r = row(assess(table, summary, "gb5599"), "carbody_vertical_acc_m_s2")
    assert r["location"] == "car1_centre"
    assert r["processed_value"] == pytest.approx(a * bandpass_power(f, 0.4, 40.0, 4), rel=1e-3)
    assert (r["filter_low_hz"], r["filter_high_hz"], r["limit"]) == (0.4, 40.0, 2.5)


@pytest.mark.parametrize("direction, axis, amp, f", [("vertical", "az", 0.3, 2.0),
                                                    ("lateral", "ay", 0.2, 8.0)])
def test_sperling_of_a_sinusoid_is_the_closed_form(direction, axis, amp, f):
    table, summary = synthetic_run(
        {f"car1_body_rear_{axis}_m_s2": lambda t: amp * np.sin(2 * np.pi * f * t + 0.3)},
        duration_s=10.0)
    r = row(assess(table, summary, "gb5599"), f"sperling_{direction}")
    expected = 3.57 * (amp ** 3 * sperling_weighting(np.array([f]), direction)[0] / f) ** 0.1
    assert r["location"] == "car1_rear"
    assert r["processed_value"] == pytest.approx(expected, rel=1e-9)
    assert r["limit"] == 3.0 and r["statistic"] == "largest 5 s window"
