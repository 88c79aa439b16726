"""Probability-preserving selection of representative PSD sets (TIPM, Xu & Zhai).

Seed paper §3.2 (eq. 49 and steps 1-5): cut the line into sections, estimate each section's PSD,
derive the probability distribution of the PSD ordinates, and select Ñ << N representative PSD
sets P_r(ω) that keep "the statistical properties in amplitudes and frequencies". The full
TIPM papers (MSSP/AMM 2017) were not retrievable; physics.md §3 reconstructs the method and
docs/tipm.md states and justifies every choice made here. In short:

1. **Joint stratification on the equivalent TQI** (Xu & Zhai 2020: PSD -> equivalent TQI by the
   discrete Parseval theorem, "where the correlation between various types of track
   irregularities is accounted for"). Each section's TQI vector (σ_vertical, σ_alignment,
   σ_cross_level, σ_gauge) is log-transformed and standardised; its first principal component
   orders the sections; M equal-probability strata are cut along that order (physics.md §3
   step 4: p_j = (j-½)/M, probability 1/M each).
2. **One whole section per stratum** (physics.md §3 step 5: the same section index for all four
   channels keeps their cross-correlation). Starting from the stratum medoid, a deterministic
   coordinate search picks, per stratum, the member that makes each channel's selected log-TQI
   values closest to that channel's population quantiles at p_j (so each channel's RMS
   distribution is kept, not only the first principal component's).
3. Representative PSD values, two methods:

   * ``"sections"``: the selected sections' own PSDs, weight = stratum probability (stratum size
     / N). Simple and literal; its per-frequency moments carry the Welch scatter of M raw
     estimates (≈ σ_X/sqrt(M), about 10 % for M = 18), see docs/tipm.md.
   * ``"copula"`` (default): at every (frequency, channel) the population's distribution is
     discretised into M equal-probability bins, each represented by its conditional mean
     E[S | bin j] (so the weighted mean equals the population mean exactly, law of total
     expectation); the bin values are assigned to the M selected sections in the order of
     those sections' own values there (empirical-copula reordering, the "Schaake shuffle",
     Clark et al. 2004, J. Hydrometeorol. 5:243). The representative sets thus have the
     population's per-frequency marginal distribution and the rank dependence across channels
     and frequencies of M real sections. With ``match_variance`` the bin values are finally
     spread, since the between-bin variance misses the within-bin part: a mean-preserving
     exponential tilt v_j = c·b_j·exp(κ·b_j/max b) (κ by bisection per ordinate) matches the
     per-frequency standard deviation exactly and keeps the mean, the order, the positivity and
     the lower-tail shape of the values (an affine stretch about the mean would push the lowest
     bins of the χ²₂-like periodogram ordinates below zero).

Every weight is a probability: the weights sum to one.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from .population import PSDPopulation

__all__ = ["TIPMSelector", "TIPMSelection", "selection_metrics", "equal_probability_bin_means"]

log = logging.getLogger(__name__)

METHODS = ("copula", "sections")


def equal_probability_bin_means(values: np.ndarray, n_bins: int) -> np.ndarray:
    """Conditional means of ``values`` (axis 0 = population) over ``n_bins`` equal-probability bins.

    The empirical distribution puts mass 1/N on each value; bin j covers cumulative probability
    [j/M, (j+1)/M], and a value straddling a bin edge contributes its share of mass to both
    bins, so the bin means average exactly to the population mean for any N and M.
    Returns an array of shape (n_bins, *values.shape[1:]), sorted ascending along axis 0.
    """
    values = np.sort(np.asarray(values, dtype=float), axis=0)
    n = values.shape[0]
    # integral of the empirical quantile function from 0 to i/N, at i = 0..N
    cumulative = np.concatenate([np.zeros((1,) + values.shape[1:]), np.cumsum(values, axis=0)]) / n
    edges = np.arange(n_bins + 1) * n / n_bins   # bin edges in units of 1/N
    lower = np.minimum(np.floor(edges).astype(int), n - 1)
    frac = (edges - lower).reshape((-1,) + (1,) * (values.ndim - 1))
    # the integral is piecewise linear between i/N points with slope values[i]
    integral = cumulative[lower] + frac * values[lower] / n
    return (integral[1:] - integral[:-1]) * n_bins


@dataclass
class TIPMSelection:
    """Representative PSD sets with probability weights.

    ``psd_mm2_m[sample, frequency, channel]``; ``weights`` sum to one; ``samples`` has one row
    per representative: ``sample_index, weight, stratum, stratum_size, source_campaign_date,
    source_section, source_section_start_m, source_section_end_m`` and ``tqi_<channel>_mm`` (the
    representative's equivalent TQI).
    """

    psd_mm2_m: np.ndarray
    weights: np.ndarray
    frequency_per_m: np.ndarray
    channels: tuple[str, ...]
    samples: pd.DataFrame = field(repr=False)
    method: str = "copula"

    @property
    def n_samples(self) -> int:
        return self.psd_mm2_m.shape[0]

    def weighted_mean(self) -> np.ndarray:
        """Probability-weighted mean PSD, (n_frequencies, n_channels)."""
        return np.tensordot(self.weights, self.psd_mm2_m, axes=1)

    def weighted_std(self) -> np.ndarray:
        """Probability-weighted standard deviation of the PSD ordinates (population form)."""
        mean = self.weighted_mean()
        return np.sqrt(np.tensordot(self.weights, (self.psd_mm2_m - mean) ** 2, axes=1))

    def tqi_mm(self) -> np.ndarray:
        df = float(self.frequency_per_m[1] - self.frequency_per_m[0])
        return np.sqrt(self.psd_mm2_m.sum(axis=1) * df)

    def to_long_table(self) -> pd.DataFrame:
        """Long table: ``sample_index, weight, channel, spatial_frequency_per_m, psd_mm2_m``."""
        m, f, c = self.psd_mm2_m.shape
        return pd.DataFrame({
            "sample_index": np.repeat(np.arange(m), f * c),
            "weight": np.repeat(self.weights, f * c),
            "channel": np.tile(np.array(self.channels, dtype=object), m * f),
            "spatial_frequency_per_m": np.tile(np.repeat(self.frequency_per_m, c), m),
            "psd_mm2_m": self.psd_mm2_m.reshape(-1),
        })

    @classmethod
    def from_long_table(cls, table: pd.DataFrame, samples: pd.DataFrame,
                        method: str = "copula") -> "TIPMSelection":
        """Inverse of :meth:`to_long_table` (``samples`` is the weights table)."""
        from ..channels import SPECTRAL_CHANNELS
        present = set(table["channel"].astype(str).unique())
        channels = tuple(c for c in SPECTRAL_CHANNELS if c in present)
        wide = table.pivot(index=["sample_index", "spatial_frequency_per_m"], columns="channel",
                           values="psd_mm2_m").reindex(columns=list(channels)).sort_index()
        idx = wide.index.get_level_values(0).unique()
        freqs = np.sort(wide.index.get_level_values(1).unique().to_numpy(dtype=float))
        psd = wide.to_numpy(float).reshape(len(idx), freqs.size, len(channels))
        samples = samples.set_index("sample_index").loc[idx].reset_index()
        return cls(psd, samples["weight"].to_numpy(float), freqs, channels, samples, method)


class TIPMSelector:
    """Select M representative PSD sets with probability weights from a population.

    Parameters
    ----------
    fraction
        M = max(min_samples, floor(fraction · N)) for a population of N sections (capped by
        ``max_samples`` and N).
    min_samples, max_samples
        Bounds on M.
    method
        ``"copula"`` (default) or ``"sections"``; see the module docstring.
    match_variance
        Copula method only: spread the bin values (exponential tilt) so that the per-frequency
        standard deviation equals the population's.
    max_sweeps
        Coordinate-search sweeps over the strata (step 2); it stops earlier when no stratum
        changes.
    """

    def __init__(self, fraction: float = 0.1, min_samples: int = 5, max_samples: int | None = None,
                 method: str = "copula", match_variance: bool = True, max_sweeps: int = 10):
        if not 0 < fraction <= 1:
            raise ValueError(f"tipm selection fraction must be in (0, 1], got {fraction}")
        if min_samples < 1:
            raise ValueError(f"min_samples must be >= 1, got {min_samples}")
        if method not in METHODS:
            raise ValueError(f"unknown TIPM selection method {method!r}; choose one of {METHODS}")
        self.fraction = float(fraction)
        self.min_samples = int(min_samples)
        self.max_samples = None if max_samples is None else int(max_samples)
        self.method = method
        self.match_variance = bool(match_variance)
        self.max_sweeps = int(max_sweeps)

    def n_samples(self, n_sections: int) -> int:
        m = max(self.min_samples, int(np.floor(self.fraction * n_sections + 1e-9)))
        if self.max_samples is not None:
            m = min(m, self.max_samples)
        return max(1, min(m, n_sections))

    # -- step 1 -----------------------------------------------------------------------------
    @staticmethod
    def joint_index(log_tqi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(standardised log-TQI features, first-principal-component score) per section."""
        std = log_tqi.std(axis=0)
        features = (log_tqi - log_tqi.mean(axis=0)) / np.where(std > 0, std, 1.0)
        if features.shape[1] == 1 or not np.any(features):
            return features, features.sum(axis=1)
        _, _, vt = np.linalg.svd(features, full_matrices=False)
        direction = vt[0] * (1.0 if vt[0].sum() >= 0 else -1.0)  # larger score = rougher track
        return features, features @ direction

    def strata(self, population: PSDPopulation, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        """(stratum label per section, standardised log-TQI features)."""
        features, score = self.joint_index(np.log(population.tqi_mm()))
        order = np.lexsort((np.arange(score.size), score))  # ties: lower section index first
        labels = np.empty(score.size, dtype=int)
        labels[order] = (np.arange(score.size) * n_samples) // score.size
        return labels, features

    # -- step 2 -----------------------------------------------------------------------------
    def _choose_sections(self, labels: np.ndarray, features: np.ndarray, n_samples: int) -> np.ndarray:
        """One section per stratum whose per-channel values match the population quantiles."""
        targets = np.quantile(features, (np.arange(n_samples) + 0.5) / n_samples, axis=0,
                              method="hazen")  # (M, C): population quantiles at p_j

        def misfit(chosen: np.ndarray) -> float:
            return float(np.sum((np.sort(features[chosen], axis=0) - targets) ** 2))

        members = [np.flatnonzero(labels == j) for j in range(n_samples)]
        chosen = np.array([m[np.argmin(((features[m] - features[m].mean(axis=0)) ** 2).sum(axis=1))]
                           for m in members])
        best = misfit(chosen)
        for _ in range(self.max_sweeps):
            changed = False
            for j, m in enumerate(members):
                for candidate in m:
                    if candidate == chosen[j]:
                        continue
                    trial = chosen.copy()
                    trial[j] = candidate
                    value = misfit(trial)
                    if value < best - 1e-12:
                        best, chosen, changed = value, trial, True
            if not changed:
                break
        return chosen

    # -- step 3 -----------------------------------------------------------------------------
    @staticmethod
    def _tilt_spread(bins: np.ndarray, mean: np.ndarray, sigma: np.ndarray,
                     iterations: int = 80, max_tilt: float = 300.0) -> np.ndarray:
        """Mean-preserving exponential tilt v_j = c·b_j·exp(κ·b_j/max_j b_j), std(v) = ``sigma``.

        The between-bin variance lacks the within-bin part, which sits mostly in the upper
        tail (the top bin of a χ²₂-like ordinate); the tilt inflates the large values and
        shrinks all values by the common factor c = mean / mean_j(b_j·exp(κ b_j/max b)), so the
        equally weighted mean is kept, the values stay positive and ordered, and the lower tail
        keeps its shape (relative change c, close to 1). The coefficient of variation grows
        monotonically with κ >= 0, so κ is found by bisection in [0, ``max_tilt``] per
        (frequency, channel); κ = 0 where the bins already carry the whole variance.
        """
        target_cov = sigma / mean
        x = bins / bins.max(axis=0)

        def cov(kappa: np.ndarray) -> np.ndarray:
            tilted = x * np.exp(kappa * x)
            return tilted.std(axis=0) / tilted.mean(axis=0)

        lo = np.zeros(mean.shape)
        hi = np.full(mean.shape, max_tilt)
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            too_small = cov(mid) < target_cov
            lo = np.where(too_small, mid, lo)
            hi = np.where(too_small, hi, mid)
        kappa = 0.5 * (lo + hi)
        unresolved = hi > max_tilt * (1 - 1e-9)
        if unresolved.any():
            log.warning("variance matching: tilt at its bound %g at %d of %d (frequency, channel) "
                        "ordinates; their std stays below the population's", max_tilt,
                        int(unresolved.sum()), unresolved.size)
        tilted = x * np.exp(kappa * x)
        return tilted * (mean / tilted.mean(axis=0))

    def _copula_values(self, population: PSDPopulation, chosen: np.ndarray) -> np.ndarray:
        m = chosen.size
        bins = equal_probability_bin_means(population.psd_mm2_m, m)      # (M, F, C) ascending
        if self.match_variance and m > 1:
            mean = population.psd_mm2_m.mean(axis=0)
            sigma_pop = population.psd_mm2_m.std(axis=0)
            spread = bins.std(axis=0) > 0
            if spread.all():
                bins = self._tilt_spread(bins, mean, sigma_pop)
            elif spread.any():
                bins[:, spread] = self._tilt_spread(bins[:, spread], mean[spread], sigma_pop[spread])
        selected = population.psd_mm2_m[chosen]
        ranks = np.argsort(np.argsort(selected, axis=0, kind="stable"), axis=0, kind="stable")
        return np.take_along_axis(bins, ranks, axis=0)

    def select(self, population: PSDPopulation) -> TIPMSelection:
        """Representative PSD sets of ``population`` (deterministic: no random numbers)."""
        n = population.n_sections
        m = self.n_samples(n)
        labels, features = self.strata(population, m)
        chosen = self._choose_sections(labels, features, m)
        sizes = np.bincount(labels, minlength=m)
        if self.method == "sections":
            psd = population.psd_mm2_m[chosen]
            weights = sizes / n
        else:
            psd = self._copula_values(population, chosen)
            weights = np.full(m, 1.0 / m)
        src = population.sections.iloc[chosen].reset_index(drop=True)
        samples = pd.DataFrame({
            "sample_index": np.arange(m), "weight": weights, "stratum": np.arange(m),
            "stratum_size": sizes, "source_campaign_date": src["campaign_date"].astype(str),
            "source_section": src["section"].to_numpy(),
            "source_section_start_m": src["section_start_m"].to_numpy(float),
            "source_section_end_m": src["section_end_m"].to_numpy(float),
        })
        selection = TIPMSelection(psd, weights, population.frequency_per_m, population.channels,
                                  samples, self.method)
        tqi = selection.tqi_mm()
        for c, channel in enumerate(population.channels):
            samples[f"tqi_{channel}_mm"] = tqi[:, c]
        log.info("TIPM (%s): %d representative sets out of %d sections", self.method, m, n)
        return selection


def selection_metrics(population: PSDPopulation, selection: TIPMSelection,
                      ks_alpha: float = 0.05) -> pd.DataFrame:
    """Per-channel fidelity of a selection to its population.

    Columns: ``channel, n_population, n_samples, max_rel_error_mean, max_rel_error_std``
    (max over frequencies of |weighted − population| / population, population std with
    ddof = 0), ``rms_ks_statistic, rms_ks_pvalue`` (two-sample Kolmogorov-Smirnov test,
    scipy.stats.ks_2samp, exact mode where available, between the representatives' band RMS
    (equivalent TQI) and the sections' band RMS), ``rms_ks_rejected`` at ``ks_alpha``.
    The KS test treats the representatives as equally weighted, which they are for the copula
    method and nearly are (stratum sizes differ by at most one) for the sections method.
    """
    pop_mean = population.psd_mm2_m.mean(axis=0)
    pop_std = population.psd_mm2_m.std(axis=0)
    err_mean = np.abs(selection.weighted_mean() - pop_mean) / pop_mean
    err_std = np.abs(selection.weighted_std() - pop_std) / np.where(pop_std > 0, pop_std, np.inf)
    tqi_pop, tqi_sel = population.tqi_mm(), selection.tqi_mm()
    rows = []
    for c, channel in enumerate(population.channels):
        ks = stats.ks_2samp(tqi_sel[:, c], tqi_pop[:, c])
        rows.append({"channel": channel, "n_population": population.n_sections,
                     "n_samples": selection.n_samples,
                     "max_rel_error_mean": float(err_mean[:, c].max()),
                     "max_rel_error_std": float(err_std[:, c].max()),
                     "rms_ks_statistic": float(ks.statistic), "rms_ks_pvalue": float(ks.pvalue),
                     "rms_ks_rejected": bool(ks.pvalue < ks_alpha)})
    return pd.DataFrame(rows)
