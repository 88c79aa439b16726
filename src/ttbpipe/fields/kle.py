"""Karhunen-Loeve expansion (KLE) of a stationary 1-D Gaussian field (paper eqs. 46-48).

The Fredholm problem  int C(x, y) phi(y) dy = lambda phi(x)  is discretised by the Nystrom method
with trapezoid weights W on the field's own points (the carriers: elements or supports):

    W^1/2 C W^1/2 v = lambda v,   phi = W^-1/2 v,

a symmetric eigenproblem solved by ``scipy.linalg.eigh`` (reference/uq.md). The eigenfunctions are
orthonormal in the weighted inner product, sum_i w_i phi_k(x_i) phi_l(x_i) = delta_kl, and the
discrete covariance is recovered exactly with all modes: C = Phi Lambda Phi^T. Unweighted
eigenvalues would come out as lambda / h and converge only to first order.

The field is  g(x) = sum_k sqrt(lambda_k) phi_k(x) xi_k  with independent standard normal xi_k
(eq. 46, zero mean, unit variance: the Nataf marginal map is applied afterwards).

Truncation: the first m modes are kept such that sum_{k<=m} lambda_k / trace >= variance_fraction,
where trace = sum_i w_i C(x_i, x_i) = sigma^2 * sum_i w_i is the exact total variance of the
discrete operator (not the sum over computed modes). Truncation leaves the pointwise variance
v(x) = sum_k lambda_k phi_k(x)^2 below 1, most at the ends of the line. With
``rescale_variance=True`` (the default, see docs/random_fields.md) each point is divided by
sqrt(v(x)) so that every carrier has exactly a standard normal marginal, which the Nataf map
x = F^-1(Phi(g)) requires for the configured marginal (mean, COV) to hold; the price is a slightly
altered (still valid) correlation structure: the correlation of the truncated expansion.
"""

from __future__ import annotations

import logging

import numpy as np
from scipy import linalg, optimize

from .covariance import correlation_matrix

log = logging.getLogger(__name__)

# Dense eigenproblems above this size compute only the leading modes, doubling the count until the
# variance fraction is reached.
_FULL_EIGH_LIMIT = 1500


def fix_eigenvector_signs(vectors: np.ndarray) -> np.ndarray:
    """Eigenvectors (columns) with a sign that does not depend on the LAPACK build.

    An eigenvector is defined up to its sign, and LAPACK's choice changes with the kernel
    (AVX2/AVX-512) and the number of BLAS threads: with the same standard-normal coefficients a
    KLE field then comes out different (measured: 2 % in the pad stiffness factors between a
    one-thread and a two-thread run). Each column is turned so that its projection on a fixed
    pseudo-random vector is positive: a generic direction, so the projection is far from zero for
    symmetric and antisymmetric modes alike (the largest component is not: an antisymmetric
    mode on a symmetric grid has two of equal size and opposite sign).
    """
    vectors = np.array(vectors, dtype=float, copy=True)
    probe = np.random.default_rng(20261201).standard_normal(vectors.shape[0])
    projection = probe @ vectors
    tiny = np.abs(projection) < 1e-8 * np.linalg.norm(probe) * np.linalg.norm(vectors, axis=0)
    largest = vectors[np.argmax(np.abs(vectors), axis=0), np.arange(vectors.shape[1])]
    sign = np.where(tiny, np.sign(largest), np.sign(projection))
    return vectors * np.where(sign == 0, 1.0, sign)


def trapezoid_weights(positions_m: np.ndarray) -> np.ndarray:
    """Trapezoid quadrature weights of a strictly increasing (possibly non-uniform) grid."""
    x = np.asarray(positions_m, dtype=float)
    if x.ndim != 1 or x.size == 0:
        raise ValueError("positions must be a non-empty 1-D array")
    if x.size == 1:
        return np.ones(1)
    steps = np.diff(x)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        raise ValueError(f"positions must be strictly increasing; x[{k}] = {x[k]} m, "
                         f"x[{k + 1}] = {x[k + 1]} m")
    w = np.empty_like(x)
    w[0], w[-1] = steps[0] / 2, steps[-1] / 2
    w[1:-1] = (steps[:-1] + steps[1:]) / 2
    return w


