"""Probability density of per-sample extremes: weighted Gaussian KDE with boundary treatment.

Built on :class:`scipy.stats.gaussian_kde` (``weights=`` carries the TIPM probabilities; the
bandwidth is Scott's rule on Kish's effective size, scipy's default). Most extremes are bounded
below by 0 (ratios, absolute maxima), and a plain KDE puts mass below the bound and underestimates
the density next to it. Two treatments (``docs/reliability.md``):

* ``'log'``: estimate the density ``g`` of ``y = log(x - lower)`` and transform back,
  ``f(x) = g(log(x - lower)) / (x - lower)``. The density goes to 0 at the bound, as it does for
  maxima of positive quantities (Gumbel-, lognormal-like); needs every value > lower.
  (Silverman 1986, *Density Estimation*, section 2.10.)
* ``'reflect'``: ``f(x) = k(x) + k(2 lower - x) [+ k(2 upper - x)]`` inside the bounds, 0 outside
  (Schuster 1985, Commun. Stat. Theory 14:1123). Keeps the density finite and non-zero at the
  bound (zero slope there); handles values equal to the bound.

``'auto'`` uses ``'log'`` when only a lower bound is given and all values exceed it, otherwise
``'reflect'`` when a bound is given (logging why), otherwise ``'none'``.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy import stats

from .schema import EXTREMES_SPEC

log = logging.getLogger(__name__)

BOUNDARY_METHODS = ("auto", "none", "log", "reflect")


def bounds_for(column: str) -> tuple[float | None, float | None]:
    """Physical (lower, upper) bounds of a documented extremes column; None when unbounded."""
    spec = EXTREMES_SPEC.get(column)
    if spec is None:
        return None, None
    lower = spec.lower if math.isfinite(spec.lower) else None
    upper = spec.upper if math.isfinite(spec.upper) else None
    return lower, upper


class ExtremeValueKDE:
    """Weighted Gaussian KDE of one extreme-value column with a boundary treatment.

    Parameters: ``values`` (n,), ``weights`` (n,) > 0 or None, ``lower``/``upper`` bounds (None:
    unbounded), ``boundary`` one of :data:`BOUNDARY_METHODS`, ``bw_method`` passed to scipy.
    """

    def __init__(self, values, weights=None, *, lower: float | None = None,
                 upper: float | None = None, boundary: str = "auto", bw_method=None) -> None:
        values = np.asarray(values, dtype=float).ravel()
        if boundary not in BOUNDARY_METHODS:
            raise ValueError(f"boundary must be one of {BOUNDARY_METHODS}, got {boundary!r}")
        if not np.isfinite(values).all():
            raise ValueError("KDE input contains NaN or infinite values")
        if weights is not None:
            weights = np.asarray(weights, dtype=float).ravel()
            if weights.shape != values.shape or not (weights > 0).all():
                raise ValueError("weights must be positive, one per value")
        if values.size < 2 or np.ptp(values) == 0.0:
            raise ValueError(f"cannot estimate a density from {values.size} value(s) with no "
                             "spread; plot the value as a line instead")
        if lower is not None and (values < lower).any():
            raise ValueError(f"{int((values < lower).sum())} values below the lower bound {lower}")
        if upper is not None and (values > upper).any():
            raise ValueError(f"{int((values > upper).sum())} values above the upper bound {upper}")
        if boundary == "auto":
            if lower is not None and upper is None and (values > lower).all():
                boundary = "log"
            elif lower is not None or upper is not None:
                if lower is not None and upper is None:
                    log.info("KDE: %d value(s) equal the lower bound %g; using reflection instead "
                             "of the log transform", int((values == lower).sum()), lower)
                boundary = "reflect"
            else:
                boundary = "none"
        if boundary == "log":
            if lower is None or upper is not None:
                raise ValueError("boundary='log' needs a lower bound and no upper bound")
            if not (values > lower).all():
                raise ValueError(f"boundary='log' needs every value > {lower}; "
                                 "use boundary='reflect'")
            data = np.log(values - lower)
        else:
            data = values
        self.values, self.weights = values, weights
        self.lower, self.upper, self.boundary = lower, upper, boundary
        self._kde = stats.gaussian_kde(data, bw_method=bw_method, weights=weights)

    @property
    def bandwidth(self) -> float:
        """Kernel standard deviation in the estimation variable (x, or log(x - lower))."""
        return float(np.sqrt(self._kde.covariance[0, 0]))

    def pdf(self, x) -> np.ndarray:
        """Density at ``x`` (per unit of the column)."""
        x = np.asarray(x, dtype=float)
        out = np.zeros_like(x)
        inside = np.ones_like(x, dtype=bool)
        if self.lower is not None:
            inside &= x >= self.lower
        if self.upper is not None:
            inside &= x <= self.upper
        xi = x[inside]
        if self.boundary == "log":
            with np.errstate(divide="ignore"):
                shifted = xi - self.lower
                dens = np.where(shifted > 0,
                                self._kde(np.log(np.where(shifted > 0, shifted, 1.0)))
                                / np.where(shifted > 0, shifted, 1.0), 0.0)
        else:
            dens = self._kde(xi)
            if self.boundary == "reflect":
                if self.lower is not None:
                    dens = dens + self._kde(2.0 * self.lower - xi)
                if self.upper is not None:
                    dens = dens + self._kde(2.0 * self.upper - xi)
        out[inside] = dens
        return out

    __call__ = pdf

    def grid(self, n: int = 512, pad: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
        """(x, pdf) on ``n`` points covering the data plus ``pad`` bandwidths, clipped to bounds."""
        h = self.bandwidth
        if self.boundary == "log":
            y = np.log(self.values - self.lower)
            lo = self.lower + math.exp(y.min() - pad * h)
            hi = self.lower + math.exp(y.max() + pad * h)
            lo = self.lower if lo - self.lower < 0.05 * (hi - lo) else lo
        else:
            lo, hi = self.values.min() - pad * h, self.values.max() + pad * h
            if self.lower is not None:
                lo = max(lo, self.lower)
            if self.upper is not None:
                hi = min(hi, self.upper)
        x = np.linspace(lo, hi, n)
        pdf = self.pdf(x)
        # Trim far tails (the log transform's padding is long on the right), keeping the data.
        keep = (pdf >= 1e-3 * pdf.max()) | ((x >= self.values.min()) & (x <= self.values.max()))
        first, last = np.flatnonzero(keep)[[0, -1]]
        if first > 0 or last < n - 1:
            x = np.linspace(x[max(first - 1, 0)], x[min(last + 1, n - 1)], n)
            pdf = self.pdf(x)
        return x, pdf
