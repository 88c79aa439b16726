"""Nataf transformation: correlated random variables with arbitrary marginals.

The paper's "linear-nonlinear transformation" (Xu, Zhai & Li, section 3.1.2, eqs. 37-45):

1. each variable x_i with marginal CDF F_i is the image of a standard normal g_i,
   x_i = F_i^-1(Phi(g_i)) (eq. 41);
2. the Gaussian-space correlation r_g of each pair is solved from the target Pearson correlation
   r_x through the double integral of eq. 42;
3. correlated standard normals come from the Cholesky factor of R_g (eqs. 43-44) and are mapped
   back through the marginals (eq. 45).

Step 2 uses closed forms where they exist (Liu & Der Kiureghian 1986, "Multivariate distribution
models with prescribed marginals and covariances", Prob. Eng. Mech. 1(2); reference/uq.md) and
otherwise 2-D Gauss-Hermite quadrature of E[x_i x_j] with Brent's bracketing root finder on
r_g in [-1, 1] (the map r_g -> r_x is increasing, so the root is unique).
"""

from __future__ import annotations

import logging
from typing import Sequence

import numpy as np
from numpy.polynomial.hermite_e import hermegauss
from scipy import optimize, special

log = logging.getLogger(__name__)

# Relative tolerance on the unit diagonal / symmetry of a target correlation matrix.
_MATRIX_TOL = 1e-10


class InfeasibleCorrelationError(ValueError):
    """A target Pearson correlation cannot be reached with the given marginals."""


def marginal_ppf_of_normal(dist, standard_normal: np.ndarray) -> np.ndarray:
    """Return F^-1(Phi(z)) for a frozen scipy.stats distribution, accurate in both tails.

    For z > 0, Phi(z) rounds to 1 long before the distribution's upper tail is exhausted
    (Phi(8.3) == 1.0 in double precision), and F^-1(1) = inf. The upper half therefore goes through
    the survival function: F^-1(Phi(z)) = isf(Phi(-z)) (reference/uq.md, "tail trap").
    """
    z = np.asarray(standard_normal, dtype=float)
    out = np.empty_like(z)
    upper = z > 0
    out[~upper] = dist.ppf(special.ndtr(z[~upper]))
    out[upper] = dist.isf(special.ndtr(-z[upper]))
    return out


def _fast_marginal_map(dist):
    """Exact closed-form F^-1(Phi(z)) for normal and lognormal marginals, else None.

    normal: mu + sigma z; lognormal (scipy lognorm(s, loc, scale)): loc + scale exp(s z). These
    avoid scipy's per-call overhead in the sampling loop and are exact in both tails.
    """
    name = _family(dist)
    if name == "norm":
        mean, std = float(dist.mean()), float(dist.std())
        return lambda z: mean + std * z
    if name == "lognorm":
        s = _lognormal_sigma(dist)
        loc = float(dist.support()[0])
        scale = float(dist.median()) - loc
        return lambda z: loc + scale * np.exp(s * z)
    return None


def _family(dist) -> str:
    """scipy name of a frozen distribution's family ('norm', 'lognorm', ...)."""
    return getattr(getattr(dist, "dist", None), "name", type(dist).__name__)


def _lognormal_sigma(dist) -> float:
    """Log-space standard deviation s of a (possibly shifted) scipy lognorm."""
    return float(dist.args[0] if dist.args else dist.kwds["s"])


