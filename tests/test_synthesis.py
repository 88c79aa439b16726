"""Space-domain synthesis of irregularity profiles (ttbpipe.irregularity.synthesis).

References: physics.md §2 (spectral representation, numpy irfft convention, Welch estimate of a
synthetic TB/T profile within 1-4 %), the TB/T 3352 band RMS values of physics.md §1a.
"""

import numpy as np
import pytest
from scipy import signal

from ttbpipe.channels import SPECTRAL_CHANNELS
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.irregularity.synthesis import (fft_grid, synthesize_channel,
                                            synthesize_from_psd_table, synthesize_profiles)

COLUMNS = ["chainage_m", "vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm"]


@pytest.fixture(scope="module")
def long_tbt_profiles():
    """One 200 km TB/T 3352 realisation at 0.25 m (0.3 s)."""
    return synthesize_profiles("tbt3352", 200_000.0, 0.25, seed=20261121)


def test_irfft_convention_against_direct_cosine_sum():
    """The IFFT result equals the slow, obviously correct sum
    z(x) = Σ sqrt(2 G(n_k) Δn) cos(2π n_k x + φ_k) with the same phases (physics.md §2);
    tolerance 1e-10 mm absolute (round-off)."""
    dx, length = 0.5, 300.0
    band = (2.0, 200.0)
    spectrum = get_spectrum("tbt3352")
    z = synthesize_channel(spectrum.as_function("vertical"), length, dx, np.random.default_rng(7), band)
    n_samples, n_fft = fft_grid(length, dx)
    phases = np.random.default_rng(7).uniform(0.0, 2 * np.pi, size=n_fft // 2 + 1)
    delta_n = 1.0 / (n_fft * dx)
    k = np.arange(n_fft // 2 + 1)
    n_k = k * delta_n
    in_band = (n_k >= 1 / band[1]) & (n_k <= 1 / band[0]) & (k > 0) & (k < n_fft // 2)
    x = np.arange(n_samples) * dx
    amplitude = np.sqrt(2 * spectrum.psd_mm2_m("vertical", n_k[in_band]) * delta_n)
    direct = (amplitude[:, None] * np.cos(2 * np.pi * n_k[in_band][:, None] * x[None, :]
                                          + phases[in_band][:, None])).sum(axis=0)
    assert z.shape == (n_samples,)
    np.testing.assert_allclose(z, direct, rtol=0, atol=1e-10)


def test_full_period_variance_is_exact():
    """Over one full FFT period the realised variance is exactly Σ G(n_k) Δn (physics.md §2,
    "the realised σ equals the theory exactly"); tolerance 1e-10 relative."""
    dx = 0.25
    n_fft = 8192
    length = (n_fft - 1) * dx
    assert fft_grid(length, dx) == (n_fft, n_fft)
    spectrum = get_spectrum("tbt3352")
    z = synthesize_channel(spectrum.as_function("gauge"), length, dx, 3, (2.0, 200.0))
    delta_n = 1.0 / (n_fft * dx)
    n_k = np.arange(1, n_fft // 2) * delta_n
    n_k = n_k[(n_k >= 1 / 200) & (n_k <= 0.5)]
    expected = np.sum(spectrum.psd_mm2_m("gauge", n_k) * delta_n)
    assert np.mean(z) == pytest.approx(0.0, abs=1e-12)
    assert np.mean(z ** 2) == pytest.approx(expected, rel=1e-10)


def test_no_periodic_repetition():
    """1/Δn = N·Δx >= profile length for awkward lengths (physics.md §7.5)."""
    for length, dx in [(200_000.0, 0.25), (1234.5, 0.25), (999.9, 0.3), (10.0, 0.25)]:
        n_samples, n_fft = fft_grid(length, dx)
        assert n_fft >= n_samples and n_fft % 2 == 0
        assert n_fft * dx >= length
        assert (n_samples - 1) * dx <= length + 1e-9 < n_samples * dx


def test_profiles_table_and_rms(long_tbt_profiles):
    """200 km TB/T profile: columns, chainage, and RMS within 2 % of the band RMS over 2-200 m
    (physics.md §1a: 1.220, 0.668, 0.524, 0.344 mm). Tolerance 2 % (brief); the deterministic
    amplitudes leave only the truncation of the FFT period as an error source."""
    df = long_tbt_profiles
    assert list(df.columns) == COLUMNS
    assert len(df) == 800_001
    np.testing.assert_allclose(df["chainage_m"].to_numpy()[[0, 1, -1]], [0.0, 0.25, 200_000.0])
    for channel, expected in zip(SPECTRAL_CHANNELS, (1.220, 0.668, 0.524, 0.344)):
        rms = np.sqrt(np.mean(df[f"{channel}_mm"].to_numpy() ** 2))
        assert rms == pytest.approx(expected, rel=0.02), channel


def test_welch_of_synthetic_matches_target(long_tbt_profiles):
    """Welch estimate (scipy.signal.welch, Hann, 1024 m segments, 50 % overlap, linear detrend,
    density) of a 200 km synthetic profile vs the target PSD, averaged over the bins of six
    log-spaced bands over 2-200 m: within 10 % (brief; physics.md §2 reports 1-4 %)."""
    spectrum = get_spectrum("tbt3352")
    edges = np.geomspace(1 / 200, 1 / 2, 7)
    nperseg = 4096
    for channel in SPECTRAL_CHANNELS:
        f, psd = signal.welch(long_tbt_profiles[f"{channel}_mm"].to_numpy(), fs=4.0,
                              window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                              detrend="linear", scaling="density")
        for lo, hi in zip(edges[:-1], edges[1:]):
            sel = (f >= lo) & (f < hi)
            ratio = psd[sel].mean() / spectrum.psd_mm2_m(channel, f[sel]).mean()
            assert ratio == pytest.approx(1.0, rel=0.10), (channel, lo, hi, ratio)


def test_reproducible_from_seed_and_differs_across_seeds():
    """Same seed -> identical profiles; a Generator with that seed gives the same; another seed
    gives a different realisation (correlation well below 1)."""
    a = synthesize_profiles("german_low", 2000.0, 0.25, seed=11)
    b = synthesize_profiles("german_low", 2000.0, 0.25, seed=11)
    c = synthesize_profiles("german_low", 2000.0, 0.25, rng=np.random.default_rng(11))
    d = synthesize_profiles("german_low", 2000.0, 0.25, seed=12)
    assert a.equals(b) and a.equals(c)
    for column in COLUMNS[1:]:
        assert abs(np.corrcoef(a[column], d[column])[0, 1]) < 0.5
    # channels are independent draws, not copies
    assert abs(np.corrcoef(a["vertical_mm"], a["alignment_mm"])[0, 1]) < 0.5
    with pytest.raises(ValueError, match="either seed or rng"):
        synthesize_profiles("tbt3352", 100.0, seed=1, rng=np.random.default_rng(1))


def test_default_band_is_valid_band():
    """wavelength_band_m=None uses the spectrum's valid band; the PSD is never evaluated outside
    it (German: 3-150 m, which raises if exceeded without extrapolate)."""
    df = synthesize_profiles("german_high", 5000.0, 0.25, seed=1)
    spectrum = get_spectrum("german_high")
    rms = np.sqrt(np.mean(df["alignment_mm"] ** 2))
    # 5 km realisation: ~ 1/sqrt(number of waves) scatter on the RMS; 10 % is loose but can fail
    assert rms == pytest.approx(spectrum.band_rms_mm("alignment", (3.0, 150.0)), rel=0.10)
    with pytest.raises(ValueError, match="outside the valid band"):
        synthesize_profiles("german_high", 1000.0, 0.25, seed=1, wavelength_band_m=(2.0, 200.0))


def test_from_psd_table_reproduces_spectrum():
    """Tabulated TB/T PSD on a log grid (200 points) -> synthesised 200 km profiles whose RMS is
    within 2 % of the standard's band RMS (log-log interpolation of a piecewise power law is
    exact inside each piece)."""
    spectrum = get_spectrum("tbt3352")
    n = np.geomspace(0.005, 0.5, 200)
    table = {channel: spectrum.psd_mm2_m(channel, n) for channel in SPECTRAL_CHANNELS}
    df = synthesize_from_psd_table(n, table, 200_000.0, 0.25, np.random.default_rng(2))
    assert list(df.columns) == COLUMNS
    for channel in SPECTRAL_CHANNELS:
        rms = np.sqrt(np.mean(df[f"{channel}_mm"] ** 2))
        assert rms == pytest.approx(spectrum.band_rms_mm(channel), rel=0.02), channel


def test_from_psd_table_errors():
    """Bad tables fail clearly: band outside the table, non-positive PSD, unknown channel."""
    n = np.geomspace(0.01, 0.5, 20)
    good = np.ones_like(n)
    with pytest.raises(ValueError, match="leave the tabulated range"):
        synthesize_from_psd_table(n, {"vertical": good}, 1000.0, 0.25, 1, (2.0, 200.0))
    bad = good.copy()
    bad[3] = 0.0
    with pytest.raises(ValueError, match="finite and > 0"):
        synthesize_from_psd_table(n, {"vertical": bad}, 1000.0, 0.25, 1, (2.0, 50.0))
    with pytest.raises(ValueError, match="unknown channels"):
        synthesize_from_psd_table(n, {"twist": good}, 1000.0, 0.25, 1, (2.0, 50.0))
    # a Welch zero-frequency row is ignored, a subset of channels is allowed
    df = synthesize_from_psd_table(np.r_[0.0, n], {"gauge": np.r_[5.0, good]}, 1000.0, 0.25, 1,
                                   (2.0, 50.0))
    assert list(df.columns) == ["chainage_m", "gauge_mm"]


def test_input_errors():
    """Nyquist, empty band and bad lengths raise ValueError naming the remedy."""
    f = get_spectrum("tbt3352").as_function("vertical")
    with pytest.raises(ValueError, match="Nyquist"):
        synthesize_channel(f, 1000.0, 1.0, 1, (2.0, 200.0))
    with pytest.raises(ValueError, match="lengthen the profile"):
        synthesize_channel(f, 20.0, 0.25, 1, (100.0, 200.0))
    with pytest.raises(ValueError, match="length must be > 0"):
        synthesize_channel(f, -5.0, 0.25, 1)
