"""Gaussian spectral representation and random spectral level (ttbpipe.irregularity.gaussian)."""

import numpy as np
import pandas as pd
import pytest
from scipy import signal, stats

from ttbpipe.irregularity.gaussian import (GaussianIrregularityModel, frequency_score_plateau,
                                           level_quantiles, ordinate_normal_scores)
from ttbpipe.irregularity.synthesis import (gaussian_band_frequencies,
                                            gaussian_channel_from_normals,
                                            n_gaussian_coefficients, synthesize_channel)
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.tipm.population import synthetic_population

G0 = 2.0          # flat PSD level, mm²/(1/m)
DX = 0.25
LENGTH = 4095 * DX   # 4096 samples = the FFT size: realisations cover one full period
BAND = (2.0, 50.0)


def flat(n):
    return np.full(np.shape(n), G0)


def _full_period_variances(amplitudes, m, seed):
    rng = np.random.default_rng(seed)
    return np.array([np.mean(synthesize_channel(flat, LENGTH, DX, rng, BAND,
                                                amplitudes=amplitudes) ** 2) for _ in range(m)])


def test_gaussian_ensemble_variance_is_the_band_integral_and_random_phase_is_fixed():
    """Flat PSD: ∫G dn = G0 (1/2 − 1/50) in closed form; the grid sum differs by < 1 bin Δn·G0.
    Over one FFT period a Gaussian realisation's mean square is Σ G_kΔn (a²+b²)/2, whose standard
    deviation is sqrt(Σ (G_kΔn)²): the ensemble mean of M = 800 lies within 4 standard errors
    (plus the one-bin grid term) of the integral, and the spread of the realisations' variance is
    that standard deviation within 12 % (relative standard error of a std ≈ 1/sqrt(2M) = 2.5 %).
    The random-phase version has the same mean but every realisation's variance is Σ G_kΔn to
    round-off."""
    freqs = gaussian_band_frequencies(LENGTH, DX, BAND)
    dn = 1.0 / (4096 * DX)
    exact = G0 * (1 / BAND[0] - 1 / BAND[1])
    sd_one = np.sqrt(np.sum((G0 * dn * np.ones(freqs.size)) ** 2))
    m = 800
    gauss = _full_period_variances("gaussian", m, 1)
    assert abs(gauss.mean() - exact) < 4 * sd_one / np.sqrt(m) + G0 * dn
    assert gauss.std(ddof=1) == pytest.approx(sd_one, rel=0.12)
    phase = _full_period_variances("random_phase", 50, 2)
    assert np.ptp(phase) < 1e-9 * exact
    assert phase[0] == pytest.approx(G0 * dn * freqs.size, rel=1e-9)
    assert abs(phase[0] - exact) <= G0 * dn


def _values_at_origin(amplitudes, m, seed):
    """z(0) of m independent short profiles with 6 frequencies in the band (10-64 m)."""
    rng = np.random.default_rng(seed)
    return np.array([synthesize_channel(flat, 255 * DX, DX, rng, (10.0, 64.0),
                                        amplitudes=amplitudes)[0] for _ in range(m)])


def test_gaussian_values_are_normal_and_random_phase_ones_are_not():
    """Six equal cosines with random phases: excess kurtosis −1.5/6 = −0.25 (a cosine's is −1.5);
    the Gaussian form's is 0. Standard error of the sample excess for M = 20000: sqrt(24/M) =
    0.035, so 4 SE = 0.14 separates them. KS of the Gaussian values against N(0, Σ G Δn): not
    rejected at 1 % (fixed seed)."""
    assert gaussian_band_frequencies(255 * DX, DX, (10.0, 64.0)).size == 6
    m = 20000
    se = np.sqrt(24.0 / m)
    variance = G0 * 6 / (256 * DX)
    gauss = _values_at_origin("gaussian", m, 3)
    phase = _values_at_origin("random_phase", m, 4)
    assert abs(stats.kurtosis(gauss)) < 4 * se
    assert abs(stats.kurtosis(phase) + 0.25) < 4 * se
    assert stats.kstest(gauss / np.sqrt(variance), "norm").pvalue > 0.01
    assert np.var(gauss) == pytest.approx(variance, rel=4 * np.sqrt(2 / m))