def _closed_form(dist_i, dist_j, rho_x: float) -> float | None:
    """Gaussian correlation of a pair from a closed form, or None when there is none.

    Sources (reference/uq.md; Liu & Der Kiureghian 1986, table 2 and eqs. for lognormals), with
    s = sqrt(ln(1 + V^2)) and V the coefficient of variation of the un-shifted lognormal
    (V = sqrt(exp(s^2) - 1); a location shift does not change correlations):

    * normal-normal        r_g = r_x
    * normal-lognormal     r_g = r_x V / s
    * lognormal-lognormal  r_g = ln(1 + r_x V1 V2) / (s1 s2)
    * uniform-uniform      r_g = 2 sin(pi r_x / 6)
    * normal-uniform       r_g = r_x sqrt(pi / 3)

    May return a value outside [-1, 1] (or NaN), which the caller reports as infeasible.
    """
    fam = sorted([(_family(dist_i), dist_i), (_family(dist_j), dist_j)], key=lambda t: t[0])
    (name_a, dist_a), (name_b, dist_b) = fam
    if name_a == "norm" and name_b == "norm":
        return rho_x
    if name_a == "lognorm" and name_b == "norm":
        s = _lognormal_sigma(dist_a)
        return rho_x * np.sqrt(np.expm1(s * s)) / s
    if name_a == "lognorm" and name_b == "lognorm":
        s1, s2 = _lognormal_sigma(dist_a), _lognormal_sigma(dist_b)
        v1, v2 = np.sqrt(np.expm1(s1 * s1)), np.sqrt(np.expm1(s2 * s2))
        arg = 1.0 + rho_x * v1 * v2
        return np.log(arg) / (s1 * s2) if arg > 0 else np.nan
    if name_a == "uniform" and name_b == "uniform":
        return 2.0 * np.sin(np.pi * rho_x / 6.0)
    if name_a == "norm" and name_b == "uniform":
        return rho_x * np.sqrt(np.pi / 3.0)
    return None


