"""Signal processing of the assessment profiles (ttbpipe.assessment.processing) against closed
forms.

* Zero-phase Butterworth: a record P0 + A1 sin(2 pi 5 t) + A2 sin(2 pi 80 t) through each
  profile's filter keeps the 5 Hz part within 1 % and scales the 80 Hz part by the filter's
  |H|^2 (forward-backward): digital low-pass of order N designed at fs (bilinear transform,
  pre-warped) |H|^2 = 1 / (1 + (tan(pi f/fs) / tan(pi fc/fs))^(2N)); band-pass (prototype order N)
  |H|^2 = 1 / (1 + ((W^2 - W_lo W_hi) / ((W_hi - W_lo) W))^(2N)), W = tan(pi f/fs)
  (Oppenheim & Schafer, Discrete-Time Signal Processing, 3rd ed., 7.3). Tolerance 0.5 % of the
  predicted attenuation (amplitudes by least squares over whole periods, 0.5 s edges dropped).
* Sliding mean over L of a sinusoid of wavelength lambda: scaled by sin(pi L/lambda)/(pi L/lambda)
  (the window mean of the sinusoid); tolerance 2e-4, above the linear-interpolation error
  (2 pi dx/lambda)^2/12 = 4e-5 at dx = 1 cm, lambda = 3 m.
* Percentile 99.85 of Gaussian noise: mu + z sigma, z = Phi^-1(0.9985) = 2.968; a sample quantile's
  standard error is sqrt(p (1 - p) / n) / phi(z) sigma (asymptotic normality of order
  statistics, e.g. David & Nagaraja, Order Statistics, 3rd ed., 10.2); tolerance 4 standard errors.
"""

import numpy as np
import pytest
from scipy import stats

from assessment_synthetic import fitted_amplitudes
from ttbpipe.assessment import en1990, en14363, gb5599
from ttbpipe.assessment.processing import (Butterworth, mean_plus_k_sigma, percentile, resample,
                                           segment_maxima, sliding_mean, sliding_mean_gain,
                                           window_rms)

DT = 1e-3


def lowpass_power(f, fc, order, fs=1.0 / DT):
    return 1.0 / (1.0 + (np.tan(np.pi * f / fs) / np.tan(np.pi * fc / fs)) ** (2 * order))


def bandpass_power(f, lo, hi, order, fs=1.0 / DT):
    w, wl, wh = (np.tan(np.pi * v / fs) for v in (f, lo, hi))
    return 1.0 / (1.0 + ((w * w - wl * wh) / ((wh - wl) * w)) ** (2 * order))


def expected_power(filt, f):
    if filt.kind == "lowpass":
        return lowpass_power(f, filt.high_hz, filt.order)
    return bandpass_power(f, filt.low_hz, filt.high_hz, filt.order)


PROFILE_FILTERS = {
    "en14363 wheel forces": en14363.force_filter(en14363.DEFAULTS),
    "gb5599 wheel forces": gb5599.force_filter(gb5599.DEFAULTS),
    "gb5599 car body": gb5599.carbody_filter(gb5599.DEFAULTS),
    "en1990 deck (f0 5.6, f3 40.4 Hz)": en1990.deck_filter(5.6, 40.4),
    "en1990 deck (f0 4, f3 20 Hz)": en1990.deck_filter(4.0, 20.0),
}


@pytest.mark.parametrize("name", list(PROFILE_FILTERS))
def test_profile_filter_passes_5hz_and_attenuates_80hz_as_its_order_predicts(name):
    filt = PROFILE_FILTERS[name]
    t = DT * np.arange(int(40.0 / DT))
    p0, a1, a2 = 70e3, 8e3, 5e3
    y = filt.apply(p0 + a1 * np.sin(2 * np.pi * 5 * t) + a2 * np.sin(2 * np.pi * 80 * t), DT)
    keep = (t >= 15.0) & (t < 25.0)             # whole periods, far from the edges (0.4 Hz high-pass)
    g5, g80 = (a / amp for a, amp in zip(fitted_amplitudes(t[keep], y[keep], [5.0, 80.0]), (a1, a2)))
    assert g5 == pytest.approx(1.0, abs=0.01)
    assert g5 == pytest.approx(expected_power(filt, 5.0), rel=1e-4)
    assert g80 == pytest.approx(expected_power(filt, 80.0), rel=5e-3)
    assert g80 < 0.05                           # and it is a strong attenuation
    # the filter's own gain function is the same closed form
    assert filt.power_gain([5.0, 80.0], DT) == pytest.approx(
        [expected_power(filt, 5.0), expected_power(filt, 80.0)], rel=1e-6)