def test_welch_psd_of_gaussian_realisations_recovers_the_psd():
    """Hann segments of 512 samples without overlap, K = 8 per profile, M = 40 profiles: each
    Welch ordinate of a Gaussian process is G·χ²_{2KM}/(2KM). Every ordinate well inside the
    band (3 Welch bins from the edges) lies inside the two-sided 1e-4/n_bins chi-square interval
    (Bonferroni), and their mean within 4 standard errors sqrt(1/(KM·n_bins))."""
    rng = np.random.default_rng(5)
    k, m, nper = 8, 40, 512
    estimates = []
    for _ in range(m):
        z = synthesize_channel(flat, LENGTH, DX, rng, BAND, amplitudes="gaussian")
        f, p = signal.welch(z, fs=1 / DX, window="hann", nperseg=nper, noverlap=0,
                            detrend=False)
        estimates.append(p)
    g = np.mean(estimates, axis=0)
    inside = (f >= 1 / BAND[1] + 3 / (nper * DX)) & (f <= 1 / BAND[0] - 3 / (nper * DX))
    dof = 2 * k * m
    n_bins = int(inside.sum())
    lo, hi = stats.chi2.ppf([0.5e-4 / n_bins, 1 - 0.5e-4 / n_bins], dof) / dof
    ratio = g[inside] / G0
    assert np.all((ratio > lo) & (ratio < hi))
    assert abs(ratio.mean() - 1) < 4 * np.sqrt(1 / (k * m * n_bins))


def test_normals_are_explicit_and_counted():
    n = n_gaussian_coefficients(500.0, DX, (2.0, 200.0))
    u = np.random.default_rng(0).standard_normal(n)
    psd = get_spectrum("tbt3352").as_function("vertical")
    a = gaussian_channel_from_normals(psd, 500.0, DX, u, (2.0, 200.0))
    assert np.array_equal(a, gaussian_channel_from_normals(psd, 500.0, DX, u.copy(), (2.0, 200.0)))
    assert np.array_equal(gaussian_channel_from_normals(psd, 500.0, DX, np.zeros(n), (2.0, 200.0)),
                          np.zeros(a.size))
    # the keyword draws exactly these normals from the generator
    b = synthesize_channel(psd, 500.0, DX, np.random.default_rng(0), (2.0, 200.0),
                           amplitudes="gaussian")
    assert np.array_equal(a, b)
    with pytest.raises(ValueError, match="expected"):
        gaussian_channel_from_normals(psd, 500.0, DX, u[:-1], (2.0, 200.0))
    with pytest.raises(ValueError, match="amplitudes"):
        synthesize_channel(psd, 500.0, DX, 0, (2.0, 200.0), amplitudes="uniform")


FIT_F = np.arange(4, 600, 10) / 1000.0   # 1/m; on the 1/1000 m FFT grid of a 1000 m profile


def _fits(family):
    """Known per-frequency fits: median decreasing as n^-2, shape varying with frequency."""
    shape = np.linspace(0.3, 0.8, FIT_F.size) if family == "lognorm" else np.linspace(2, 6, FIT_F.size)
    scale = 1e-3 * FIT_F ** -2.0 if family == "lognorm" else 1e-3 * FIT_F ** -2.0 / shape
    rows = [{"channel": ch, "spatial_frequency_per_m": f, "family": family, "shape": a,
             "scale": s, "best": family}
            for ch in ("vertical", "alignment") for f, a, s in zip(FIT_F, shape, scale)]
    return pd.DataFrame(rows)


