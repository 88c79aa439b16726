"""Gaussian irregularity profiles as an explicit function of independent standard normals.

A profile of the four spectral channels is the image of a vector u ~ N(0, I) (the
standard-normal space of rare-event methods, docs/irregularity.md "Gaussian representation"):

* **Fourier coefficients.** Each channel is the Gaussian spectral representation of its PSD
  G_c(n) (:func:`~ttbpipe.irregularity.synthesis.gaussian_channel_from_normals`; Shinozuka &
  Deodatis 1991, Appl. Mech. Rev. 44:191): 2 normals per in-band FFT frequency.
* **Spectral level** (optional). With per-frequency distributions of the PSD ordinates across
  sections (lognormal or gamma, :func:`ttbpipe.tipm.distribution.fit_ordinate_distributions`,
  seed paper §3.2 step 3) the PSD of the sample is itself random:

      G_c(n_j) = F_{c,j}^{-1}(Φ(v_{c,b(j)})),

  one standard normal v per channel and level band b (by default one band: the whole
  spectrum), or, with a score correlation ρ < 1 between frequencies,

      G_c(n_j) = F_{c,j}^{-1}(Φ(sqrt(ρ)·v_{c,b(j)} + sqrt(1 − ρ)·e_{c,j})),

  e_{c,j} one more independent normal per fitted frequency. Either way every frequency keeps its
  fitted marginal F_{c,j} exactly, and the normal scores of two frequencies are correlated by ρ
  whatever their distance. That is what the section populations show (docs/irregularity.md,
  measured on the default synthetic campaigns): beyond the window's leakage the correlation of
  the scores does not decay with frequency separation -- a section is rough or smooth as a
  whole -- so one common normal per channel carries the dependence; ρ = 1 (default) makes the
  ordinates comonotone, :meth:`from_population` can measure ρ. The levels of different
  channels/bands may be correlated (``level_correlation``, standard-normal space;
  :meth:`from_population` estimates it from the sections). Between fitted frequencies the
  quantile PSD is interpolated log-log onto the FFT frequencies (as
  :func:`~ttbpipe.irregularity.synthesis.synthesize_from_psd_table`).

u = 0 gives the zero profile (all coefficients 0) and, where it matters for the PSD, the
median level of every frequency.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import linalg, special, stats

from ..channels import SPECTRAL_CHANNELS
from .spectra import TrackSpectrum, get_spectrum
from .synthesis import gaussian_band_frequencies, gaussian_channel_from_normals, fft_grid

__all__ = ["GaussianIrregularityModel", "standard_normal_point", "ordinate_normal_scores", "level_quantiles",
           "frequency_score_plateau"]

#: families of the per-frequency fits this module can invert (tipm.distribution.FAMILIES)
FAMILIES = ("lognorm", "gamma")


def level_quantiles(family: np.ndarray, shape: np.ndarray, scale: np.ndarray,
                    v: np.ndarray) -> np.ndarray:
    """F^{-1}(Φ(v)) of zero-location lognormal/gamma fits, elementwise (mm²/(1/m)).

    Lognormal in closed form, scale·exp(shape·v) (exact in the far tails a subset simulation
    reaches, where Φ(v) rounds to 1); gamma through the upper-tail inverse for v > 0 for the
    same reason.
    """
    family = np.asarray(family)
    shape, scale, v = (np.asarray(a, dtype=float) for a in (shape, scale, v))
    out = np.empty(np.broadcast(shape, v).shape)
    logn = family == "lognorm"
    out[logn] = (scale * np.exp(shape * v))[logn]
    gam = family == "gamma"
    if np.any(gam):
        lower = special.gammaincinv(shape, special.ndtr(v))      # P(a, x) = Φ(v)
        upper = special.gammainccinv(shape, special.ndtr(-v))    # Q(a, x) = 1 − Φ(v)
        out[gam] = (scale * np.where(v > 0, upper, lower))[gam]
    if not np.all(logn | gam):
        raise ValueError(f"unknown family in {sorted(set(family.tolist()) - set(FAMILIES))}; "
                         f"expected {FAMILIES}")
    return out


def _chosen_fits(fits: pd.DataFrame, family: str) -> pd.DataFrame:
    """One fit per (channel, frequency): the named family, or the AIC-best (``best``)."""
    needed = {"channel", "spatial_frequency_per_m", "family", "shape", "scale", "best"}
    missing = needed - set(fits.columns)
    if missing:
        raise ValueError(f"fits: missing column(s) {sorted(missing)} (expected the table of "
                         "ttbpipe.tipm.distribution.fit_ordinate_distributions)")
    if family == "best":
        chosen = fits[fits["family"] == fits["best"]]
    elif family in FAMILIES:
        chosen = fits[fits["family"] == family]
    else:
        raise ValueError(f"family: {family!r}; expected 'best' or one of {FAMILIES}")
    if chosen.empty:
        raise ValueError(f"fits: no row of family {family!r}")
    return chosen.sort_values(["channel", "spatial_frequency_per_m"])


def ordinate_normal_scores(psd_mm2_m: np.ndarray, frequency_per_m: np.ndarray,
                           channels: Sequence[str], fits: pd.DataFrame,
                           family: str = "best") -> np.ndarray:
    """Normal scores Φ^{-1}(F_{c,k}(S_ikc)) of a population's ordinates, (sections, freq, channels).

    The inverse of the level map: if the fitted marginals are right, each score is N(0, 1) and
    the correlation of the scores between frequencies (or channels) across sections is the
    dependence the level model has to represent (docs/irregularity.md).
    """
    psd = np.asarray(psd_mm2_m, dtype=float)
    chosen = _chosen_fits(fits, family)
    out = np.empty_like(psd)
    for c, channel in enumerate(channels):
        rows = chosen[chosen["channel"] == channel]
        if len(rows) != len(frequency_per_m) or not np.allclose(
                rows["spatial_frequency_per_m"].to_numpy(), np.sort(frequency_per_m)):
            raise ValueError(f"fits of channel {channel} do not match the population frequencies")
        order = np.argsort(frequency_per_m)
        fam = rows["family"].to_numpy()
        a, sc = rows["shape"].to_numpy(float), rows["scale"].to_numpy(float)
        x = psd[:, order, c]
        cdf = np.where(fam == "lognorm", stats.lognorm.cdf(x, a, scale=sc),
                       stats.gamma.cdf(x, a, scale=sc))
        out[:, order, c] = special.ndtri(np.clip(cdf, 1e-300, 1 - 1e-16))
    return out


def frequency_score_plateau(scores: np.ndarray, min_lag: int = 3) -> np.ndarray:
    """Per channel: mean correlation across sections of the normal scores of two frequencies at
    least ``min_lag`` bins apart, shape (channels,).

    Neighbouring Welch bins share the window's leakage (a Hann window correlates adjacent bins
    by about 0.5 whatever the track), so the section-level dependence is read beyond it; a
    value that does not fall with the lag is the common section level of the module docstring.
    """
    scores = np.asarray(scores, dtype=float)
    out = np.empty(scores.shape[2])
    for c in range(scores.shape[2]):
        corr = np.corrcoef(scores[:, :, c].T)
        i, j = np.triu_indices(corr.shape[0], k=int(min_lag))
        out[c] = float(np.mean(corr[i, j]))
    return out


def standard_normal_point(u: np.ndarray, n_dims: int) -> np.ndarray:
    """``u`` as a float vector of length ``n_dims`` with finite entries, else ValueError (the
    check of every map from standard-normal space)."""
    u = np.asarray(u, dtype=float)
    if u.shape != (n_dims,):
        raise ValueError(f"u: shape {u.shape}, expected ({n_dims},)")
    if not np.all(np.isfinite(u)):
        raise ValueError("u must be finite")
    return u


class GaussianIrregularityModel:
    """Profile (four spectral channels, mm) as a pure function of u ~ N(0, I_n_dims).

    Parameters
    ----------
    length_m, dx_m
        Profile length and sample spacing (m); the FFT grid of
        :func:`~ttbpipe.irregularity.synthesis.fft_grid`.
    wavelength_band_m
        (shortest, longest) wavelength kept (m); default: the spectrum's valid band, or
        2-200 m with ``fits``.
    spectrum
        A standard spectrum (name or :class:`TrackSpectrum`): deterministic G, no level
        dimensions. Exactly one of ``spectrum`` and ``fits``.
    fits
        Per-frequency fits of a PSD population (the table of
        :func:`ttbpipe.tipm.distribution.fit_ordinate_distributions`); channels missing from
        it stay flat (zero), as in the study's Monte Carlo irregularity.
    family
        ``"best"`` (the AIC-best family at each frequency), ``"lognorm"`` or ``"gamma"``.
    level_split_wavelengths_m
        Wavelengths (m) cutting the spectrum into level bands with one standard normal each;
        empty (default): one level per channel.
    level_correlation
        Correlation of the level normals (standard-normal space), order: channel
        (:data:`SPECTRAL_CHANNELS` order, fitted channels only), then level band (increasing
        wavelength); default identity.
    frequency_score_correlation
        ρ in (0, 1] (one value, or {channel: value}): correlation of the normal scores of two
        fitted frequencies of a level band (module docstring); 1 (default): comonotone, no
        per-frequency normals.

    Layout of u (:attr:`slices`): ``irregularity/<channel>/level`` (the channel's level
    normals, if any), ``irregularity/<channel>/level_scatter`` (one normal per fitted
    frequency, only if ρ < 1), then ``irregularity/<channel>/coefficients`` (a_k then b_k,
    :func:`~ttbpipe.irregularity.synthesis.gaussian_channel_from_normals`) per channel.
    """

    def __init__(self, length_m: float, dx_m: float,
                 wavelength_band_m: tuple[float, float] | None = None, *,
                 spectrum: TrackSpectrum | str | None = None, fits: pd.DataFrame | None = None,
                 family: str = "best", level_split_wavelengths_m: Sequence[float] = (),
                 level_correlation: np.ndarray | None = None,
                 frequency_score_correlation: float | Mapping[str, float] = 1.0) -> None:
        if (spectrum is None) == (fits is None):
            raise ValueError("give exactly one of spectrum (a standard spectrum) and fits "
                             "(per-frequency fits of a PSD population)")
        self.length_m, self.dx_m = float(length_m), float(dx_m)
        self.n_samples, _ = fft_grid(self.length_m, self.dx_m)
        self.spectrum = get_spectrum(spectrum) if isinstance(spectrum, str) else spectrum
        if wavelength_band_m is None:
            wavelength_band_m = (self.spectrum.valid_wavelength_band_m if self.spectrum is not None
                                 else (2.0, 200.0))
        self.wavelength_band_m = tuple(float(b) for b in wavelength_band_m)
        self.frequency_per_m = gaussian_band_frequencies(self.length_m, self.dx_m,
                                                         self.wavelength_band_m)
        self.splits_m = np.sort(np.asarray(level_split_wavelengths_m, dtype=float))
        self._level_fits: dict[str, dict[str, np.ndarray]] = {}
        if self.spectrum is not None:
            self.channels = tuple(c for c in SPECTRAL_CHANNELS if c in self.spectrum.channels)
            self._fixed_psd = {c: np.asarray(self.spectrum.as_function(c)(self.frequency_per_m),
                                             float) for c in self.channels}
            if self.splits_m.size or level_correlation is not None \
                    or frequency_score_correlation != 1.0:
                raise ValueError("a standard spectrum has no random level: level options need fits")
        else:
            chosen = _chosen_fits(fits, family)
            self.channels = tuple(c for c in SPECTRAL_CHANNELS if c in set(chosen["channel"]))
            for c in self.channels:
                rows = chosen[chosen["channel"] == c]
                f = rows["spatial_frequency_per_m"].to_numpy(float)
                lo, hi = self.frequency_per_m[[0, -1]]
                if f.size < 2 or f[0] > lo * (1 + 1e-12) or f[-1] < hi * (1 - 1e-12):
                    raise ValueError(f"fits of channel {c} cover {f.min():g}-{f.max():g} 1/m, "
                                     f"not the synthesis band {lo:g}-{hi:g} 1/m; narrow the band")
                band = np.searchsorted(self.splits_m, 1.0 / f)   # 0: shortest wavelengths
                empty = sorted(set(range(self.splits_m.size + 1)) - set(band.tolist()))
                if empty:
                    raise ValueError(f"level bands {empty} (splits {self.splits_m.tolist()} m) "
                                     f"hold no fitted frequency of channel {c}")
                rho = float(frequency_score_correlation[c]
                            if isinstance(frequency_score_correlation, Mapping)
                            else frequency_score_correlation)
                if not 0.0 < rho <= 1.0:
                    raise ValueError(f"frequency_score_correlation of {c}: {rho}; expected 0 < ρ <= 1")
                self._level_fits[c] = {"log_f": np.log(f), "band": band, "rho": rho,
                                       "family": rows["family"].to_numpy(),
                                       "shape": rows["shape"].to_numpy(float),
                                       "scale": rows["scale"].to_numpy(float)}
        self.n_level_bands = self.splits_m.size + 1 if self._level_fits else 0
        n_levels = self.n_level_bands * len(self._level_fits)
        corr = np.eye(n_levels) if level_correlation is None else np.asarray(level_correlation,
                                                                             float)
        if corr.shape != (n_levels, n_levels) or not np.allclose(corr, corr.T) \
                or not np.allclose(np.diag(corr), 1.0):
            raise ValueError(f"level_correlation: a symmetric {n_levels}x{n_levels} correlation "
                             f"matrix (channels {self.channels} x {self.n_level_bands} band(s)) "
                             f"is needed, got shape {corr.shape}")
        self.level_correlation = corr
        self._level_factor = linalg.cholesky(corr, lower=True) if n_levels else corr
        n_coef = 2 * self.frequency_per_m.size
        self.slices: dict[str, slice] = {}
        start = 0
        for c, fit in self._level_fits.items():
            self.slices[f"irregularity/{c}/level"] = slice(start, start + self.n_level_bands)
            start += self.n_level_bands
            if fit["rho"] < 1.0:
                self.slices[f"irregularity/{c}/level_scatter"] = slice(start,
                                                                       start + fit["log_f"].size)
                start += fit["log_f"].size
        for c in self.channels:
            self.slices[f"irregularity/{c}/coefficients"] = slice(start, start + n_coef)
            start += n_coef
        self.n_dims = start

    @classmethod
    def from_population(cls, population, length_m: float, dx_m: float,
                        wavelength_band_m: tuple[float, float] = (2.0, 200.0), *,
                        families: Sequence[str] = FAMILIES, family: str = "best",
                        level_split_wavelengths_m: Sequence[float] = (),
                        correlated_levels: bool = True,
                        frequency_score_correlation: float | str = 1.0
                        ) -> "GaussianIrregularityModel":
        """Fit the population's ordinates (tipm.distribution) and, with ``correlated_levels``,
        estimate the level correlation: the correlation across sections of each section's mean
        normal score per channel and level band (:func:`ordinate_normal_scores`).
        ``frequency_score_correlation="measured"`` takes ρ per channel from
        :func:`frequency_score_plateau` (clipped to [0.01, 1])."""
        from ..tipm.distribution import fit_ordinate_distributions

        fits = fit_ordinate_distributions(population, families)
        corr = None
        scores = ordinate_normal_scores(population.psd_mm2_m, population.frequency_per_m,
                                        population.channels, fits, family)
        if frequency_score_correlation == "measured":
            plateau = np.clip(frequency_score_plateau(scores), 0.01, 1.0)
            frequency_score_correlation = {ch: float(r) for ch, r in
                                           zip(population.channels, plateau)}
        elif isinstance(frequency_score_correlation, str):
            raise ValueError(f"frequency_score_correlation: {frequency_score_correlation!r}; "
                             "expected a number in (0, 1] or 'measured'")
        if correlated_levels:
            splits = np.sort(np.asarray(level_split_wavelengths_m, dtype=float))
            band = np.searchsorted(splits, 1.0 / np.asarray(population.frequency_per_m))
            # model order: channel (SPECTRAL_CHANNELS order), then level band
            ordered = [scores[:, band == b, population.channels.index(ch)].mean(axis=1)
                       for ch in SPECTRAL_CHANNELS if ch in population.channels
                       for b in range(splits.size + 1)]
            corr = np.atleast_2d(np.corrcoef(np.array(ordered)))
            values, vectors = linalg.eigh(corr)   # sampling noise: keep it positive definite
            corr = (vectors * np.maximum(values, 1e-6)) @ vectors.T
            d = np.sqrt(np.diag(corr))
            corr = corr / np.outer(d, d)
            corr = 0.5 * (corr + corr.T)
        return cls(length_m, dx_m, wavelength_band_m, fits=fits, family=family,
                   level_split_wavelengths_m=level_split_wavelengths_m, level_correlation=corr,
                   frequency_score_correlation=frequency_score_correlation)

    def _check(self, u: np.ndarray) -> np.ndarray:
        return standard_normal_point(u, self.n_dims)

    def levels(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Correlated level normals v per fitted channel (one per level band) of u."""
        u = self._check(u)
        if not self._level_fits:
            return {}
        raw = np.concatenate([u[self.slices[f"irregularity/{c}/level"]]
                              for c in self._level_fits])
        v = self._level_factor @ raw
        return {c: v[i * self.n_level_bands:(i + 1) * self.n_level_bands]
                for i, c in enumerate(self._level_fits)}

    def scores(self, u: np.ndarray, channel: str, v: np.ndarray | None = None) -> np.ndarray:
        """Normal scores s_j of the fitted frequencies of ``channel`` (module docstring)."""
        fit = self._level_fits[channel]
        v = self.levels(u)[channel] if v is None else v
        if fit["rho"] == 1.0:
            return v[fit["band"]]
        e = np.asarray(u, float)[self.slices[f"irregularity/{channel}/level_scatter"]]
        return np.sqrt(fit["rho"]) * v[fit["band"]] + np.sqrt(1.0 - fit["rho"]) * e

    def band_psd(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """PSD of the sample at :attr:`frequency_per_m` per channel (mm²/(1/m))."""
        if self.spectrum is not None:
            self._check(u)
            return {c: g.copy() for c, g in self._fixed_psd.items()}
        out = {}
        for c, v in self.levels(u).items():
            fit = self._level_fits[c]
            q = level_quantiles(fit["family"], fit["shape"], fit["scale"],
                                self.scores(u, c, v))
            out[c] = np.exp(np.interp(np.log(self.frequency_per_m), fit["log_f"], np.log(q)))
        return out

    def profile(self, u: np.ndarray) -> pd.DataFrame:
        """``chainage_m, vertical_mm, alignment_mm, cross_level_mm, gauge_mm`` of u (pure)."""
        u = self._check(u)
        psd = self.band_psd(u)
        columns = {}
        for c in SPECTRAL_CHANNELS:
            if c not in psd:
                columns[f"{c}_mm"] = np.zeros(self.n_samples)
                continue
            g = psd[c]
            columns[f"{c}_mm"] = gaussian_channel_from_normals(
                lambda n, g=g: g, self.length_m, self.dx_m,
                u[self.slices[f"irregularity/{c}/coefficients"]], self.wavelength_band_m)
        return pd.DataFrame({"chainage_m": np.arange(self.n_samples) * self.dx_m, **columns})

    def describe(self) -> Mapping[str, int]:
        """{slice name: number of dimensions}."""
        return {k: s.stop - s.start for k, s in self.slices.items()}
