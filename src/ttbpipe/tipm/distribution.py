"""Per-frequency probability distribution of PSD ordinates across sections (seed paper §3.2 step 3).

At each (channel, spatial frequency) the N section ordinates S_i(n_k) are fitted with

* a two-parameter **lognormal** (location 0): natural for a product of a section level and an
  estimation scatter (physics.md §3 step 2), and
* a two-parameter **gamma** (location 0): the family of Welch-averaged ordinates, ≈ χ²_{2K}/2K
  times the true PSD (physics.md §2).

Both by maximum likelihood (scipy.stats ``fit`` with ``floc=0``). Goodness of fit:

* Kolmogorov-Smirnov statistic and exact p-value of the fitted distribution (as
  scipy.stats.kstest, for every frequency at once: :func:`_kolmogorov_smirnov`).
  The parameters are estimated from the same data, so these p-values are conservative (too
  large; Lilliefors effect): they are reported for ranking and for gross misfit.
* Anderson-Darling statistic: for the lognormal, scipy.stats.anderson on log S against the
  normal family, with the p-value interpolated from tables that account for the estimated
  parameters (``method="interpolate"``; tabulated range 0.01-0.15, clipped outside); for the
  gamma, the AD statistic of the fitted CDF (no p-value: NaN).
* AIC = 2·2 − 2·log-likelihood; ``best`` names the family with the lower AIC.

:func:`summarize_fits` aggregates per channel and wavelength band: the fraction of frequencies at
which each family is not rejected at 5 % and how often it is the better one.
"""

from __future__ import annotations

import logging
from typing import Sequence

import numpy as np
import pandas as pd
from scipy import stats

from .population import PSDPopulation

__all__ = ["fit_ordinate_distributions", "summarize_fits", "DEFAULT_BANDS_M"]

log = logging.getLogger(__name__)

#: Wavelength bands (m) of the summary: short, medium, long waves.
DEFAULT_BANDS_M: tuple[tuple[float, float], ...] = ((2.0, 10.0), (10.0, 50.0), (50.0, 200.0))

FAMILIES = {"lognorm": stats.lognorm, "gamma": stats.gamma}

#: fewer sections cannot support a goodness-of-fit test
MIN_SECTIONS_FOR_FIT = 8

FIT_COLUMNS = ("channel", "spatial_frequency_per_m", "wavelength_m", "family", "shape", "scale",
               "ks_statistic", "ks_pvalue", "ad_statistic", "ad_pvalue", "loglik", "aic",
               "n_sections", "best")
SUMMARY_COLUMNS = ("channel", "family", "band_min_m", "band_max_m", "n_frequencies",
                   "ks_not_rejected_share", "ks_pvalue_median", "ad_not_rejected_share", "best_share")


def _anderson_darling(cdf_values: np.ndarray) -> float:
    """A² = −n − Σ (2i−1)/n [ln F(x_(i)) + ln(1 − F(x_(n+1−i)))] (Anderson & Darling 1954)."""
    u = np.clip(np.sort(cdf_values), 1e-300, 1 - 1e-16)
    n = u.size
    i = np.arange(1, n + 1)
    return float(-n - np.sum((2 * i - 1) / n * (np.log(u) + np.log1p(-u[::-1]))))


