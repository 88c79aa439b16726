"""Per-frequency distribution fits of PSD ordinates (ttbpipe.tipm.distribution)."""

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from ttbpipe.tipm import PSDPopulation
from ttbpipe.tipm.distribution import (_anderson_darling, _kolmogorov_smirnov,
                                       fit_ordinate_distributions, summarize_fits)

FREQ = np.array([0.01, 0.02, 0.03, 0.04, 0.05, 0.06])


def _population(psd: np.ndarray) -> PSDPopulation:
    n = psd.shape[0]
    sections = pd.DataFrame({"campaign_date": "2024-01-01", "section": np.arange(n),
                             "section_start_m": np.arange(n) * 1000.0,
                             "section_end_m": np.arange(n) * 1000.0 + 1000.0})
    return PSDPopulation(psd, FREQ, ("vertical",), sections)


def test_lognormal_ordinates_are_recognised():
    """Known lognormal (sigma 0.5, median 2): MLE shape within 0.1 (standard error
    sigma/sqrt(2N) = 0.018 for N = 400, so > 5 standard errors), lognormal preferred by AIC at
    most frequencies, KS not rejected at most frequencies (5 % level: >= 4 of 6 expected)."""
    rng = np.random.default_rng(11)
    psd = rng.lognormal(np.log(2.0), 0.5, size=(400, FREQ.size, 1))
    fits = fit_ordinate_distributions(_population(psd))
    logn = fits[fits["family"] == "lognorm"]
    assert np.allclose(logn["shape"], 0.5, atol=0.1)
    assert np.allclose(logn["scale"], 2.0, rtol=0.15)
    assert (logn["best"] == "lognorm").mean() >= 4 / 6
    assert (logn["ks_pvalue"] > 0.05).sum() >= 4


def test_gamma_ordinates_are_recognised():
    """Welch-averaged ordinates ~ S·chi2_nu/nu (physics.md §2) are gamma(shape nu/2,
    scale 2S/nu): nu = 4, S = 3 -> shape 2, scale 1.5; shape within 20 % for N = 400
    (standard error ~ 7 %), gamma preferred by AIC at most frequencies."""
    rng = np.random.default_rng(12)
    psd = 3.0 * rng.chisquare(4, size=(400, FREQ.size, 1)) / 4
    fits = fit_ordinate_distributions(_population(psd))
    gam = fits[fits["family"] == "gamma"]
    assert np.allclose(gam["shape"], 2.0, rtol=0.2)
    assert np.allclose(gam["shape"] * gam["scale"], 3.0, rtol=0.1)   # mean
    assert (gam["best"] == "gamma").mean() >= 4 / 6


def test_anderson_darling_statistic_matches_scipy():
    """Our A² of a fully specified CDF against scipy.stats.anderson's A² for the normal family
    evaluated at the same fitted normal (mean, std with ddof = 1): identical to 1e-9."""
    x = np.random.default_rng(5).normal(1.0, 2.0, size=60)
    ours = _anderson_darling(stats.norm(x.mean(), x.std(ddof=1)).cdf(x))
    assert ours == pytest.approx(stats.anderson(x, "norm", method="interpolate").statistic, rel=1e-9)


@pytest.mark.parametrize("n", [8, 25, 180])
def test_kolmogorov_smirnov_of_every_row_matches_scipy_kstest(n):
    """The rows' KS statistic and exact p-value against scipy.stats.kstest called row by row
    (the reference: the same formula and scipy.stats.kstwo), for samples that fit their CDF well
    and badly: equal to 1e-12 relative."""
    rng = np.random.default_rng(n)
    rows = [rng.lognormal(0.3, 0.8, size=n), rng.gamma(2.0, 1.5, size=n),
            rng.lognormal(0.0, 2.0, size=n), rng.uniform(0.5, 4.0, size=n)]
    shapes, scales = np.array([0.8, 1.0, 0.7, 1.2]), np.array([1.3, 2.0, 3.0, 1.0])
    ordered = np.sort(np.array(rows), axis=1)
    statistic, pvalue = _kolmogorov_smirnov(
        stats.lognorm.cdf(ordered, shapes[:, None], scale=scales[:, None]))
    for r, x in enumerate(rows):
        reference = stats.kstest(x, stats.lognorm(shapes[r], scale=scales[r]).cdf)
        assert statistic[r] == pytest.approx(reference.statistic, rel=1e-12)
        assert pvalue[r] == pytest.approx(reference.pvalue, rel=1e-12, abs=1e-300)
    assert pvalue.min() < 0.01 < pvalue.max()      # both a rejected and an accepted row


def test_summary_shares_and_small_population_error():
    rng = np.random.default_rng(1)
    fits = fit_ordinate_distributions(_population(rng.lognormal(size=(50, FREQ.size, 1))))
    summary = summarize_fits(fits, bands_m=((10.0, 40.0), (40.0, 100.0)))
    assert set(summary["family"]) == {"lognorm", "gamma"}
    assert summary["n_frequencies"].sum() == 2 * FREQ.size
    assert summary[["ks_not_rejected_share", "best_share"]].apply(lambda s: s.between(0, 1).all()).all()
    with pytest.raises(ValueError, match=">= 8 sections"):
        fit_ordinate_distributions(_population(rng.lognormal(size=(5, FREQ.size, 1))))
