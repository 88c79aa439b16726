"""EN 12299 profile (ttbpipe.assessment.en12299): weighting filters and N_MV against closed forms.

* Weightings: the analog transfer functions of ISO 2631-1 form with EN 12299's parameters
  (module docstring; written out again here) and the digital filters (bilinear transform at
  1 kHz) agree within 0.1 % up to 16 Hz (frequency warping tan(pi f/fs) fs/pi - f < 0.1 %).
  Wd is the acceleration-velocity transition at 2 Hz: above it |Wd| -> f4^2/(f3 f) = 2/f
  (within 1 % at 16 Hz, where the 100 Hz band limit still costs 0.5 %).
* N_MV of sinusoids: a_Z = A sin(2 pi f t), a_Y = B sin(2 pi g t) give 5 s r.m.s. values
  A |Wb(f)| / sqrt(2) and B |Wd(g)| / sqrt(2), so N_MV = 6 sqrt(B^2 |Wd(g)|^2 + A^2 |Wb(f)|^2)
  / sqrt(2); tolerance 2e-3 (the digital gain, 0.1 %, and the causal filter's start-up, which
  only the first of 25 windows holds: the 95th percentile interpolates between the 23rd and
  24th of the sorted 25 values, all in steady state).
"""

import math

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from ttbpipe.assessment import assess
from ttbpipe.assessment.en12299 import WB, WC, WD, WP, mean_comfort

DT = 1e-3
PARAMS = {  # f1, f2, f3, f4, Q4, f5, Q5, f6, Q6, K (EN 12299 as in PyRidy / comfpy)
    "Wb": (0.4, 100, 16, 16, 0.63, 2.5, 0.8, 4, 0.8, 0.4),
    "Wc": (0.4, 100, 8, 8, 0.63, None, None, None, None, 1.0),
    "Wd": (0.4, 100, 2, 2, 0.63, None, None, None, None, 1.0),
    "Wp": (None, 100, 2, 2, 0.63, None, None, None, None, 1.0),
}


def closed_form_gain(name, f):
    f1, f2, f3, f4, q4, f5, q5, f6, q6, k = PARAMS[name]
    s = 2j * math.pi * np.asarray(f, dtype=float)
    w = lambda v: 2 * math.pi * v  # noqa: E731
    q1 = 1 / math.sqrt(2)
    h = w(f2) ** 2 / (s * s + w(f2) * s / q1 + w(f2) ** 2)
    if f1 is not None:
        h = h * s * s / (s * s + w(f1) * s / q1 + w(f1) ** 2)
    h = h * (1 + s / w(f3)) / (1 + s / (q4 * w(f4)) + (s / w(f4)) ** 2)
    if f5 is not None:
        h = h * (1 + s / (q5 * w(f5)) + (s / w(f5)) ** 2) / (1 + s / (q6 * w(f6)) + (s / w(f6)) ** 2)
    return k * np.abs(h)


@pytest.mark.parametrize("weighting", [WB, WC, WD, WP], ids=lambda w: w.name)
def test_weighting_filters_match_their_transfer_functions(weighting):
    f = np.array([0.5, 1.0, 2.0, 4.0, 8.0, 12.5, 16.0])
    expected = closed_form_gain(weighting.name, f)
    assert weighting.analog_gain(f) == pytest.approx(expected, rel=1e-12)
    assert weighting.digital_gain(f, DT) == pytest.approx(expected, rel=1e-3)


def test_wd_falls_as_velocity_above_its_transition():
    assert WD.analog_gain(np.array([16.0]))[0] == pytest.approx(2.0 / 16.0, rel=0.01)
    assert WD.analog_gain(np.array([1.0]))[0] == pytest.approx(1.0, abs=0.02)


def test_mean_comfort_of_sinusoids_is_the_weighted_rms():
    t = DT * np.arange(int(125.0 / DT))
    a, f, b, g = 0.4, 6.0, 0.25, 1.5
    n_mv, parts = mean_comfort(b * np.sin(2 * np.pi * g * t), a * np.sin(2 * np.pi * f * t), DT)
    assert parts["n_windows"] == 25
    wb, wd = closed_form_gain("Wb", [f])[0], closed_form_gain("Wd", [g])[0]
    assert parts["a_ZP95"] == pytest.approx(a * wb / math.sqrt(2), rel=2e-3)
    assert parts["a_YP95"] == pytest.approx(b * wd / math.sqrt(2), rel=2e-3)
    assert n_mv == pytest.approx(6 * math.sqrt((a * wb) ** 2 + (b * wd) ** 2) / math.sqrt(2), rel=2e-3)


def test_profile_row_on_a_short_record_says_it_used_one_window():
    table, summary = synthetic_run({
        "car1_body_front_az_m_s2": lambda t: 0.3 * np.sin(2 * np.pi * 4.0 * t),
        "car1_body_centre_az_m_s2": lambda t: 0.1 * np.sin(2 * np.pi * 4.0 * t)})
    df = assess(table, summary, "en12299")
    assert list(df["index"]) == ["N_MV"]
    r = df.iloc[0]
    assert r["location"] == "car1_front" and r["category"] == "grade" and r["limit"] == 1.0
    assert "1 window(s) from a 4.00 s record" in r["notes"]
    # one window of the whole record: N_MV = 6 x its weighted r.m.s.
    rms = np.sqrt(np.mean(WB.apply(table["car1_body_front_az_m_s2"].to_numpy(), DT) ** 2))
    assert r["processed_value"] == pytest.approx(6 * rms, rel=1e-12)


def test_a_weighting_is_designed_once_per_rate_and_handed_out_as_a_copy():
    """The cached sections equal a fresh design (the undecorated function) at each rate; a
    caller writing into its copy does not change the next caller's."""
    from ttbpipe.assessment.en12299 import _weighting_design

    first = WB.sos(1000.0)
    np.testing.assert_array_equal(first, _weighting_design.__wrapped__(WB, 1000.0))
    first[:] = 0.0
    np.testing.assert_array_equal(WB.sos(1000.0), _weighting_design.__wrapped__(WB, 1000.0))
    assert not np.array_equal(WB.sos(500.0), WB.sos(1000.0))
    assert not np.array_equal(WD.sos(1000.0), WB.sos(1000.0))
