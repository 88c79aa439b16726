"""Plain Monte Carlo estimate of a failure probability: the reference for the other estimators.

``p = k/N`` from N independent standard-normal points; interval from the binomial estimator of
:mod:`ttbpipe.stats.reliability` (Wilson score by default, Clopper-Pearson on request), c.o.v.
``sqrt((1-p)/(N p))``. Point ``i`` is drawn from ``SeedSequence([seed, RARE_EVENT,
RARE_EVENT_MONTE_CARLO, i])`` (ttbpipe.streams), so the estimate does not depend on the batch
size used to evaluate the points.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .. import streams
from .result import FailureProbability

__all__ = ["indexed_points", "monte_carlo_points", "monte_carlo"]


def indexed_points(seed: int, estimator: int, n_dims: int, indices: np.ndarray) -> np.ndarray:
    """Standard-normal points with the given indices, shape ``(len(indices), n_dims)``: point i
    of ``estimator`` (a ``streams.RARE_EVENT_*`` word) from ``SeedSequence([seed, RARE_EVENT,
    estimator, i])``, so that a point never depends on how the caller batches them."""
    indices = np.asarray(indices, dtype=np.int64)
    out = np.empty((indices.size, int(n_dims)))
    for row, index in enumerate(indices):
        seq = np.random.SeedSequence([int(seed), streams.RARE_EVENT, int(estimator), int(index)])
        out[row] = np.random.default_rng(seq).standard_normal(int(n_dims))
    return out


def monte_carlo_points(seed: int, n_dims: int, indices: np.ndarray) -> np.ndarray:
    """Plain Monte Carlo's points with the given indices (:func:`indexed_points`)."""
    return indexed_points(seed, streams.RARE_EVENT_MONTE_CARLO, n_dims, indices)


def evaluate_limit_state(g: Callable[[np.ndarray], np.ndarray], points: np.ndarray,
                         what: str) -> np.ndarray:
    """``g(points)`` checked: shape (n,), finite (a NaN is a failed model run, never a value)."""
    values = np.asarray(g(points), dtype=float)
    if values.shape != (points.shape[0],):
        raise ValueError(f"{what}: the limit-state function returned shape {values.shape} for "
                         f"{points.shape[0]} points; it must return one value per row")
    bad = ~np.isfinite(values)
    if bad.any():
        raise FloatingPointError(
            f"{what}: the limit-state function returned {int(bad.sum())} non-finite values "
            f"(first at row {int(np.flatnonzero(bad)[0])}); a failed model run cannot be counted "
            "as safe or failed: fix the run (see its log) or make g return a finite value")
    return values


def monte_carlo(g: Callable[[np.ndarray], np.ndarray], n_dims: int, *, seed: int = 0,
                n_samples: int = 10_000, batch_size: int = 10_000,
                confidence_level: float = 0.95, interval: str = "wilson") -> FailureProbability:
    """Crude Monte Carlo: ``n_samples`` points, evaluated ``batch_size`` at a time."""
    # imported here: ttbpipe.stats.reliability imports this package's tail model
    from ..stats.reliability import BinomialExceedance

    if n_samples < 1 or batch_size < 1:
        raise ValueError("n_samples and batch_size must be >= 1")
    failed = np.empty(int(n_samples), dtype=bool)
    for start in range(0, int(n_samples), int(batch_size)):
        idx = np.arange(start, min(int(n_samples), start + int(batch_size)))
        values = evaluate_limit_state(g, monte_carlo_points(seed, n_dims, idx),
                                      f"Monte Carlo points {idx[0]}-{idx[-1]}")
        failed[idx] = values <= 0.0
    est = BinomialExceedance(confidence_level, interval).estimate(failed)
    p = est.probability
    cov = float(np.sqrt((1.0 - p) / (n_samples * p))) if p > 0 else float("inf")
    return FailureProbability(p, est.ci_low, est.ci_high, cov, int(n_samples),
                              f"Monte Carlo, {n_samples} samples, {interval} interval",
                              confidence_level,
                              {"n_failed": est.n_exceed, "upper_one_sided": est.upper_one_sided})
