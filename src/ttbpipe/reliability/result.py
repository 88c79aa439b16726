"""The result of a failure-probability estimate: probability, interval, c.o.v., cost, method.

One result type for every estimator of :mod:`ttbpipe.reliability` (plain Monte Carlo, subset
simulation, the extreme-value tail model), so that estimates of one limit by different methods
can be put side by side and cross-checked (docs/reliability.md, "Rare events").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

__all__ = ["FailureProbability", "reliability_index", "lognormal_interval"]


def reliability_index(probability: float) -> float:
    """Generalised reliability index ``beta = -Phi^-1(p)`` (EN 1990 Annex C, eq. C.1).

    ``+inf`` at p = 0, ``-inf`` at p = 1, NaN for NaN (a table row without an estimate)
    (``scipy.stats.norm.isf`` keeps full precision for small p, where ``ppf(1 - p)`` would not).
    """
    p = float(probability)
    if np.isnan(p):
        return float("nan")
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"probability must lie in [0, 1], got {probability!r}")
    return float(stats.norm.isf(p))


def lognormal_interval(probability: float, cov: float,
                       confidence_level: float) -> tuple[float, float]:
    """Two-sided interval of a positive estimator taken as lognormal with its mean and c.o.v.

    ``ln p_hat ~ N(ln p - s^2/2, s^2)``, ``s^2 = ln(1 + cov^2)``, so the interval is
    ``p_hat exp(s^2/2 -+ z s)``. For subset simulation the estimator is a product of level
    probabilities, whose logarithm is a sum of nearly independent terms: the lognormal form is
    the usual one (Au & Wang 2014, *Engineering Risk Assessment with Subset Simulation*, Wiley,
    section 5.7) and keeps the interval inside (0, 1] better than a normal one does.
    """
    if not probability > 0.0 or not np.isfinite(cov) or cov < 0.0:
        return 0.0, 1.0
    z = float(stats.norm.ppf(0.5 + 0.5 * confidence_level))
    s = float(np.sqrt(np.log1p(cov * cov)))
    centre = probability * np.exp(0.5 * s * s)
    return float(centre * np.exp(-z * s)), float(min(1.0, centre * np.exp(z * s)))


@dataclass(frozen=True)
class FailureProbability:
    """``P(g(U) <= 0)`` for standard-normal U, with its uncertainty and cost.

    Attributes
    ----------
    probability
        The estimate.
    ci_low, ci_high
        Two-sided confidence interval at ``confidence_level``.
    cov
        Estimated coefficient of variation of the estimator (``inf`` when p = 0).
    n_evaluations
        Number of limit-state evaluations (model runs) spent.
    method
        What produced it, in words (estimator, interval, settings).
    details
        Method-specific diagnostics (subset simulation: the levels table, acceptance rates).
    """

    probability: float
    ci_low: float
    ci_high: float
    cov: float
    n_evaluations: int
    method: str
    confidence_level: float = 0.95
    details: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def reliability_index(self) -> float:
        """``beta = -Phi^-1(p)`` of the estimate."""
        return reliability_index(self.probability)

    @property
    def beta_interval(self) -> tuple[float, float]:
        """The interval on beta that corresponds to ``[ci_low, ci_high]`` (low p = high beta)."""
        return reliability_index(self.ci_high), reliability_index(self.ci_low)

    def covers(self, exact: float) -> bool:
        """Whether ``exact`` lies in the interval (inclusive)."""
        return self.ci_low <= exact <= self.ci_high

    def as_row(self) -> dict[str, Any]:
        """Flat dict for a results table (no details)."""
        return {"probability": self.probability, "ci_low": self.ci_low, "ci_high": self.ci_high,
                "cov": self.cov, "reliability_index": self.reliability_index,
                "n_evaluations": int(self.n_evaluations), "method": self.method,
                "confidence_level": self.confidence_level}

    def __str__(self) -> str:
        level = f"{100 * self.confidence_level:g} %"
        return (f"P = {self.probability:.3g} [{self.ci_low:.3g}, {self.ci_high:.3g}] ({level}), "
                f"c.o.v. {self.cov:.3g}, beta = {self.reliability_index:.3g}, "
                f"{self.n_evaluations} evaluations, {self.method}")
