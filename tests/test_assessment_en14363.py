"""EN 14363 profile (ttbpipe.assessment.en14363) on synthetic runs with closed-form answers.

* A steady flange force Y on one wheel at its static load Q0 gives (Y/Q)2m = Y/Q0 exactly (the
  sliding mean and the percentile of a constant are the constant; tolerance 1e-9), in the
  flange-climbing sense (-Q on a left wheel, +Q on a right one); an 80 Hz part on top is removed
  to the filter's |H|^2 x sinc of the 2 m window (predicted residue < 1e-5, tolerance 1e-4).
* A steady sum Y = h gives (sum Y)2m = h and the limit alpha (10 kN + 2 Q0/3) (standards.md).
* Q = Q0 + A sin(2 pi f t) with f = 2 Hz (passed by the 20 Hz low-pass): the p-percentile of a
  uniformly sampled sinusoid is Q0 + A sin(pi (p - 1/2)) (the quantile of A sin(theta), theta
  uniform); tolerance 2e-4 A over whole periods. An 80 Hz part adds to the raw maximum, not to
  the processed value. Q_qst (50 %) is then Q0.
"""

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from ttbpipe.assessment import assess
from ttbpipe.assessment.en14363 import DEFAULTS, q_max_limit_N, sum_y_limit_N

P0 = 70e3


def row(df, index):
    out = df[df["index"] == index]
    assert len(out) == 1, f"{index}: {len(out)} rows"
    return out.iloc[0]


def test_steady_flange_force_gives_y_over_q0_in_the_climbing_sense():
    y = 20e3
    table, summary = synthetic_run({
        "car1_ws1_left_Q_N": lambda t: -y + 3e3 * np.sin(2 * np.pi * 80 * t),   # flange pushed right
        "car1_ws2_right_Q_N": lambda t: -0.5 * y + 0 * t,   # pushed away from the flange: no climbing
    })
    df = assess(table, summary, "en14363")
    r = row(df, "Y_Q_2m")
    assert r["location"] == "car1_ws1_left"
    assert r["processed_value"] == pytest.approx(y / P0, abs=1e-4)
    assert r["raw_value"] == pytest.approx((y + 3e3) / P0, rel=1e-3)      # raw keeps the 80 Hz peak
    assert r["limit"] == DEFAULTS["yq_limit"] and r["utilisation"] == pytest.approx(
        r["processed_value"] / 0.8)
    assert (r["window_m"], r["step_m"], r["filter_high_hz"], r["filter_order"]) == (2.0, 0.5, 20.0, 4)
    assert r["clause"] and r["standard"] == "EN 14363:2016"


def test_steady_track_shift_force_and_its_prudhomme_limit():
    h = 15e3
    table, summary = synthetic_run({"car1_ws2_left_Q_N": lambda t: h + 0 * t})
    r = row(assess(table, summary, "en14363"), "sum_Y_2m_N")
    assert r["location"] == "car1_ws2"
    assert r["processed_value"] == pytest.approx(h, rel=1e-9)
    assert r["limit"] == pytest.approx(10e3 + 2 * P0 / 3, rel=1e-12)
    assert sum_y_limit_N(P0, 0.85) == pytest.approx(0.85 * (10e3 + 2 * P0 / 3))
    alpha = assess(table, summary, "en14363", options={"alpha": 0.85})
    assert row(alpha, "sum_Y_2m_N")["limit"] == pytest.approx(0.85 * (10e3 + 2 * P0 / 3))


def test_vertical_force_percentiles_of_a_sinusoid():
    a, f = 12e3, 2.0
    table, summary = synthetic_run({
        "car1_ws1_right_P_N": lambda t: P0 + a * np.sin(2 * np.pi * f * t)
        + 9e3 * np.sin(2 * np.pi * 80 * t)})
    df = assess(table, summary, "en14363")
    q = row(df, "Q_max_N")
    assert q["location"] == "car1_ws1_right"
    assert q["processed_value"] == pytest.approx(P0 + a * np.sin(np.pi * (0.9985 - 0.5)), abs=2e-4 * a)
    assert q["raw_value"] > P0 + a + 8e3                       # the unfiltered maximum
    assert q["limit"] == pytest.approx(q_max_limit_N(P0, 300.0))
    qst = row(df, "Q_qst_N")
    assert qst["processed_value"] == pytest.approx(P0, abs=2e-4 * a)
    assert row(df, "Y_qst_N")["processed_value"] == pytest.approx(0.0, abs=1e-6)


def test_q_limit_is_90_kN_plus_q0_capped_by_speed():
    assert q_max_limit_N(78.45e3, 300.0) == pytest.approx(168.45e3)
    assert q_max_limit_N(85e3, 300.0) == pytest.approx(170e3)
    assert q_max_limit_N(85e3, 301.0) == pytest.approx(160e3)
    assert q_max_limit_N(70e3, 160.0) == pytest.approx(160e3)
    assert q_max_limit_N(120e3, 120.0) == pytest.approx(200e3)


def test_unknown_option_is_an_error():
    table, summary = synthetic_run()
    with pytest.raises(ValueError, match="unknown option"):
        assess(table, summary, "en14363", options={"cutof_hz": 30.0})