def test_cutoff_at_nyquist_passes_the_signal_unchanged():
    x = np.random.default_rng(1).normal(size=1000)
    assert np.array_equal(Butterworth("lowpass", 480.0).apply(x, DT), x)


@pytest.mark.parametrize("wavelength", [4.0, 3.0, 1.5, 0.9])
def test_sliding_mean_scales_a_sinusoid_by_the_window_sinc(wavelength):
    dx, window, step = 0.01, 2.0, 0.5
    x = np.arange(0.0, 400.0, dx)
    k = 2 * np.pi / wavelength
    centres, means = sliding_mean(x, 1.5 * np.sin(k * x + 0.4), window, step)
    basis = np.column_stack([np.sin(k * centres + 0.4), np.cos(k * centres + 0.4)])
    coef, *_ = np.linalg.lstsq(basis, means, rcond=None)
    assert coef[0] / 1.5 == pytest.approx(sliding_mean_gain(window, wavelength), abs=2e-4)
    assert abs(coef[1]) < 2e-4                   # no phase shift: the windows are centred
    assert sliding_mean_gain(window, wavelength) == pytest.approx(
        np.sin(np.pi * window / wavelength) / (np.pi * window / wavelength), rel=1e-12)
    assert centres[0] == pytest.approx(x[0] + 1.0) and np.allclose(np.diff(centres), step)
    assert centres[-1] + 1.0 <= x[-1] + 1e-9


def test_sliding_mean_of_a_line_is_its_value_at_the_centre_and_never_exceeds_the_maximum():
    x = np.linspace(0.0, 50.0, 5001)
    centres, means = sliding_mean(x, 3.0 * x - 1.0, 2.0, 0.5)
    assert np.allclose(means, 3.0 * centres - 1.0, rtol=0, atol=1e-9)
    y = np.random.default_rng(2).normal(size=x.size)
    _, m = sliding_mean(x, y, 2.0, 0.5)
    assert m.max() <= y.max() and m.min() >= y.min()


def test_gaussian_percentile_sits_at_mean_plus_2_97_sigma_within_its_sampling_error():
    n, mu, sigma, p = 1_000_000, 5.0, 2.0, 0.9985
    z = stats.norm.ppf(p)
    assert z == pytest.approx(2.97, abs=0.005)
    se = np.sqrt(p * (1 - p) / n) / stats.norm.pdf(z) * sigma
    x = np.random.default_rng(20261201).normal(mu, sigma, n)
    assert abs(percentile(x, 99.85) - (mu + z * sigma)) < 4 * se
    assert abs(percentile(x, 0.15) - (mu - z * sigma)) < 4 * se
    assert abs(percentile(x, 50.0) - mu) < 4 * np.sqrt(0.25 / n) / stats.norm.pdf(0) * sigma


def test_segment_maxima_resample_and_window_statistics():
    x = np.round(np.arange(0.0, 10.05, 0.1), 10)       # 0 ... 10.0: five whole 2 m segments
    starts, peaks = segment_maxima(x, x.copy(), 2.0)
    assert np.allclose(starts, [0, 2, 4, 6, 8])
    assert np.allclose(peaks, [1.9, 3.9, 5.9, 7.9, 9.9])
    grid, values = resample(x, 2.0 * x, 0.25)
    assert np.allclose(values, 2.0 * grid) and grid[-1] <= x[-1]
    v = np.array([1.0, 2.0, 3.0, 4.0])
    assert mean_plus_k_sigma(v, 2.2) == pytest.approx(2.5 + 2.2 * np.sqrt(1.25))
    t = DT * np.arange(10_000)
    rms = window_rms(0.7 * np.sin(2 * np.pi * 2.0 * t), DT, 5.0)
    assert rms.shape == (2,) and np.allclose(rms, 0.7 / np.sqrt(2), rtol=1e-9)
