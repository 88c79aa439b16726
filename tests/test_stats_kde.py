"""Weighted KDE of extremes with boundary treatment (ttbpipe.stats.kde).

References: the known densities the synthetic data are drawn from (scipy.stats distributions);
integrals by scipy.integrate.quad. Tolerances are from the KDE error at these sample sizes
(integrated absolute error ~ n^(-2/5); measured values in each docstring).
"""

import numpy as np
import pytest
from scipy import integrate, stats

from ttbpipe.stats.kde import ExtremeValueKDE, bounds_for


def _l1(kde, dist, lo, hi):
    """Integrated absolute error on [lo, hi] (fine trapezoid grid)."""
    x = np.linspace(lo, hi, 4001)
    return np.trapezoid(np.abs(kde.pdf(x) - dist.pdf(x)), x)


@pytest.mark.parametrize("boundary", ["log", "reflect", "none"])
def test_density_integrates_to_one(boundary):
    """Integral over the support equals 1 within 1e-3 (quad tolerance 1e-8; the reflected
    density's missing mass beyond a far upper bound is nil here)."""
    x = stats.lognorm(0.4, scale=0.3).rvs(300, random_state=1)
    kde = ExtremeValueKDE(x, lower=None if boundary == "none" else 0.0, boundary=boundary)
    lo = -np.inf if boundary == "none" else 0.0
    total = integrate.quad(kde.pdf, lo, np.inf, limit=500, points=None)[0] if boundary == "none" \
        else integrate.quad(kde.pdf, 0.0, 5.0, limit=500)[0] + integrate.quad(kde.pdf, 5.0, np.inf)[0]
    assert total == pytest.approx(1.0, abs=1e-3)


def test_log_transform_recovers_lognormal():
    """Lognormal(sigma 0.5) maxima, 4000 samples: integrated absolute error of the log-KDE below
    0.06 (measured 0.029); the density is 0 below the bound."""
    dist = stats.lognorm(0.5, scale=1.0)
    x = dist.rvs(4000, random_state=2)
    kde = ExtremeValueKDE(x, lower=0.0)
    assert kde.boundary == "log"
    assert _l1(kde, dist, 1e-6, 10.0) < 0.06
    assert kde.pdf(np.array([-0.1]))[0] == 0.0


def test_reflection_fixes_the_boundary_bias():
    """Exponential(1) data, density 1 at the bound x = 0: the reflected KDE gives f(0) within
    0.2 of 1 (kernel bias O(h); measured 0.86), while the plain KDE gives about half (mass leaks
    below 0); integrated absolute error below 0.08 for reflection on [0, 8] (4000 samples,
    measured 0.038)."""
    dist = stats.expon()
    x = dist.rvs(4000, random_state=3)
    reflected = ExtremeValueKDE(x, lower=0.0, boundary="reflect")
    plain = ExtremeValueKDE(x, boundary="none")
    assert reflected.pdf(np.array([0.0]))[0] == pytest.approx(1.0, abs=0.2)
    assert plain.pdf(np.array([0.0]))[0] < 0.65
    assert _l1(reflected, dist, 0.0, 8.0) < 0.08


def test_weighted_kde_matches_target_density():
    """Importance weights: samples from Exp(1) weighted by the density ratio Gamma(2,1)/Exp(1)
    = x estimate the Gamma(2,1) density; 6000 samples, integrated absolute error below 0.08
    (measured 0.043), whereas the unweighted estimate misses it by more than 0.3 (measured 0.73)."""
    x = stats.expon().rvs(6000, random_state=4)
    target = stats.gamma(2.0)
    weighted = ExtremeValueKDE(x, weights=x, lower=0.0, boundary="log")
    unweighted = ExtremeValueKDE(x, lower=0.0, boundary="log")
    assert _l1(weighted, target, 1e-6, 12.0) < 0.08
    assert _l1(unweighted, target, 1e-6, 12.0) > 0.3


def test_auto_boundary_and_errors():
    """'auto' picks log for strictly positive data with a lower bound, reflection when a value
    sits on the bound or an upper bound exists; degenerate input is a clear error."""
    assert ExtremeValueKDE([0.1, 0.2, 0.4], lower=0.0).boundary == "log"
    assert ExtremeValueKDE([0.0, 0.2, 0.4], lower=0.0).boundary == "reflect"
    assert ExtremeValueKDE([0.1, 0.2, 0.4], upper=1.0).boundary == "reflect"
    assert bounds_for("max_wheel_unloading_ratio") == (None, 1.0)
    assert bounds_for("max_derailment_coefficient") == (0.0, None)
    with pytest.raises(ValueError, match="no spread"):
        ExtremeValueKDE([0.3, 0.3, 0.3])
    with pytest.raises(ValueError, match="below the lower bound"):
        ExtremeValueKDE([-0.1, 0.3], lower=0.0)
