"""Random track-irregularity profiles from a one-sided PSD, by inverse FFT.

Method (spectral representation, physics.md §2): a one-sided PSD G(n) in mm²/(1/m) becomes

    z(x) = Σ_k sqrt(2·G(n_k)·Δn) · cos(2π n_k x + φ_k),   φ_k ~ U(0, 2π) independent,

over the discrete frequencies n_k = k·Δn inside the wavelength band, so that the variance is
exactly Σ G(n_k)Δn (the Riemann sum of ∫G dn over the band). The sum is evaluated with one
inverse real FFT. **numpy ``irfft`` convention** (physics.md §2, [C, checked]): for a grid of N
points at spacing Δx, Δn = 1/(N·Δx) and

    X_k = (N/2) · sqrt(2·G(n_k)·Δn) · exp(i φ_k)  for n_k in the band,  X_k = 0 otherwise,
    z = numpy.fft.irfft(X, N).

(``irfft`` computes z_j = (1/N)[X_0 + 2 Re Σ_{0<k<N/2} X_k e^{2πi kj/N} + X_{N/2}(-1)^j], hence
the factor N/2.) The mean (k = 0) and, for even N, the Nyquist bin k = N/2 are always zero: a
Nyquist term would be a real cosine with half the intended variance.

The series repeats with period N·Δx = 1/Δn; N is chosen >= the number of output samples, so the
profile never repeats over its length (physics.md §7.5). The amplitudes are deterministic and
only the phases are random, so every realisation has the target band variance (the realised
RMS over a profile shorter than the FFT period differs from it by O(1/sqrt(number of waves))).

``amplitudes="gaussian"`` (:func:`gaussian_channel_from_normals`) replaces the random phases by
random Fourier coefficients X_k = (N/2)·sqrt(G Δn)·(a_k + i b_k), a_k, b_k ~ N(0, 1): the same
mean power per frequency, but a stationary Gaussian process whose one-realisation variance is
random (docs/irregularity.md, "Gaussian representation"). The random-phase form stays the
default (the seed paper's TIPM synthesis). Configurations choose it with the key ``amplitudes``
(:data:`AMPLITUDES`): a run's ``irregularity:`` section, the study's ``simulation.irregularity``
(the mean-spectrum profile) and ``tipm.profiles`` (the TIPM, forecast and Monte Carlo profiles).
"""

from __future__ import annotations

import logging
from typing import Callable, Mapping

import numpy as np
import pandas as pd
from scipy import fft as sp_fft

from ..channels import SPECTRAL_CHANNELS
from .spectra import TrackSpectrum, get_spectrum

__all__ = ["synthesize_channel", "synthesize_profiles", "synthesize_from_psd_table",
           "fft_grid", "psd_table_interpolator", "gaussian_channel_from_normals",
           "n_gaussian_coefficients", "gaussian_band_frequencies", "AMPLITUDES",
           "DEFAULT_AMPLITUDES", "check_amplitudes"]

log = logging.getLogger(__name__)


def fft_grid(length_m: float, dx_m: float) -> tuple[int, int]:
    """(number of output samples, FFT size) for a profile of ``length_m`` at ``dx_m``.

    The output covers chainage 0..length_m inclusive: ``floor(length_m/dx_m + 1e-9) + 1``
    samples. The FFT size is the next even FFT-friendly size >= that, so 1/Δn = N·Δx exceeds the
    profile length and the profile does not repeat.
    """
    if not (np.isfinite(length_m) and length_m > 0):
        raise ValueError(f"profile length must be > 0 m, got {length_m!r}")
    if not (np.isfinite(dx_m) and dx_m > 0):
        raise ValueError(f"sample spacing dx must be > 0 m, got {dx_m!r}")
    n_samples = int(np.floor(length_m / dx_m + 1e-9)) + 1
    if n_samples < 2:
        raise ValueError(f"profile length {length_m} m is shorter than one sample spacing {dx_m} m")
    n_fft = sp_fft.next_fast_len(n_samples, real=True)
    n_fft += n_fft % 2  # even: a well-defined Nyquist bin that we zero
    return n_samples, n_fft


def _band_mask(frequencies_per_m: np.ndarray, wavelength_band_m: tuple[float, float]) -> np.ndarray:
    lam_min, lam_max = (float(v) for v in wavelength_band_m)
    if not 0 < lam_min < lam_max:
        raise ValueError(f"wavelength band must be 0 < min < max (m), got {wavelength_band_m}")
    # relative slack so that band edges that fall on a grid frequency are included
    return ((frequencies_per_m >= (1.0 / lam_max) * (1 - 1e-12))
            & (frequencies_per_m <= (1.0 / lam_min) * (1 + 1e-12)))