def _kolmogorov_smirnov(cdf_sorted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided one-sample Kolmogorov-Smirnov test of each row: (statistic, p-value).

    ``cdf_sorted[r]``: the fitted CDF at row r's sample in ascending order. D = max(D+, D-),
    D+ = max_i (i/n - F(x_(i))), D- = max_i (F(x_(i)) - (i-1)/n) (Kolmogorov 1933); the p-value is
    the exact null distribution's survival function, ``scipy.stats.kstwo.sf(D, n)`` (Simard &
    L'Ecuyer 2011), as ``scipy.stats.kstest`` computes them for one sample. Written out because
    kstest hands its CDF one sample at a time, also along an axis, at about 1.6 ms a call: the
    stage's largest cost. tests/test_tipm_distribution.py compares the two.
    """
    n = cdf_sorted.shape[1]
    d_plus = (np.arange(1.0, n + 1) / n - cdf_sorted).max(axis=1)
    d_minus = (cdf_sorted - np.arange(0.0, n) / n).max(axis=1)
    statistic = np.where(d_plus > d_minus, d_plus, d_minus)
    return statistic, np.clip(stats.kstwo.sf(statistic, n), 0.0, 1.0)


def fit_ordinate_distributions(population: PSDPopulation,
                               families: Sequence[str] = ("lognorm", "gamma")) -> pd.DataFrame:
    """Fit each family at every (channel, frequency); one row per (channel, frequency, family).

    Columns: ``channel, spatial_frequency_per_m, wavelength_m, family, shape, scale,
    ks_statistic, ks_pvalue, ad_statistic, ad_pvalue, loglik, aic,
    best, n_sections``. Needs at least 8 sections (fewer cannot support a test).
    """
    if population.n_sections < MIN_SECTIONS_FOR_FIT:
        raise ValueError(f"distribution fit needs >= {MIN_SECTIONS_FOR_FIT} sections, the population has "
                         f"{population.n_sections}; widen the TIPM population")
    unknown = set(families) - set(FAMILIES)
    if unknown:
        raise ValueError(f"unknown distribution families {sorted(unknown)}; choose from {list(FAMILIES)}")
    rows = []
    for c, channel in enumerate(population.channels):
        ordinates = population.psd_mm2_m[:, :, c]            # (section, frequency)
        ordered = np.sort(ordinates.T, axis=1)                 # (frequency, section)
        per_family = {}
        for name in families:
            dist = FAMILIES[name]
            params = np.array([dist.fit(ordinates[:, k], floc=0)[::2]
                               for k in range(ordinates.shape[1])])   # (shape, scale) each
            shape, scale = params[:, 0], params[:, 1]
            cdf_sorted = dist.cdf(ordered, shape[:, None], loc=0, scale=scale[:, None])
            ks_statistic, ks_pvalue = _kolmogorov_smirnov(cdf_sorted)
            per_family[name] = {"shape": shape, "scale": scale, "ks_statistic": ks_statistic,
                                "ks_pvalue": ks_pvalue, "cdf_sorted": cdf_sorted}
        for k, freq in enumerate(population.frequency_per_m):
            x = ordinates[:, k]
            fits = []
            for name in families:
                dist = FAMILIES[name]
                fitted = per_family[name]
                shape, scale = float(fitted["shape"][k]), float(fitted["scale"][k])
                if name == "lognorm":
                    ad = stats.anderson(np.log(x), "norm", method="interpolate")
                    ad_stat, ad_p = float(ad.statistic), float(ad.pvalue)
                else:   # the fitted CDF at the sorted sample, as the KS test used it
                    ad_stat, ad_p = _anderson_darling(fitted["cdf_sorted"][k]), np.nan
                loglik = float(np.sum(dist.logpdf(x, shape, loc=0, scale=scale)))
                fits.append({"channel": channel, "spatial_frequency_per_m": float(freq),
                             "wavelength_m": 1.0 / float(freq), "family": name,
                             "shape": shape, "scale": scale,
                             "ks_statistic": float(fitted["ks_statistic"][k]),
                             "ks_pvalue": float(fitted["ks_pvalue"][k]),
                             "ad_statistic": ad_stat, "ad_pvalue": ad_p,
                             "loglik": loglik, "aic": 4.0 - 2.0 * loglik,
                             "n_sections": int(x.size)})
            best = min(fits, key=lambda r: r["aic"])["family"]
            for r in fits:
                r["best"] = best
            rows.extend(fits)
    return pd.DataFrame(rows, columns=list(FIT_COLUMNS))


def summarize_fits(fits: pd.DataFrame, bands_m: Sequence[tuple[float, float]] = DEFAULT_BANDS_M,
                   alpha: float = 0.05) -> pd.DataFrame:
    """Per channel, wavelength band and family: share of frequencies with KS (and, for the
    lognormal, AD) not rejected at ``alpha``, median KS p-value, share where the family has the
    lower AIC."""
    rows = []
    for (channel, family), group in fits.groupby(["channel", "family"], sort=False):
        for lo, hi in bands_m:
            g = group[(group["wavelength_m"] >= lo) & (group["wavelength_m"] <= hi)]
            if g.empty:
                continue
            rows.append({"channel": channel, "family": family, "band_min_m": lo, "band_max_m": hi,
                         "n_frequencies": len(g),
                         "ks_not_rejected_share": float((g["ks_pvalue"] >= alpha).mean()),
                         "ks_pvalue_median": float(g["ks_pvalue"].median()),
                         "ad_not_rejected_share": float((g["ad_pvalue"] >= alpha).mean())
                         if g["ad_pvalue"].notna().all() else np.nan,
                         "best_share": float((g["best"] == family).mean())})
    return pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