class NatafTransform:
    """Correlated variables with given marginals and Pearson correlation (paper eqs. 37-45).

    Parameters
    ----------
    marginals:
        frozen ``scipy.stats`` distributions with finite variance, one per variable.
    correlation:
        target Pearson correlation matrix R_x (symmetric, unit diagonal).
    names:
        optional variable names used in messages.
    quadrature_nodes:
        Gauss-Hermite nodes per axis for pairs without a closed form (>= 32; reference/uq.md:
        8 nodes leave errors near 1e-3).
    use_closed_forms:
        set False to force quadrature everywhere (used by the tests to cross-check both paths).
    repair:
        ``"higham"`` (default): a solved R_g that is not positive definite is replaced by the
        nearest correlation matrix (Higham 2002) with a logged warning; ``"raise"``: error.

    Attributes
    ----------
    gaussian_correlation : ndarray
        R_g, the solved (and possibly repaired) Gaussian-space correlation.
    cholesky_factor : ndarray
        lower-triangular C with C C^T = R_g.
    """

    def __init__(self, marginals: Sequence, correlation: np.ndarray, *,
                 names: Sequence[str] | None = None, quadrature_nodes: int = 64,
                 use_closed_forms: bool = True, repair: str = "higham",
                 xtol: float = 1e-13) -> None:
        self.marginals = list(marginals)
        n = len(self.marginals)
        self.names = list(names) if names is not None else [f"x{i}" for i in range(n)]
        if len(self.names) != n:
            raise ValueError(f"{len(self.names)} names for {n} marginals")
        if quadrature_nodes < 32:
            raise ValueError(f"quadrature_nodes={quadrature_nodes}: use at least 32 "
                             "(8 nodes give correlation errors near 1e-3)")
        if repair not in ("higham", "raise"):
            raise ValueError(f"repair={repair!r}: expected 'higham' or 'raise'")
        self.target_correlation = self._check_matrix(np.asarray(correlation, dtype=float), n)
        self.quadrature_nodes = int(quadrature_nodes)
        self.use_closed_forms = use_closed_forms
        self.xtol = xtol
        nodes, weights = hermegauss(self.quadrature_nodes)
        self._nodes = nodes
        self._weights = weights / np.sqrt(2.0 * np.pi)  # probabilists' weights sum to sqrt(2 pi)
        self._maps = [_fast_marginal_map(d) or (lambda z, d=d: marginal_ppf_of_normal(d, z))
                      for d in self.marginals]
        self._moments = [self._quadrature_moments(d, name) for d, name in
                         zip(self.marginals, self.names)]
        solved = self._solve_matrix()
        self.gaussian_correlation = self._ensure_positive_definite(solved, repair)
        self.cholesky_factor = np.linalg.cholesky(self.gaussian_correlation)

    # ----------------------------------------------------------------------------------- setup
    def _check_matrix(self, r: np.ndarray, n: int) -> np.ndarray:
        if r.shape != (n, n):
            raise ValueError(f"correlation matrix has shape {r.shape}, expected ({n}, {n}) "
                             f"for variables {self.names}")
        if not np.all(np.isfinite(r)):
            raise ValueError("correlation matrix has non-finite entries")
        if np.max(np.abs(np.diag(r) - 1.0)) > _MATRIX_TOL:
            raise ValueError(f"correlation matrix diagonal must be 1, got {np.diag(r)}")
        if np.max(np.abs(r - r.T)) > _MATRIX_TOL:
            i, j = np.unravel_index(np.argmax(np.abs(r - r.T)), r.shape)
            raise ValueError(f"correlation matrix is not symmetric: entry ({self.names[i]}, "
                             f"{self.names[j]}) = {r[i, j]} but ({self.names[j]}, "
                             f"{self.names[i]}) = {r[j, i]}")
        off = r[~np.eye(n, dtype=bool)]
        if off.size and np.max(np.abs(off)) > 1.0:
            raise ValueError("correlation matrix has an off-diagonal entry outside [-1, 1]")
        return 0.5 * (r + r.T)

    def _quadrature_moments(self, dist, name: str) -> tuple[float, float]:
        """Mean and standard deviation of F^-1(Phi(g)) by the same 1-D quadrature.

        Using quadrature moments (rather than dist.mean()) makes r_x(r_g = 1) exactly 1 for a pair
        of identical marginals, so the attainable range [r_x(-1), r_x(1)] is computed consistently.
        """
        values = marginal_ppf_of_normal(dist, self._nodes)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"variable {name}: marginal {_family(dist)} gives non-finite "
                             "quantiles at the quadrature nodes")
        mean = float(self._weights @ values)
        var = float(self._weights @ (values - mean) ** 2)
        if not var > 0:
            raise ValueError(f"variable {name}: marginal has zero variance")
        return mean, np.sqrt(var)

    # ----------------------------------------------------------------------------- pair solve
    def pearson_from_gaussian(self, i: int, j: int, rho_g: float) -> float:
        """Pearson correlation of x_i, x_j when their Gaussian images have correlation rho_g.

        Eq. 42 by 2-D Gauss-Hermite quadrature: with independent nodes t_k, t_l,
        g_i = t_k and g_j = rho_g t_k + sqrt(1 - rho_g^2) t_l.
        """
        mean_i, std_i = self._moments[i]
        mean_j, std_j = self._moments[j]
        t = self._nodes
        u_i = (marginal_ppf_of_normal(self.marginals[i], t) - mean_i) / std_i
        g_j = rho_g * t[:, None] + np.sqrt(max(0.0, 1.0 - rho_g * rho_g)) * t[None, :]
        u_j = (marginal_ppf_of_normal(self.marginals[j], g_j) - mean_j) / std_j
        return float(self._weights @ (u_i[:, None] * u_j) @ self._weights)

    def _solve_pair(self, i: int, j: int, rho_x: float) -> float:
        pair = f"({self.names[i]}, {self.names[j]})"
        if rho_x == 0.0:
            return 0.0
        if self.use_closed_forms:
            rho_g = _closed_form(self.marginals[i], self.marginals[j], rho_x)
            if rho_g is not None:
                if not (np.isfinite(rho_g) and abs(rho_g) <= 1.0):
                    lo = self.pearson_from_gaussian(i, j, -1.0)
                    hi = self.pearson_from_gaussian(i, j, 1.0)
                    raise InfeasibleCorrelationError(
                        f"target correlation {rho_x} of {pair} is not attainable with marginals "
                        f"{_family(self.marginals[i])}/{_family(self.marginals[j])}: attainable "
                        f"range is [{lo:.6f}, {hi:.6f}]")
                return float(rho_g)
        lo, hi = (self.pearson_from_gaussian(i, j, -1.0), self.pearson_from_gaussian(i, j, 1.0))
        if not lo <= rho_x <= hi:
            raise InfeasibleCorrelationError(
                f"target correlation {rho_x} of {pair} is not attainable with marginals "
                f"{_family(self.marginals[i])}/{_family(self.marginals[j])}: attainable range "
                f"is [{lo:.6f}, {hi:.6f}]")
        return optimize.brentq(lambda r: self.pearson_from_gaussian(i, j, r) - rho_x,
                               -1.0, 1.0, xtol=self.xtol, rtol=4 * np.finfo(float).eps)

    def _solve_matrix(self) -> np.ndarray:
        n = len(self.marginals)
        r_g = np.eye(n)
        for i in range(n):
            for j in range(i + 1, n):
                r_g[i, j] = r_g[j, i] = self._solve_pair(i, j, self.target_correlation[i, j])
        return r_g

    def _ensure_positive_definite(self, r_g: np.ndarray, repair: str) -> np.ndarray:
        min_eig = float(np.linalg.eigvalsh(r_g)[0])
        if min_eig > 1e-10:
            return r_g
        if repair == "raise":
            raise ValueError(f"solved Gaussian correlation matrix of {self.names} is not "
                             f"positive definite (smallest eigenvalue {min_eig:.3e}); lower the "
                             "target correlations or use repair='higham'")
        repaired = nearest_correlation_matrix(r_g, min_eigenvalue=1e-8)
        log.warning("Nataf: Gaussian correlation matrix of %s is not positive definite "
                    "(smallest eigenvalue %.3e); replaced by the nearest correlation matrix "
                    "(Higham 2002), largest entry change %.3e",
                    self.names, min_eig, float(np.max(np.abs(repaired - r_g))))
        return repaired

    # ------------------------------------------------------------------------------ sampling
    def correlate(self, independent_normals: np.ndarray) -> np.ndarray:
        """Independent standard normals (..., n) -> normals with correlation R_g (eq. 44)."""
        return np.asarray(independent_normals) @ self.cholesky_factor.T

    def to_physical(self, gaussian: np.ndarray) -> np.ndarray:
        """Correlated standard normals (..., n) -> physical variables (eq. 45)."""
        gaussian = np.asarray(gaussian, dtype=float)
        out = np.empty_like(gaussian)
        for k, marginal_map in enumerate(self._maps):
            out[..., k] = marginal_map(gaussian[..., k])
        return out

    def sample(self, independent_normals: np.ndarray) -> np.ndarray:
        """Independent standard normals (..., n) -> correlated physical variables."""
        return self.to_physical(self.correlate(independent_normals))