def _spectral_grid(length_m: float, dx_m: float, wavelength_band_m: tuple[float, float]
                   ) -> tuple[int, int, np.ndarray, np.ndarray]:
    """(output samples, FFT size, FFT frequencies (1/m), in-band mask) of one channel.

    The mask excludes the mean and Nyquist bins (module docstring); shared by the random-phase
    and the Gaussian representations so that both use the same frequencies.
    """
    n_samples, n_fft = fft_grid(length_m, dx_m)
    if wavelength_band_m[0] <= 2.0 * dx_m:
        raise ValueError(f"shortest wavelength {wavelength_band_m[0]} m must exceed 2·dx = "
                         f"{2 * dx_m} m (Nyquist); refine dx or shorten the band")
    frequencies = np.arange(n_fft // 2 + 1) / (n_fft * dx_m)
    in_band = _band_mask(frequencies, wavelength_band_m)
    in_band[0] = in_band[-1] = False  # mean and Nyquist bins stay zero (module docstring)
    if not np.any(in_band):
        raise ValueError(f"no FFT frequency inside the band {wavelength_band_m} m for a "
                         f"{length_m} m profile at dx {dx_m} m; lengthen the profile")
    return n_samples, n_fft, frequencies, in_band


def _band_psd(psd_mm2_m: Callable[[np.ndarray], np.ndarray], frequencies: np.ndarray) -> np.ndarray:
    psd = np.asarray(psd_mm2_m(frequencies), dtype=float)
    if psd.shape != frequencies.shape or not np.all(np.isfinite(psd)) or np.any(psd < 0):
        raise ValueError("the PSD callable must return finite, non-negative values of the same "
                         "shape as its argument")
    return psd


#: Representations of the profile (module docstring): deterministic amplitudes with random
#: phases, or random Gaussian Fourier coefficients. The configuration key ``amplitudes`` of a
#: run's ``irregularity:`` section and of the study's ``simulation.irregularity`` and
#: ``tipm.profiles`` takes these names (the schemas' enums are tested against this tuple).
AMPLITUDES = ("random_phase", "gaussian")
#: The default: the seed paper's TIPM synthesis (random phases), unchanged bit for bit.
DEFAULT_AMPLITUDES = AMPLITUDES[0]


def check_amplitudes(amplitudes: str, where: str = "amplitudes") -> str:
    """``amplitudes`` if it is one of :data:`AMPLITUDES`, else ValueError naming ``where`` (the
    key) and the choices."""
    if amplitudes not in AMPLITUDES:
        raise ValueError(f"{where}: {amplitudes!r}; expected one of {AMPLITUDES}")
    return amplitudes


def synthesize_channel(psd_mm2_m: Callable[[np.ndarray], np.ndarray], length_m: float,
                       dx_m: float, rng: np.random.Generator | int | None,
                       wavelength_band_m: tuple[float, float] = (2.0, 200.0), *,
                       amplitudes: str = DEFAULT_AMPLITUDES) -> np.ndarray:
    """One random profile in mm, samples at chainage 0, dx, ..., covering ``length_m``.

    Parameters
    ----------
    psd_mm2_m
        One-sided PSD, ``n (1/m, ndarray) -> G (mm²/(1/m), ndarray)``; called only with
        frequencies inside ``wavelength_band_m`` (e.g. ``spectrum.as_function(channel)``).
    length_m, dx_m
        Profile length and sample spacing in m.
    rng
        ``numpy.random.Generator`` (or a seed for ``numpy.random.default_rng``). Random phase:
        exactly N/2 + 1 uniform phases are drawn from it, N = FFT size, whatever the band.
        Gaussian: exactly :func:`n_gaussian_coefficients` standard normals.
    wavelength_band_m
        (shortest, longest) wavelength in m kept; frequencies 1/λmax <= n <= 1/λmin. The
        shortest wavelength must exceed 2·dx (Nyquist).
    amplitudes
        ``"random_phase"`` (default; deterministic amplitudes, the seed paper's method) or
        ``"gaussian"`` (random Fourier coefficients: a stationary Gaussian profile,
        :func:`gaussian_channel_from_normals`).

    Convention: module docstring (numpy ``irfft``, X_k = (N/2)·sqrt(2 G Δn)·e^{iφ}).
    """
    check_amplitudes(amplitudes)
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    if amplitudes == "gaussian":
        normals = rng.standard_normal(n_gaussian_coefficients(length_m, dx_m, wavelength_band_m))
        return gaussian_channel_from_normals(psd_mm2_m, length_m, dx_m, normals,
                                             wavelength_band_m)
    n_samples, n_fft, frequencies, in_band = _spectral_grid(length_m, dx_m, wavelength_band_m)
    phases = rng.uniform(0.0, 2.0 * np.pi, size=frequencies.size)
    delta_n = 1.0 / (n_fft * dx_m)
    psd = _band_psd(psd_mm2_m, frequencies[in_band])
    spectrum = np.zeros(frequencies.size, dtype=complex)
    spectrum[in_band] = (0.5 * n_fft) * np.sqrt(2.0 * psd * delta_n) * np.exp(1j * phases[in_band])
    return sp_fft.irfft(spectrum, n_fft)[:n_samples]


def gaussian_band_frequencies(length_m: float, dx_m: float,
                              wavelength_band_m: tuple[float, float] = (2.0, 200.0)) -> np.ndarray:
    """The FFT frequencies n_k (1/m) inside the band that carry a Gaussian coefficient pair."""
    _, _, frequencies, in_band = _spectral_grid(length_m, dx_m, wavelength_band_m)
    return frequencies[in_band]


def n_gaussian_coefficients(length_m: float, dx_m: float,
                            wavelength_band_m: tuple[float, float] = (2.0, 200.0)) -> int:
    """Standard normals one Gaussian channel needs: 2 per in-band frequency (a_k, b_k)."""
    return 2 * int(gaussian_band_frequencies(length_m, dx_m, wavelength_band_m).size)


def gaussian_channel_from_normals(psd_mm2_m: Callable[[np.ndarray], np.ndarray],
                                  length_m: float, dx_m: float, normals: np.ndarray,
                                  wavelength_band_m: tuple[float, float] = (2.0, 200.0)
                                  ) -> np.ndarray:
    """Gaussian profile in mm from explicit standard normals (random Fourier coefficients).

    Spectral representation with random amplitudes (Shinozuka & Deodatis 1991, Appl. Mech. Rev.
    44:191, eq. 40 form with Gaussian coefficients):

        z(x) = Σ_k sqrt(G(n_k)·Δn) · (a_k cos 2π n_k x − b_k sin 2π n_k x),
        a_k, b_k ~ N(0, 1) independent,

    i.e. X_k = (N/2)·sqrt(G(n_k)·Δn)·(a_k + i b_k) in the numpy ``irfft`` convention of the
    module docstring. E|X_k|² = (N/2)²·2·G Δn, the random-phase |X_k|² exactly, so both forms
    have the variance Σ G(n_k)Δn; but here z is a linear map of Gaussian variables, hence a
    stationary Gaussian process for any number of frequencies, and the variance of one
    realisation is random (chi-square with 2 degrees of freedom per frequency). The random-phase
    sum is Gaussian only as the number of frequencies grows (Grigoriu 1993, J. Eng. Mech.
    119:328): its one-realisation band variance is fixed.

    ``normals``: shape ``(n_gaussian_coefficients(...),)``; the first half are a_k, the second
    half b_k, both in increasing frequency (:func:`gaussian_band_frequencies`). All zeros give a
    zero profile. Pure: no random state.
    """
    n_samples, n_fft, frequencies, in_band = _spectral_grid(length_m, dx_m, wavelength_band_m)
    n_band = int(in_band.sum())
    normals = np.asarray(normals, dtype=float)
    if normals.shape != (2 * n_band,):
        raise ValueError(f"normals: shape {normals.shape}, expected ({2 * n_band},) = 2 × "
                         f"{n_band} in-band frequencies for {length_m} m at dx {dx_m} m, band "
                         f"{tuple(wavelength_band_m)} m")
    if not np.all(np.isfinite(normals)):
        raise ValueError("normals must be finite")
    delta_n = 1.0 / (n_fft * dx_m)
    psd = _band_psd(psd_mm2_m, frequencies[in_band])
    spectrum = np.zeros(frequencies.size, dtype=complex)
    spectrum[in_band] = ((0.5 * n_fft) * np.sqrt(psd * delta_n)
                         * (normals[:n_band] + 1j * normals[n_band:]))
    return sp_fft.irfft(spectrum, n_fft)[:n_samples]


def synthesize_profiles(spectrum: TrackSpectrum | str, length_m: float, dx_m: float = 0.25,
                        seed: int | None = None, rng: np.random.Generator | None = None,
                        wavelength_band_m: tuple[float, float] | None = None, *,
                        amplitudes: str = DEFAULT_AMPLITUDES) -> pd.DataFrame:
    """Four independent channels of a standard spectrum, as a table.

    Columns ``chainage_m, vertical_mm, alignment_mm, cross_level_mm, gauge_mm``; chainage from 0
    to ``length_m`` at ``dx_m``. Randomness: ``rng`` if given, else ``default_rng(seed)``; the
    channels draw from it in the order of :data:`ttbpipe.channels.SPECTRAL_CHANNELS`.
    ``wavelength_band_m=None`` uses the spectrum's valid band (2-200 m for TB/T 3352).
    ``amplitudes``: :func:`synthesize_channel`. Rail inputs:
    :func:`ttbpipe.channels.rails_from_spectral`.
    """
    spectrum = get_spectrum(spectrum) if isinstance(spectrum, str) else spectrum
    if rng is None:
        rng = np.random.default_rng(seed)
    elif seed is not None:
        raise ValueError("pass either seed or rng, not both")
    band = spectrum.valid_wavelength_band_m if wavelength_band_m is None else tuple(wavelength_band_m)
    columns: dict[str, np.ndarray] = {}
    for channel in SPECTRAL_CHANNELS:
        columns[f"{channel}_mm"] = synthesize_channel(spectrum.as_function(channel), length_m, dx_m,
                                                      rng, band, amplitudes=amplitudes)
    n_samples = next(iter(columns.values())).size
    return pd.DataFrame({"chainage_m": np.arange(n_samples) * float(dx_m), **columns})


def psd_table_interpolator(spatial_frequency_per_m, psd_mm2_m, *,
                           label: str = "PSD table") -> Callable[[np.ndarray], np.ndarray]:
    """Log-log linear interpolation of a tabulated one-sided PSD, ``n -> G(n)``.

    Rows with n <= 0 (a Welch zero-frequency bin) are ignored. The table must be finite and
    strictly positive; the returned callable raises ``ValueError`` for frequencies outside the
    tabulated range (no extrapolation).
    """
    n = np.asarray(spatial_frequency_per_m, dtype=float)
    g = np.asarray(psd_mm2_m, dtype=float)
    if n.shape != g.shape or n.ndim != 1:
        raise ValueError(f"{label}: frequency and PSD arrays must be 1-D of equal length")
    keep = n > 0
    n, g = n[keep], g[keep]
    order = np.argsort(n)
    n, g = n[order], g[order]
    if n.size < 2 or np.any(np.diff(n) <= 0):
        raise ValueError(f"{label}: need at least two distinct positive frequencies")
    if not np.all(np.isfinite(g)) or np.any(g <= 0):
        bad = np.flatnonzero(~np.isfinite(g) | (g <= 0))
        raise ValueError(f"{label}: PSD must be finite and > 0 for log-log interpolation; "
                         f"{bad.size} bad values, first at n = {n[bad[0]]:g} 1/m")
    log_n, log_g = np.log(n), np.log(g)

    def interpolate(freq: np.ndarray) -> np.ndarray:
        freq = np.asarray(freq, dtype=float)
        if np.any(freq < n[0] * (1 - 1e-12)) or np.any(freq > n[-1] * (1 + 1e-12)):
            raise ValueError(f"{label}: frequencies {freq.min():g}-{freq.max():g} 1/m leave the "
                             f"tabulated range {n[0]:g}-{n[-1]:g} 1/m; narrow the wavelength band")
        return np.exp(np.interp(np.log(freq), log_n, log_g))

    return interpolate


def synthesize_from_psd_table(spatial_frequency_per_m, psd_by_channel: Mapping[str, np.ndarray],
                              length_m: float, dx_m: float,
                              rng: np.random.Generator | int | None,
                              wavelength_band_m: tuple[float, float] = (2.0, 200.0), *,
                              amplitudes: str = DEFAULT_AMPLITUDES) -> pd.DataFrame:
    """Profiles from tabulated one-sided PSDs (estimated, selected or forecast spectra).

    ``psd_by_channel`` maps channel names (any subset of the four spectral channels) to PSD
    values in mm²/(1/m) on the common ``spatial_frequency_per_m`` grid (1/m). Between table
    points the PSD is interpolated linearly in log-log; the band must lie inside the table.
    Returns ``chainage_m`` and one ``<channel>_mm`` column per given channel, channels
    synthesised independently in :data:`SPECTRAL_CHANNELS` order (``amplitudes``:
    :func:`synthesize_channel`).
    """
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    unknown = set(psd_by_channel) - set(SPECTRAL_CHANNELS)
    if unknown:
        raise ValueError(f"unknown channels {sorted(unknown)}; expected {SPECTRAL_CHANNELS}")
    if not psd_by_channel:
        raise ValueError("psd_by_channel is empty")
    columns: dict[str, np.ndarray] = {}
    for channel in SPECTRAL_CHANNELS:
        if channel not in psd_by_channel:
            continue
        interpolator = psd_table_interpolator(spatial_frequency_per_m, psd_by_channel[channel],
                                              label=f"PSD table, channel {channel}")
        columns[f"{channel}_mm"] = synthesize_channel(interpolator, length_m, dx_m, rng,
                                                      wavelength_band_m, amplitudes=amplitudes)
    n_samples = next(iter(columns.values())).size
    return pd.DataFrame({"chainage_m": np.arange(n_samples) * float(dx_m), **columns})
