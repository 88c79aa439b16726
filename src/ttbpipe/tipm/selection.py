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

from ..jit import kernel
from .population import PSDPopulation
from .settings import representative_count

__all__ = ["TIPMSelector", "TIPMSelection", "selection_metrics", "equal_probability_bin_means"]

log = logging.getLogger(__name__)

METHODS = ("copula", "sections")

#: Step 2's annealing: initial temperature (in units of the normalised deviation; about half the
#: deviation the test accepts, so early moves may worsen the fit by that much) and the weight of
#: the mean deviation beside the largest one (breaks ties between selections of equal maximum).
_ANNEAL_T0 = 0.05
_ANNEAL_MEAN_WEIGHT = 0.01


@kernel
def _sorted_misfit(sorted_values, targets, inv_scale, mean_weight):
    """max_{j,c} |sorted_values[j,c] - targets[j,c]| inv_scale[c] + mean_weight * mean of the same."""
    m, c = sorted_values.shape
    largest = 0.0
    total = 0.0
    for k in range(c):
        for j in range(m):
            d = abs(sorted_values[j, k] - targets[j, k]) * inv_scale[k]
            total += d
            if d > largest:
                largest = d
    return largest + mean_weight * total / (m * c)


@kernel
def _replace_in_sorted(column, old, new, out):
    """``out`` = sorted ``column`` with one occurrence of ``old`` replaced by ``new`` (O(M))."""
    m = column.size
    skipped = False
    inserted = False
    i_out = 0
    for i in range(m):
        value = column[i]
        if not skipped and value == old:
            skipped = True
            continue
        if not inserted and new <= value:
            out[i_out] = new
            i_out += 1
            inserted = True
        out[i_out] = value
        i_out += 1
    if not inserted:
        out[i_out] = new


@kernel
def _anneal_strata(values, member_start, members, chosen, targets, inv_scale, n_iter, t0,
                   mean_weight, seed):
    """Simulated annealing of one member per stratum against per-channel sorted targets.

    ``values[section, channel]``; stratum j's members are ``members[member_start[j]:
    member_start[j+1]]``; ``chosen[j]`` the starting member (modified). A move replaces one
    stratum's member by another member of that stratum; it is accepted by the Metropolis rule at
    a temperature falling linearly from ``t0`` to 0. Returns (best chosen, its misfit
    :func:`_sorted_misfit`). Deterministic for a given ``seed``.
    """
    np.random.seed(seed)
    m = chosen.size
    n_channels = values.shape[1]
    current = np.empty((m, n_channels))
    for k in range(n_channels):
        column = np.empty(m)
        for j in range(m):
            column[j] = values[chosen[j], k]
        current[:, k] = np.sort(column)
    trial = np.empty((m, n_channels))
    value = _sorted_misfit(current, targets, inv_scale, mean_weight)
    best_value = value
    best = chosen.copy()
    for it in range(n_iter):
        j = np.random.randint(m)
        size = member_start[j + 1] - member_start[j]
        if size < 2:
            continue
        candidate = members[member_start[j] + np.random.randint(size)]
        old = chosen[j]
        if candidate == old:
            continue
        for k in range(n_channels):
            _replace_in_sorted(current[:, k], values[old, k], values[candidate, k], trial[:, k])
        trial_value = _sorted_misfit(trial, targets, inv_scale, mean_weight)
        temperature = t0 * (1.0 - it / n_iter)
        if trial_value <= value or (temperature > 0.0 and
                                    np.random.random() < np.exp((value - trial_value) / temperature)):
            chosen[j] = candidate
            current[:, :] = trial
            value = trial_value
            if value < best_value:
                best_value = value
                best[:] = chosen
    return best, best_value


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
    search_chains, search_iterations
        Step 2's search: independent annealing chains (fixed seeds 0, 1, ...) of
        ``search_iterations`` proposed swaps each; the best chain is kept. 4 x 100 000 take
        about 0.1 s for 400 sections and 1.3 s for 3060 (M = 306).
    """

    def __init__(self, fraction: float = 0.1, min_samples: int = 5, max_samples: int | None = None,
                 method: str = "copula", match_variance: bool = True, search_chains: int = 4,
                 search_iterations: int = 100_000):
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
        if search_chains < 1 or search_iterations < 1:
            raise ValueError("search_chains and search_iterations must be >= 1")
        self.search_chains = int(search_chains)
        self.search_iterations = int(search_iterations)

    def n_samples(self, n_sections: int) -> int:
        return representative_count(n_sections, self.fraction, self.min_samples, self.max_samples)

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
    def _choose_sections(self, labels: np.ndarray, tqi_mm: np.ndarray, n_samples: int) -> np.ndarray:
        """One section per stratum whose per-channel TQIs sit on the population quantiles.

        Target: the M selected values of channel c, sorted, against that channel's population
        quantiles at p_j = (j - 1/2)/M (Hazen), in mm of equivalent TQI and normalised by the
        channel's 10-90 % inter-quantile range. Objective: the largest normalised deviation over
        every (j, c), plus 1 % of the mean deviation (ties). The largest deviation sits in the
        outer strata, where a greedy search from the stratum medoids stalls (one member that fits
        one channel's tail misfits another's); a fixed-seed simulated annealing over the members
        of each stratum (:func:`_anneal_strata`, a few independent chains, best kept) finds
        selections within about 0.1 of the range on populations where the greedy search stayed
        at 0.2-0.36 (tests/test_tipm_selection.py). The chains' seeds are constants, so the
        selection is still a function of the population alone.
        """
        # (M, C): population quantiles at p_j (numpy's default, linear interpolation)
        targets = np.quantile(tqi_mm, (np.arange(n_samples) + 0.5) / n_samples, axis=0)
        spread = np.subtract(*np.quantile(tqi_mm, [0.9, 0.1], axis=0))
        inv_scale = 1.0 / np.where(spread > 0, spread, 1.0)
        members = [np.flatnonzero(labels == j) for j in range(n_samples)]
        start = np.concatenate([[0], np.cumsum([m.size for m in members])]).astype(np.int64)
        flat = np.concatenate(members).astype(np.int64)
        # start: the member of each stratum closest to the stratum's own target vector
        chosen = np.array([m[np.argmin((((tqi_mm[m] - targets[j]) * inv_scale) ** 2).sum(axis=1))]
                           for j, m in enumerate(members)], dtype=np.int64)
        if n_samples == 1 or all(m.size == 1 for m in members):
            return chosen
        best, best_value = chosen, np.inf
        for chain in range(self.search_chains):
            result, value = _anneal_strata(np.ascontiguousarray(tqi_mm, dtype=float), start, flat,
                                           chosen.copy(), np.ascontiguousarray(targets),
                                           inv_scale, self.search_iterations, _ANNEAL_T0, _ANNEAL_MEAN_WEIGHT,
                                           chain)
            if value < best_value:
                best, best_value = result, value
        return best

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
        labels, _ = self.strata(population, m)
        chosen = self._choose_sections(labels, population.tqi_mm(), m)
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