def nearest_correlation_matrix(matrix: np.ndarray, *, min_eigenvalue: float = 0.0,
                               tol: float = 1e-12, max_iterations: int = 1000) -> np.ndarray:
    """Nearest correlation matrix in the Frobenius norm (Higham 2002, IMA J. Numer. Anal. 22).

    Alternating projections with Dykstra's correction between the positive semidefinite cone
    (eigenvalues clipped at ``min_eigenvalue``) and the unit-diagonal matrices. A final clip and
    rescale keeps the result strictly positive definite so that Cholesky succeeds.
    """
    y = 0.5 * (np.asarray(matrix, dtype=float) + np.asarray(matrix, dtype=float).T)
    correction = np.zeros_like(y)
    x = y.copy()
    for _ in range(max_iterations):
        r = y - correction
        eigval, eigvec = np.linalg.eigh(r)
        x = (eigvec * np.maximum(eigval, min_eigenvalue)) @ eigvec.T
        correction = x - r
        y_new = x.copy()
        np.fill_diagonal(y_new, 1.0)
        if np.linalg.norm(y_new - y, "fro") <= tol * max(1.0, np.linalg.norm(y, "fro")):
            y = y_new
            break
        y = y_new
    eigval, eigvec = np.linalg.eigh(0.5 * (y + y.T))
    y = (eigvec * np.maximum(eigval, max(min_eigenvalue, 1e-12))) @ eigvec.T
    d = np.sqrt(np.diag(y))
    return y / np.outer(d, d)
