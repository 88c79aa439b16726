"""Sperling ride index (ttbpipe.vehicle.comfort) against its closed form."""

import numpy as np
import pytest

from ttbpipe.vehicle.comfort import sperling_index, sperling_weighting


def test_weighting_is_inverse_square_not_inverse():
    """F = 400/f^2 (vertical) and 650/f^2 (lateral) in the middle band, 0.325 f^2 / 0.8 f^2 below,
    1 above (physics.md s.4; 400/f is a common error, physics.md section 7 item 10). Exact."""
    assert sperling_weighting(np.array([10.0]), "vertical")[0] == pytest.approx(4.0)
    assert sperling_weighting(np.array([2.0]), "vertical")[0] == pytest.approx(1.3)
    assert sperling_weighting(np.array([30.0]), "vertical")[0] == 1.0
    assert sperling_weighting(np.array([10.0]), "lateral")[0] == pytest.approx(6.5)
    assert sperling_weighting(np.array([2.0]), "lateral")[0] == pytest.approx(3.2)
    # near-continuity at the breakpoints (the standard's own rounding: within 3 %)
    assert sperling_weighting(np.array([5.9 - 1e-9]), "vertical")[0] == pytest.approx(
        sperling_weighting(np.array([5.9]), "vertical")[0], rel=0.03)


@pytest.mark.parametrize("direction, freq, amp", [("vertical", 2.0, 0.3), ("vertical", 8.0, 0.5),
                                                  ("lateral", 1.4, 0.2), ("lateral", 12.0, 0.4)])
def test_pure_sinusoid_closed_form(direction, freq, amp):
    """A sinusoid of amplitude A (m/s^2) at f (on a DFT bin) gives W = 3.57 (A^3 F(f)/f)^0.1
    (physics.md s.4). Relative tolerance 1e-9; two 5 s windows give the same value."""
    dt = 0.005
    t = np.arange(int(10.0 / dt)) * dt
    acc = amp * np.sin(2 * np.pi * freq * t + 0.3)
    w, per_window = sperling_index(acc, dt, direction)
    ff = sperling_weighting(np.array([freq]), direction)[0]
    expected = 3.57 * (amp ** 3 * ff / freq) ** 0.1
    assert w == pytest.approx(expected, rel=1e-9)
    assert per_window.size == 2 and np.allclose(per_window, expected, rtol=1e-9)


def test_two_tones_combine_as_tenth_power_sum():
    """W = (W1^10 + W2^10)^0.1 for two components (physics.md s.4). Tolerance 1e-9."""
    dt = 0.005
    t = np.arange(int(5.0 / dt)) * dt
    a1, f1, a2, f2 = 0.2, 1.0, 0.3, 10.0
    acc = a1 * np.cos(2 * np.pi * f1 * t) + a2 * np.cos(2 * np.pi * f2 * t)
    w, _ = sperling_index(acc, dt, "vertical")
    w1 = 3.57 * (a1 ** 3 * sperling_weighting(np.array([f1]), "vertical")[0] / f1) ** 0.1
    w2 = 3.57 * (a2 ** 3 * sperling_weighting(np.array([f2]), "vertical")[0] / f2) ** 0.1
    assert w == pytest.approx((w1 ** 10 + w2 ** 10) ** 0.1, rel=1e-9)


def test_rejects_nan():
    with pytest.raises(ValueError, match="NaN"):
        sperling_index(np.array([0.0, np.nan] * 1000), 0.01, "vertical")
