"""Line sampling (ttbpipe.reliability.line_sampling) against limit states with exact answers.

References (independent of the code):
* linear limit state g(u) = beta - a.u, |a| = 1: P = Phi(-beta) (scipy.stats.norm.sf);
* parabolic limit state g(u) = beta - u_1 + (kappa/2) sum_{i=2}^{k+1} u_i^2: with X ~ chi2_k
  independent of u_1, P = E[Phi(-(beta + kappa X/2))], a one-dimensional integral evaluated by
  scipy.integrate.quad to 1e-12 relative.
Repeated-seed checks compare the spread and coverage of the estimates with the exact value;
docs/reliability.md section 12 has the measured table (benchmarks/line_sampling_table.py).
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy import integrate, stats

from ttbpipe.reliability import estimate_failure_probability


def linear_limit_state(beta: float, n_dims: int):
    a = np.ones(n_dims) / np.sqrt(n_dims)
    return (lambda u: beta - u @ a), a


def parabolic_limit_state(beta: float, kappa: float, k: int):
    def g(u):
        return beta - u[:, 0] + 0.5 * kappa * np.sum(u[:, 1:k + 1] ** 2, axis=1)
    exact, _ = integrate.quad(
        lambda x: stats.norm.sf(beta + 0.5 * kappa * x) * stats.chi2.pdf(x, k),
        0.0, np.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return g, exact


def test_along_the_normal_of_a_linear_limit_state_line_sampling_is_exact():
    """Every line of a linear limit state along its own normal crosses at c = beta, so
    P = Phi(-beta) with no scatter: equal to 1e-9 relative (the root search's tolerance
    1e-3 in c is reached in one secant step on a straight line), c.o.v. ~ 0, and four
    evaluations per line (two starting points, one bracketing step from 4 to 5.5, one secant)."""
    g, a = linear_limit_state(4.75, 500)
    result = estimate_failure_probability(g, 500, method="line_sampling", seed=3, n_lines=50,
                                          direction=a)
    assert result.probability == pytest.approx(stats.norm.sf(4.75), rel=1e-9)
    assert result.cov < 1e-6
    assert result.n_evaluations == 50 * 4
    assert np.allclose(result.details["crossings"], 4.75, atol=1e-9)


def test_parabolic_limit_state_near_1e_minus_6_over_seeds():
    """Curved limit state (kappa 0.1 over 10 of 200 dimensions), P = 4.63e-7, 100 seeds of the
    default settings (direction from a 4-level subset simulation of 500 points refined by 100
    lines, 200 estimating lines; about 2950 evaluations each, 0.2 s).

    Measured (seeds 0-99): mean / exact 0.991, c.o.v. observed 0.081, reported 0.074, coverage
    of the nominal 95 % interval 0.90. Asserted: c.o.v. <= 0.3 at <= 3500 evaluations (the
    rare-event target: p near 1e-6 at a few thousand evaluations), the mean within 5 % (the
    scatter of the mean is 0.6 %), coverage >= 0.88 (nominal minus three binomial standard
    deviations of 100 runs), reported / observed c.o.v. within 0.7-1.3."""
    g, exact = parabolic_limit_state(4.5, 0.1, 10)
    assert 4.0e-7 < exact < 5.0e-7
    logging.disable(logging.WARNING)
    try:
        runs = [estimate_failure_probability(g, 200, method="line_sampling", seed=seed)
                for seed in range(100)]
    finally:
        logging.disable(logging.NOTSET)
    p = np.array([r.probability for r in runs])
    observed = p.std(ddof=1) / p.mean()
    assert max(r.n_evaluations for r in runs) <= 3500
    assert np.median([r.cov for r in runs]) <= 0.3
    assert abs(p.mean() / exact - 1.0) < 0.05
    assert np.mean([r.covers(exact) for r in runs]) >= 0.88
    assert 0.7 <= np.median([r.cov for r in runs]) / observed <= 1.3


def test_linear_limit_state_in_2000_dimensions():
    """beta = 4.75 (P = 1.02e-6) in 2000 dimensions, more than the subset simulation's 1850
    points: its plane (ridge regression, penalty by generalised cross-validation) is not the
    exact normal (cosine 0.96); refined with the first 100 lines' points it is closer (measured
    0.984-0.991), and the estimate scatters a little (c.o.v. observed 0.055 over 20 seeds,
    reported 0.063, coverage 0.95; benchmarks/line_sampling_table.py). One seed (the fit's SVD
    of about 2250 x 2000 takes tens of seconds on a loaded 2-core machine; the spread over seeds
    is the table's): the exact value inside the interval, the reported c.o.v. <= 0.3, <= 3500
    evaluations, cosine > 0.9."""
    g, a = linear_limit_state(4.75, 2000)
    exact = stats.norm.sf(4.75)
    result = estimate_failure_probability(g, 2000, method="line_sampling", seed=0)
    assert result.covers(exact), result
    assert result.cov <= 0.3
    assert result.n_evaluations <= 3500
    assert float(result.details["direction"] @ a) > 0.9


def test_a_line_depends_only_on_the_seed_and_its_index():
    """With a given direction, line i's crossing is the same whether 40 or 100 lines are drawn
    (SeedSequence([seed, RARE_EVENT, RARE_EVENT_LINE, i]))."""
    g, exact = parabolic_limit_state(3.0, 0.1, 5)
    direction = np.zeros(30)
    direction[0] = 1.0
    few = estimate_failure_probability(g, 30, method="line_sampling", seed=7, n_lines=40,
                                       direction=direction)
    many = estimate_failure_probability(g, 30, method="line_sampling", seed=7, n_lines=100,
                                        direction=direction)
    assert np.array_equal(few.details["crossings"], many.details["crossings"][:40])
    assert many.covers(exact)


def test_bad_settings_are_named():
    g, _ = linear_limit_state(3.0, 10)
    with pytest.raises(ValueError, match="direction must be a finite, non-zero array of 10"):
        estimate_failure_probability(g, 10, method="line_sampling", direction=np.ones(9))
    with pytest.raises(ValueError, match="n_lines"):
        estimate_failure_probability(g, 10, method="line_sampling", n_lines=1)
    with pytest.raises(ValueError, match="direction must be 'subset' or an array"):
        estimate_failure_probability(g, 10, method="line_sampling", direction="form")


def test_a_series_system_is_refused_not_underestimated():
    """g = beta - max_k u_k over 20 of 200 dimensions (a union of 20 half-spaces, like the
    maximum of a response over time): P = 1 - Phi(beta)^20 = 6.3e-4 exactly, but no single
    direction sees more than one of the half-spaces. Without the check the estimate was 1e-5 to
    1e-13 (measured on seeds 0-2, 162-195 of 200 lines without a crossing); the estimator must
    stop and name subset simulation instead, and subset simulation must cover the exact value."""
    beta, k = 4.0, 20
    exact = 1.0 - stats.norm.cdf(beta) ** k

    def g(u):
        return beta - u[:, :k].max(axis=1)

    with pytest.raises(RuntimeError, match="use method='subset'"):
        estimate_failure_probability(g, 200, method="line_sampling", seed=0)
    assert estimate_failure_probability(g, 200, method="subset", seed=0).covers(exact)