@pytest.mark.parametrize("family, dist", [("lognorm", stats.lognorm), ("gamma", stats.gamma)])
def test_level_map_reproduces_the_fitted_quantiles(family, dist):
    """F^-1(Φ(v)) equals scipy's ppf at moderate v, and the model's PSD at a fitted frequency
    (an FFT frequency coinciding with a fit node: 0.104 1/m) at level v is that quantile; the
    unfitted channels stay flat and have no dimensions."""
    fits = _fits(family)
    v = np.array([-3.0, -1.0, 0.0, 0.7, 2.5])
    rows = fits[fits["channel"] == "vertical"]
    a, s = rows["shape"].to_numpy()[10], rows["scale"].to_numpy()[10]
    q = level_quantiles(np.full(v.size, family), np.full(v.size, a), np.full(v.size, s), v)
    assert np.allclose(q, dist(a, scale=s).ppf(stats.norm.cdf(v)), rtol=1e-10)
    model = GaussianIrregularityModel(1000 * 0.25 * 4 - DX, DX, (2.0, 200.0), fits=fits)
    assert set(model.channels) == {"vertical", "alignment"}
    k = int(np.argmin(abs(model.frequency_per_m - FIT_F[10])))
    assert model.frequency_per_m[k] == pytest.approx(FIT_F[10], rel=1e-12)
    for level in v:
        u = np.zeros(model.n_dims)
        u[model.slices["irregularity/vertical/level"]] = level
        g = model.band_psd(u)["vertical"][k]
        assert g == pytest.approx(dist(a, scale=s).ppf(stats.norm.cdf(level)), rel=1e-9)
    prof = model.profile(np.random.default_rng(1).standard_normal(model.n_dims))
    assert np.all(prof["cross_level_mm"] == 0) and np.all(prof["gauge_mm"] == 0)
    assert prof["vertical_mm"].std() > 0


def test_partial_frequency_correlation_keeps_the_marginal():
    """ρ = 0.3: the normal scores of two frequencies of 4000 level draws correlate by 0.3 within
    4 standard errors ((1 − ρ²)/sqrt(M) = 0.014) and the PSD at a fitted frequency keeps the
    fitted lognormal (KS not rejected at 1 %)."""
    model = GaussianIrregularityModel(999.75, DX, (2.0, 200.0), fits=_fits("lognorm"),
                                      frequency_score_correlation=0.3)
    assert model.slices["irregularity/vertical/level_scatter"].stop \
        - model.slices["irregularity/vertical/level_scatter"].start == FIT_F.size
    rng = np.random.default_rng(7)
    m = 4000
    scores = np.array([model.scores(rng.standard_normal(model.n_dims), "vertical")
                       for _ in range(m)])
    r = np.corrcoef(scores[:, 5], scores[:, 40])[0, 1]
    assert abs(r - 0.3) < 4 * (1 - 0.09) / np.sqrt(m)
    rows = _fits("lognorm")
    a, s = rows["shape"].iloc[5], rows["scale"].iloc[5]
    g = level_quantiles(np.full(m, "lognorm"), a, s, scores[:, 5])
    assert stats.kstest(g, stats.lognorm(a, scale=s).cdf).pvalue > 0.01


def test_population_levels_and_score_plateau():
    """Synthetic population: section levels with cross-channel correlation 0.7, log-sd 0.4 and
    Welch scatter χ²_12/12. The model's level correlation recovers 0.7 within 0.1 (SE with 200
    sections ≈ 0.04); the score plateau beyond lag 3 equals the level's share of the log
    variance, σ²/(σ² + ψ'(6)) = 0.16/(0.16 + 0.181) = 0.47, within 0.1; u = 0 gives a zero
    profile at the median PSD."""
    sp = get_spectrum("tbt3352")
    f = np.linspace(0.004, 0.55, 120)
    channels = ("vertical", "alignment", "cross_level", "gauge")
    mean = np.stack([sp.psd_mm2_m(c, f, extrapolate=True) for c in channels], axis=1)
    pop = synthetic_population(200, f, mean, np.random.default_rng(1))
    model = GaussianIrregularityModel.from_population(pop, 499.75, DX, (2.0, 200.0),
                                                      frequency_score_correlation="measured")
    off = model.level_correlation[np.triu_indices(4, 1)]
    assert np.all(abs(off - 0.7) < 0.1)
    from ttbpipe.tipm.distribution import fit_ordinate_distributions
    scores = ordinate_normal_scores(pop.psd_mm2_m, f, channels, fit_ordinate_distributions(pop))
    expected = 0.16 / (0.16 + 0.1813)
    assert np.all(abs(frequency_score_plateau(scores) - expected) < 0.1)
    zero = model.profile(np.zeros(model.n_dims))
    assert np.all(zero.drop(columns="chainage_m").to_numpy() == 0)
    sizes = sorted((s.start, s.stop) for s in model.slices.values())
    assert sizes[0][0] == 0 and sizes[-1][1] == model.n_dims
    assert all(a[1] == b[0] for a, b in zip(sizes, sizes[1:]))