class KarhunenLoeve:
    """Truncated KLE of a unit-variance stationary field on given points.

    Parameters
    ----------
    positions_m:
        strictly increasing carrier positions (m).
    correlation_length_m, kernel:
        see :mod:`ttbpipe.fields.covariance`.
    variance_fraction:
        keep the fewest modes whose eigenvalues sum to at least this fraction of the total
        variance (ignored when ``n_modes`` is given).
    n_modes:
        keep exactly this many modes.
    rescale_variance:
        divide each point by the square root of its truncated variance (default True).

    Attributes
    ----------
    eigenvalues : (m,) retained eigenvalues, descending (units: m, for unit variance).
    eigenfunctions : (n_points, m) phi_k at the positions, weighted-orthonormal.
    captured_fraction : float, sum of retained eigenvalues / total variance.
    pointwise_variance : (n_points,) truncated variance before any rescaling.
    """

    def __init__(self, positions_m: np.ndarray, correlation_length_m: float,
                 kernel: str = "exponential", *, variance_fraction: float = 0.95,
                 n_modes: int | None = None, rescale_variance: bool = True) -> None:
        if not 0 < variance_fraction <= 1:
            raise ValueError(f"variance_fraction must be in (0, 1], got {variance_fraction}")
        self.positions_m = np.asarray(positions_m, dtype=float)
        self.weights = trapezoid_weights(self.positions_m)
        self.correlation_length_m = float(correlation_length_m)
        self.kernel = kernel
        self.rescale_variance = bool(rescale_variance)
        n = self.positions_m.size
        corr = correlation_matrix(self.positions_m, correlation_length_m, kernel)
        sqrt_w = np.sqrt(self.weights)
        operator = sqrt_w[:, None] * corr * sqrt_w[None, :]
        self.total_variance = float(np.sum(self.weights))  # trace of the operator, sigma = 1
        if n_modes is not None:
            if not 1 <= n_modes <= n:
                raise ValueError(f"n_modes={n_modes} outside [1, {n}]")
            values, vectors = self._leading(operator, n_modes)
        else:
            m = n if n <= _FULL_EIGH_LIMIT else min(n, 64)
            while True:
                values, vectors = self._leading(operator, m)
                cumulative = np.cumsum(values) / self.total_variance
                if cumulative[-1] >= variance_fraction * (1 - 1e-12) or m == n:
                    break
                m = min(n, 2 * m)
            cumulative = np.cumsum(values) / self.total_variance
            keep = int(np.searchsorted(cumulative, variance_fraction * (1 - 1e-12))) + 1
            keep = min(keep, values.size)
            values, vectors = values[:keep], vectors[:, :keep]
        self.eigenvalues = values
        self.eigenfunctions = vectors / sqrt_w[:, None]
        self.captured_fraction = float(np.sum(values) / self.total_variance)
        self.pointwise_variance = (self.eigenfunctions ** 2) @ values
        scale = np.sqrt(values)[None, :] * self.eigenfunctions
        if self.rescale_variance:
            scale = scale / np.sqrt(self.pointwise_variance)[:, None]
        self._modes_matrix = scale  # (n_points, m): g = xi @ modes_matrix.T
        log.debug("KLE: %d points, b = %g m, %s kernel: %d modes capture %.4f of the variance "
                  "(pointwise variance %.3f..%.3f before rescaling)", n, correlation_length_m,
                  kernel, values.size, self.captured_fraction, self.pointwise_variance.min(),
                  self.pointwise_variance.max())

    @staticmethod
    def _leading(operator: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
        """Largest m eigenpairs of a symmetric matrix, eigenvalues descending."""
        n = operator.shape[0]
        values, vectors = linalg.eigh(operator, subset_by_index=[n - m, n - 1])
        values, vectors = values[::-1], vectors[:, ::-1]
        # Round-off can make eigenvalues of a near-singular kernel slightly negative.
        return np.maximum(values, 0.0), fix_eigenvector_signs(vectors)

    @property
    def n_modes(self) -> int:
        return int(self.eigenvalues.size)

    @property
    def modes_matrix(self) -> np.ndarray:
        """(n_points, n_modes) matrix A with g = A xi (scaled eigenfunctions, rescaled if set)."""
        return self._modes_matrix

    def realize(self, coefficients: np.ndarray) -> np.ndarray:
        """Standard-normal KL coefficients (..., n_modes) -> field values (..., n_points)."""
        coefficients = np.asarray(coefficients, dtype=float)
        if coefficients.shape[-1] != self.n_modes:
            raise ValueError(f"expected {self.n_modes} coefficients, got {coefficients.shape[-1]}")
        return coefficients @ self._modes_matrix.T


def modes_for_fractions(positions_m: np.ndarray, correlation_length_m: float,
                        kernel: str = "exponential",
                        fractions: tuple[float, ...] = (0.95, 0.99)) -> dict[float, int]:
    """Number of KL modes capturing each variance fraction on the given grid (all eigenvalues)."""
    weights = trapezoid_weights(positions_m)
    sqrt_w = np.sqrt(weights)
    operator = sqrt_w[:, None] * correlation_matrix(positions_m, correlation_length_m,
                                                    kernel) * sqrt_w[None, :]
    values = np.sort(linalg.eigvalsh(operator))[::-1]
    cumulative = np.cumsum(values) / np.sum(weights)
    return {f: int(np.searchsorted(cumulative, f * (1 - 1e-12))) + 1 for f in fractions}


def exponential_kernel_eigenvalues(n_modes: int, half_length_m: float,
                                   correlation_length_m: float,
                                   variance: float = 1.0) -> np.ndarray:
    """Exact KL eigenvalues of C = variance exp(-|x - y| / b) on [-a, a], descending.

    Ghanem & Spanos (1991), "Stochastic finite elements: a spectral approach", sec. 2.3.3:
    with c = 1/b, even modes solve c cos(w a) - w sin(w a) = 0 on (k pi, k pi + pi/2)/a, odd
    modes solve w cos(w a) + c sin(w a) = 0 on (k pi + pi/2, (k + 1) pi)/a, and
    lambda = 2 c variance / (w^2 + c^2). Classic check: a = b = 1 gives lambda_1 = 1.14931 at
    w = 0.860334 (reference/uq.md).
    """
    a, c = float(half_length_m), 1.0 / float(correlation_length_m)

    def even(w: float) -> float:
        return c * np.cos(w * a) - w * np.sin(w * a)

    def odd(w: float) -> float:
        return w * np.cos(w * a) + c * np.sin(w * a)

    roots = []
    k = 0
    while len(roots) < n_modes:
        lo, mid, hi = k * np.pi / a, (k + 0.5) * np.pi / a, (k + 1) * np.pi / a
        # Open brackets: the functions do not change sign inside except at the single root.
        roots.append(optimize.brentq(even, lo, mid, xtol=1e-15, rtol=1e-15))
        roots.append(optimize.brentq(odd, mid, hi, xtol=1e-15, rtol=1e-15))
        k += 1
    w = np.sort(np.asarray(roots))[:n_modes]
    return 2.0 * c * variance / (w * w + c * c)
