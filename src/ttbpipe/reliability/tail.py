"""Extreme-value tail model for rare exceedance probabilities ``P(X > z)`` of per-passage maxima.

Counting exceedances among a few hundred simulated passages cannot resolve the per-passage
probabilities a bridge is judged against (a one-year return period at 100 train pairs a day is
about 2.7e-5). This module fits the upper tail of the per-sample maxima ``x_i`` (one per
simulated passage, optional probability weights ``w_i``) and extrapolates it to the limit ``z``:

* ``model='gev'``: the maxima follow a generalised extreme value distribution
  ``G(x) = exp(-[1 + xi (x - mu)/sigma]^(-1/xi))`` (Coles 2001, *An Introduction to Statistical
  Modeling of Extreme Values*, eq. 3.2; Gumbel limit ``exp(-exp(-(x - mu)/sigma))`` at xi = 0).
  ``p = 1 - G(z)``. scipy's ``genextreme`` uses ``c = -xi``;
* ``model='pot'``: peaks over a threshold ``u`` (the weighted ``threshold_quantile`` of the
  sample, lowered so that at least ``min_exceedances`` samples exceed it) follow a generalised
  Pareto distribution ``H(y) = 1 - (1 + xi y/sigma)^(-1/xi)`` (Coles 2001, eq. 4.2) and
  ``p = zeta_u (1 - H(z - u))`` with ``zeta_u`` the weighted fraction above ``u`` (Coles 2001,
  §4.3.3). scipy's ``genpareto`` uses ``c = xi``.

**Weights.** Self-normalised probability weights (TIPM, importance sampling) enter the
log-likelihood as ``sum a_i log f(x_i)`` with ``a_i = w_i / mean(w)``: its score is unbiased for
the weighted (target) distribution. scipy's ``fit`` has no weights, so the weighted maximum
likelihood is computed here (Nelder-Mead, started for the GEV from the L-moment estimate,
Hosking, Wallis & Wood 1985, and Gumbel moments; for the GPD from scipy's unweighted fit and the
method of moments, Hosking & Wallis 1987, Technometrics 29:339).

**Intervals.** ``interval='profile'`` (default): the model is reparametrised by ``log p`` at the
limit (Coles 2001, §3.3.3 and §4.3.4 profile the return level; here the level is fixed at the
limit and its log-probability profiled), the other two parameters maximised out, and the interval
is ``{log p : 2 (l_max - l_prof(log p)) <= c chi2_1(level)}``. ``c = 1`` for equal weights; for
unequal weights the weighted likelihood is not a true likelihood and ``c`` is the sandwich ratio
``(I^-1 J I^-1)_pp / (I^-1)_pp`` with ``J = sum a_i^2 s_i s_i^T`` (Chandler & Bate 2007,
Biometrika 94:167, one-parameter vertical adjustment). ``interval='bootstrap'``: percentile
interval of ``B`` refits on samples of the (x_i, w_i) pairs drawn with replacement, deterministic
for a seed. The coefficient of variation ``cov`` is ``sqrt(exp(var log p) - 1)`` with the
(sandwich) delta-method variance of ``log p``, or the bootstrap's std(p*)/p.

**Goodness of fit.** Anderson-Darling statistic of the fitted distribution (for POT: the GPD of
the excesses) against the weighted empirical distribution, ``A^2 = n_eff int (F_n - F)^2 /
(F (1 - F)) dF`` evaluated exactly for a step ``F_n`` (Anderson & Darling 1954; ``n_eff`` is
Kish's effective size, the sample size for equal weights). Its p-value comes from a parametric
bootstrap (simulate ``round(n_eff)`` values from the fit, refit, recompute; Stute, Manteiga &
Quindimil 1993), ``gof_bootstrap`` replications, 0 to skip (p-value NaN).

**Guards.** The GEV/GPD likelihood is irregular for ``xi < -0.5`` and unbounded for ``xi <= -1``
(Smith 1985, Biometrika 72:67; Coles 2001 §3.3.2): the parameter space is ``xi >= min_shape``
(default -0.5, profile and fits alike) and a fit that ends on that bound is reported as not
estimable. Non-convergence, a likelihood curvature
that is not positive definite, fewer than ``min_samples`` samples, equal values, NaN: a
:class:`TailNotEstimable` saying why, never a silent 0.

**Extrapolation.** The estimate is flagged when the limit's return period ``1/p`` exceeds
``extrapolation_factor`` times the fitted return period of the largest observation: the value then
rests on the assumed domain of attraction, not on the data.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from scipy import optimize, stats

from ..jit import kernel
from ..stats.tables import weighted_quantile
from .result import reliability_index

MODELS = ("gev", "pot", "gumbel")
#: models for records shorter than ``min_samples`` (``short_record_model``)
SHORT_RECORD_MODELS = ("gumbel", "none")
INTERVALS = ("profile", "bootstrap")

#: Below this |xi| the Gumbel / exponential limit of the formulas is used.
_XI_ZERO = 1e-9
#: The optimiser never leaves xi in (-1, _XI_MAX): at xi <= -1 the likelihood is unbounded.
_XI_MIN, _XI_MAX = -1.0, 5.0
#: log p below which the lower interval end is reported as 0: the data do not exclude an upper
#: end point below the limit, and probabilities below 1e-30 are no longer engineering figures.
_LOG_P_FLOOR = np.log(1e-30)
_EULER_GAMMA = 0.5772156649015329


class TailNotEstimable(ValueError):
    """The data do not support a tail estimate; the message says why."""


@dataclass(frozen=True)
class TailSettings:
    """Tail model settings (``limits.tail`` in the configuration; defaults here).

    ``min_shape`` guards the irregular likelihood (xi < -0.5); ``extrapolation_factor`` flags a
    limit whose return period exceeds that multiple of the largest observation's;
    ``gof_bootstrap`` replications give the goodness-of-fit p-value (0: statistic only);
    ``n_bootstrap`` replications for ``interval='bootstrap'``; ``seed`` makes both deterministic.
    A GEV record shorter than ``min_samples`` (but of at least ``min_samples_short``) is fitted
    with ``short_record_model``: the two-parameter Gumbel (``'gumbel'``, default) or none.
    19 goodness-of-fit replications keep a study's tables fast; their smallest p-value, 0.05, is
    what flags a poor fit (raise it for a finer p-value).
    """

    model: str = "gev"
    threshold_quantile: float = 0.8
    min_exceedances: int = 30
    min_samples: int = 20
    min_distinct: int = 10
    short_record_model: str = "gumbel"
    min_samples_short: int = 5
    confidence_level: float = 0.95
    interval: str = "profile"
    n_bootstrap: int = 200
    gof_bootstrap: int = 19
    extrapolation_factor: float = 100.0
    min_shape: float = -0.5
    seed: int = 0

    def __post_init__(self) -> None:
        if self.model not in (*MODELS, "none"):
            raise ValueError(f"tail model must be one of {(*MODELS, 'none')}, got {self.model!r}")
        if self.interval not in INTERVALS:
            raise ValueError(f"tail interval must be one of {INTERVALS}, got {self.interval!r}")
        if not 0.0 < self.threshold_quantile < 1.0:
            raise ValueError(f"threshold_quantile must be in (0, 1), got {self.threshold_quantile}")
        if not 0.0 < self.confidence_level < 1.0:
            raise ValueError(f"confidence_level must be in (0, 1), got {self.confidence_level}")
        if self.min_samples < 5 or self.min_exceedances < 5:
            raise ValueError("min_samples and min_exceedances must be at least 5")
        if self.short_record_model not in SHORT_RECORD_MODELS:
            raise ValueError(f"short_record_model must be one of {SHORT_RECORD_MODELS}, got "
                             f"{self.short_record_model!r}")
        if not 5 <= self.min_samples_short <= self.min_samples:
            raise ValueError(f"min_samples_short must be in [5, min_samples = {self.min_samples}], "
                             f"got {self.min_samples_short}")
        if not -1.0 < self.min_shape <= 0.0:
            raise ValueError(f"min_shape must be in (-1, 0], got {self.min_shape}")

    @classmethod
    def from_config(cls, section: Mapping[str, Any] | None, **defaults) -> "TailSettings":
        """From ``limits.tail`` (keys as the fields); ``defaults`` fill keys the section omits."""
        values = {**defaults, **dict(section or {})}
        return cls(**values)


@dataclass(frozen=True)
class TailEstimate:
    """``P(X > z)`` from the tail model with its interval and diagnostics.

    ``location``/``scale``/``shape`` are (mu, sigma, xi) of the GEV, or (u, sigma, xi) of the GPD
    above ``threshold`` u with ``zeta`` the weighted fraction above u (POT). ``n_evaluations`` is
    the number of samples (simulated passages) the fit used.
    """

    limit: float
    probability: float
    ci_low: float
    ci_high: float
    cov: float
    n_evaluations: int
    model: str
    method: str
    gof_statistic: float
    gof_pvalue: float
    gof_method: str
    extrapolation: bool
    status: str
    location: float
    scale: float
    shape: float
    threshold: float = np.nan
    zeta: float = np.nan
    n_exceedances: int = 0
    return_period_ratio: float = np.nan
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def reliability_index(self) -> float:
        return reliability_index(self.probability)


# --- models ------------------------------------------------------------------------------------

def _log1p_ratio(xi: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``log(1 + xi y) / xi`` (``y`` at xi -> 0) and the support mask ``1 + xi y > 0``."""
    if abs(xi) < _XI_ZERO:
        return y.astype(float), np.ones(y.shape, dtype=bool)
    t = xi * y
    ok = t > -1.0
    return np.where(ok, np.log1p(np.where(ok, t, 0.0)) / xi, np.nan), ok


# --- negative log-likelihoods (the optimisers' objective; the models' ``logf`` is the reference) --

@kernel
def _log1p_over_xi(xi, y):
    """``log(1 + xi y) / xi`` (``y`` at |xi| < _XI_ZERO), NaN outside the support 1 + xi y > 0:
    :func:`_log1p_ratio` for one value."""
    if abs(xi) < _XI_ZERO:
        return y
    t = xi * y
    if not t > -1.0:
        return np.nan
    return np.log1p(t) / xi


@kernel
def _gev_nll(x, a, mu, lsig, xi):
    """``-sum a_i log f(x_i)`` of the GEV (Coles 2001 eq. 3.7; Gumbel limit eq. 3.9 below
    |xi| = _XI_ZERO); +inf where an x_i lies outside the support. Same terms as
    :meth:`_GEV.logf`, summed in a loop: a fit makes ~200 calls of a few dozen points, where
    numpy's per-call overhead was most of the time."""
    sigma = np.exp(lsig)
    total = 0.0
    for i in range(x.shape[0]):
        l = _log1p_over_xi(xi, (x[i] - mu) / sigma)
        if np.isnan(l):
            return np.inf
        total -= a[i] * (-lsig - (1.0 + xi) * l - np.exp(-l))
    return total if np.isfinite(total) else np.inf


@kernel
def _log1p_exp(z):
    """log(1 + e^z) without overflow (numpy's ``logaddexp(0, z)``)."""
    return max(z, 0.0) + np.log1p(np.exp(-abs(z)))


@kernel
def _pot_nll(above, e, a, eta, lsig, xi):
    """``-sum a_i log f_i`` of peaks over a threshold: the binomial term of zeta = 1/(1 + e^-eta)
    for every point and the GPD of the excesses ``e`` above it (Coles 2001 eq. 4.10); +inf
    outside the support. Same terms as :meth:`_POT.logf`."""
    sigma = np.exp(lsig)
    log_zeta = -_log1p_exp(-eta)
    log_not = -_log1p_exp(eta)
    total = 0.0
    for i in range(e.shape[0]):
        if above[i]:
            l = _log1p_over_xi(xi, e[i] / sigma)
            if np.isnan(l):
                return np.inf
            total -= a[i] * (log_zeta - lsig - (1.0 + xi) * l)
        else:
            total -= a[i] * log_not
    return total if np.isfinite(total) else np.inf


#: Objectives of :func:`_nelder_mead`, one code per model: its likelihood (``nll``) in all
#: parameters, or (``+ _PROFILE``) its profile objective in the free parameters at a fixed
#: ``log p`` at the limit (``nll(from_logp(lp, free, z))``, :func:`_profile_interval`).
_KIND_GEV, _KIND_GUMBEL, _KIND_POT = 0, 1, 2
_PROFILE = 3
#: The GEV's profile objective in coordinates along its support's edge: v = (t, xi) with
#: log sigma = log(xi (z - min x)) + xi log y + e^t (y = -log(1 - p)), for xi > 0 only; the
#: argument ``u`` carries min x (:func:`_along_edge`).
_GEV_PROFILE_ALONG_EDGE = 2 * _PROFILE
#: Placeholders for the arrays a model's objective does not read (typed as the real ones).
_NO_FLAGS, _NO_VALUES = np.zeros(0, dtype=np.bool_), np.zeros(0)


@kernel
def _shape_nll(kind, x, a, above, e, xi_min, first, lsig, xi):
    """The GEV (``first`` = mu) or POT (``first`` = eta) negative log-likelihood, +inf outside
    the shape's range ``[xi_min, 5)`` (the optimiser's parameter space)."""
    if not (xi_min <= xi and xi < _XI_MAX):
        return np.inf
    if kind == _KIND_GEV:
        return _gev_nll(x, a, first, lsig, xi)
    return _pot_nll(above, e, a, first, lsig, xi)


@kernel
def _gumbel_log_y(lp):
    """log y with y = -log(1 - p), p = e^lp < 1: the GEV's quantile term (``from_logp``)."""
    return np.log(-np.log1p(-np.exp(lp)))


@kernel
def _gev_profile_nll(x, a, above, e, xi_min, z, big_l, lsig, xi):
    """The GEV's negative log-likelihood at (log sigma, xi) with mu set so that P(X > z) = p
    (``big_l`` = :func:`_gumbel_log_y` of log p; the models' ``from_logp``)."""
    ratio = -big_l if abs(xi) < _XI_ZERO else np.expm1(-xi * big_l) / xi
    return _shape_nll(_KIND_GEV, x, a, above, e, xi_min, z - np.exp(lsig) * ratio, lsig, xi)


@kernel
def _objective(kind, x, a, above, e, xi_min, u, lp, z, v):
    """The objective ``kind`` at ``v``: a model's negative log-likelihood (theta = v), or its
    profile at ``log p = lp`` of exceeding ``z`` (v the free parameters; the models'
    ``from_logp``, +inf where it has no solution), or the GEV's profile along its support's edge
    (:data:`_GEV_PROFILE_ALONG_EDGE`, the models' ``edge_coordinates``). The same operations as
    the models' methods, so the same values."""
    if kind == _KIND_GUMBEL:
        return _gev_nll(x, a, v[0], v[1], 0.0)
    if kind == _GEV_PROFILE_ALONG_EDGE:
        xi = v[1]
        if not (xi > _XI_ZERO and lp < 0.0 and z > u):
            return np.inf
        big_l = _gumbel_log_y(lp)
        lsig = np.log(xi * (z - u)) + xi * big_l + np.exp(v[0])
        return _gev_profile_nll(x, a, above, e, xi_min, z, big_l, lsig, xi)
    if kind < _PROFILE:
        return _shape_nll(kind, x, a, above, e, xi_min, v[0], v[1], v[2])
    base = kind - _PROFILE
    lsig = v[0]
    if base == _KIND_POT:
        xi = v[1]
        l = _log1p_over_xi(xi, (z - u) / np.exp(lsig))
        log_zeta = lp - (-np.inf if np.isnan(l) else -l)
        if not (np.isfinite(log_zeta) and log_zeta < 0.0):
            return np.inf
        eta = log_zeta - np.log(-np.expm1(log_zeta))
        return _shape_nll(base, x, a, above, e, xi_min, eta, lsig, xi)
    if not lp < 0.0:
        return np.inf
    big_l = _gumbel_log_y(lp)
    if base == _KIND_GUMBEL:
        return _gev_nll(x, a, z + np.exp(lsig) * big_l, lsig, 0.0)
    return _gev_profile_nll(x, a, above, e, xi_min, z, big_l, lsig, v[1])


@kernel
def _objective_at(kind, x, a, above, e, xi_min, u, lp, z, points):
    """:func:`_objective` at each row of ``points`` (the candidates of a profile point's
    starts, :func:`_profile_starts`): one compiled loop instead of a Python call per point."""
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        out[i] = _objective(kind, x, a, above, e, xi_min, u, lp, z, points[i])
    return out


#: Nelder-Mead's moves within one step (:func:`_nelder_mead`).
_NM_REFLECT, _NM_EXPAND, _NM_OUTSIDE, _NM_INSIDE, _NM_SHRINK = 0, 1, 2, 3, 4


@kernel
def _nm_less(f1, f2):
    """numpy's sort order of floats: NaN after every number."""
    return f1 < f2 or (f2 != f2 and f1 == f1)


@kernel
def _nm_set(sim, row, values):
    """``sim[row] = values`` as a loop (numba compiles loops faster than array expressions)."""
    for k in range(values.shape[0]):
        sim[row, k] = values[k]


@kernel
def _nm_sort(sim, fsim):
    """Both arrays in ascending order of ``fsim`` by a stable insertion sort: the order of
    ``np.argsort`` (numpy sorts arrays this short by insertion), so ties keep their places."""
    m, n = sim.shape
    row = np.empty(n)
    for i in range(1, m):
        f = fsim[i]
        for k in range(n):
            row[k] = sim[i, k]
        j = i - 1
        while j >= 0 and _nm_less(f, fsim[j]):
            fsim[j + 1] = fsim[j]
            for k in range(n):
                sim[j + 1, k] = sim[j, k]
            j -= 1
        fsim[j + 1] = f
        for k in range(n):
            sim[j + 1, k] = row[k]


@kernel
def _nelder_mead(kind, x, a, above, e, xi_min, u, lp, z, x0, xatol, fatol, maxiter,
                 maxfev):
    """Minimise the objective ``kind`` (:func:`_objective`) from ``x0`` by Nelder & Mead's
    simplex method (1965), step for step SciPy's ``minimize(method='Nelder-Mead')`` without
    bounds (SciPy 1.17, ``scipy.optimize._optimize._minimize_neldermead``: coefficients rho 1,
    chi 2, psi 0.5, sigma 0.5; initial simplex x0 with one coordinate at a time times 1.05, or
    0.00025 where it is 0; stop when every vertex is within ``xatol`` of the best and every
    value within ``fatol``), with the same arithmetic, so the same iterates bit for bit
    (tests/test_reliability_tail.py compares them). Compiled because a study's tail fits run
    several thousand of these, where SciPy's per-iteration Python was most of the time
    (docs/performance.md). The objective is a closed set of codes, not a function argument:
    numba does not cache a kernel that takes a compiled function as an argument.

    Returns (x, f, iterations, evaluations, status): status 0 converged, 1 ``maxfev`` reached,
    2 ``maxiter`` reached (SciPy's ``warnflag``)."""
    n = x0.shape[0]
    sim = np.empty((n + 1, n))
    for k in range(n + 1):
        _nm_set(sim, k, x0)
    for k in range(n):
        sim[k + 1, k] = (1 + 0.05) * x0[k] if x0[k] != 0 else 0.00025
    fsim = np.full(n + 1, np.inf)
    calls = 0
    for k in range(n + 1):
        if calls >= maxfev:
            break
        calls += 1
        fsim[k] = _objective(kind, x, a, above, e, xi_min, u, lp, z, sim[k])
    _nm_sort(sim, fsim)
    iterations = 1
    xbar = np.empty(n)
    xr = np.empty(n)
    point = np.empty(n)
    while calls < maxfev and iterations < maxiter:
        done = True
        for j in range(1, n + 1):
            for i in range(n):
                if not abs(sim[j, i] - sim[0, i]) <= xatol:
                    done = False
            if not abs(fsim[0] - fsim[j]) <= fatol:
                done = False
        if done:
            break
        # xbar = np.add.reduce(sim[:-1], 0) / N: rows summed in order, then divided
        for i in range(n):
            total = sim[0, i]
            for j in range(1, n):
                total += sim[j, i]
            xbar[i] = total / n
        # One step as a sequence of evaluations: reflect, then expand, contract outside or
        # inside, or shrink vertex by vertex. Leaves the step when it is complete, or when the
        # evaluations run out (then, as in SciPy, the step is not counted).
        phase = _NM_REFLECT
        fxr = np.inf
        vertex = 1
        out_of_calls = False
        while True:
            for i in range(n):   # SciPy's vector expressions, element by element
                if phase == _NM_SHRINK:
                    sim[vertex, i] = sim[0, i] + 0.5 * (sim[vertex, i] - sim[0, i])
                    point[i] = sim[vertex, i]
                elif phase == _NM_REFLECT:
                    point[i] = 2.0 * xbar[i] - sim[n, i]
                elif phase == _NM_EXPAND:
                    point[i] = 3.0 * xbar[i] - 2.0 * sim[n, i]
                elif phase == _NM_OUTSIDE:
                    point[i] = 1.5 * xbar[i] - 0.5 * sim[n, i]
                else:
                    point[i] = 0.5 * xbar[i] + 0.5 * sim[n, i]
            if calls >= maxfev:
                out_of_calls = True
                break
            calls += 1
            f = _objective(kind, x, a, above, e, xi_min, u, lp, z, point)
            if phase == _NM_REFLECT:
                fxr = f
                for i in range(n):
                    xr[i] = point[i]
                if fxr < fsim[0]:
                    phase = _NM_EXPAND
                elif fxr < fsim[n - 1]:
                    _nm_set(sim, n, xr)
                    fsim[n] = fxr
                    break
                elif fxr < fsim[n]:
                    phase = _NM_OUTSIDE
                else:
                    phase = _NM_INSIDE
            elif phase == _NM_EXPAND:
                if f < fxr:
                    _nm_set(sim, n, point)
                    fsim[n] = f
                else:
                    _nm_set(sim, n, xr)
                    fsim[n] = fxr
                break
            elif phase == _NM_OUTSIDE or phase == _NM_INSIDE:
                if f <= fxr if phase == _NM_OUTSIDE else f < fsim[n]:
                    _nm_set(sim, n, point)
                    fsim[n] = f
                    break
                phase = _NM_SHRINK
            else:
                fsim[vertex] = f
                vertex += 1
                if vertex > n:
                    break
        if not out_of_calls:
            iterations += 1
        _nm_sort(sim, fsim)
    fval = fsim[0]
    for j in range(n + 1):
        if fsim[j] != fsim[j]:
            fval = np.nan
    status = 0
    if calls >= maxfev:
        status = 1
    elif iterations >= maxiter:
        status = 2
    return sim[0].copy(), fval, iterations, calls, status


def gev_from_lmoments(l1: float, l2: float, t3: float, shape_min: float = -0.9,
                      shape_max: float = 0.9) -> tuple[float, float, float] | None:
    """GEV (mu, sigma, xi) from the first two L-moments and the L-skewness: Hosking, Wallis &
    Wood (1985, Technometrics 27:251, eq. 15) ``c = 2/(3 + t3) - ln 2/ln 3``, ``k = 7.8590 c
    + 2.9554 c^2`` (their k is -xi; error below 9e-4 for |k| <= 0.5), then ``sigma = l2 k /
    ((1 - 2^-k) Gamma(1 + k))`` and ``mu = l1 - sigma (1 - Gamma(1 + k))/k`` (eq. 14; Gumbel
    limit ``sigma = l2/ln 2``, ``mu = l1 - gamma_E sigma`` as k -> 0). The shape is clipped to
    [shape_min, shape_max], where Gamma(1 + k) stays finite and the estimate is a start, not a
    result; None when ``l2 <= 0`` or a value is not finite."""
    if not (np.isfinite([l1, l2, t3]).all() and l2 > 0):
        return None
    c = 2.0 / (3.0 + t3) - math.log(2.0) / math.log(3.0)
    k = float(np.clip(7.8590 * c + 2.9554 * c * c, -shape_max, -shape_min))
    if abs(k) < 1e-6:
        sigma = l2 / math.log(2.0)
        mu = l1 - _EULER_GAMMA * sigma
    else:
        g = math.gamma(1.0 + k)
        sigma = l2 * k / (-math.expm1(-k * math.log(2.0)) * g)
        mu = l1 - sigma * (1.0 - g) / k
    if not (math.isfinite(mu) and math.isfinite(sigma) and sigma > 0):
        return None
    return mu, sigma, -k


class _GEV:
    """GEV of the maxima; theta = (mu, log sigma, xi) on standardised data (Coles 2001 §3.3)."""

    name = "GEV"

    def __init__(self, x: np.ndarray, a: np.ndarray, xi_min: float = _XI_MIN) -> None:
        self.x, self.a, self.xi_min = x, a, xi_min

    def logf(self, theta) -> np.ndarray:
        mu, lsig, xi = theta
        if not self.xi_min <= xi < _XI_MAX:
            return np.full(self.x.shape, -np.inf)
        y = (self.x - mu) / np.exp(lsig)
        l, ok = _log1p_ratio(xi, y)
        # log f = -log sigma - (1 + xi) log(t)/xi - t^(-1/xi), t = 1 + xi y (Coles 2001 eq. 3.7)
        out = -lsig - (1.0 + xi) * l - np.exp(-l)
        return np.where(ok, out, -np.inf)

    def kernel_data(self) -> tuple:
        """The leading arguments of :func:`_objective` (and :func:`_nelder_mead`) for this
        model: its code, the data as contiguous arrays, the shape's lower bound and the
        threshold (POT; 0 otherwise)."""
        return (_KIND_GEV, np.ascontiguousarray(self.x, dtype=float),
                np.ascontiguousarray(self.a, dtype=float), _NO_FLAGS, _NO_VALUES,
                float(self.xi_min), 0.0)

    def log_p(self, theta, z: float) -> float:
        mu, lsig, xi = theta
        l, ok = _log1p_ratio(xi, np.array([(z - mu) / np.exp(lsig)]))
        if not ok[0]:
            return -np.inf if xi < 0 else 0.0
        s = np.exp(-l[0])                       # -log G(z)
        return float(np.log(-np.expm1(-s))) if s > 0 else -np.inf

    def from_logp(self, lp: float, free, z: float):
        """mu from p at z: ``z = mu + sigma ((-log(1-p))^(-xi) - 1)/xi`` (Coles 2001 eq. 3.4).
        The models' ``from_logp`` are the readable form of the compiled profile objective
        (:func:`_objective`), which tests/test_reliability_tail.py compares with them bit for
        bit: scalars through ``math`` (the C library, as the compiled code), not numpy, whose
        SIMD exp, log1p and expm1 differ in the last bits on AVX-512 CPUs."""
        lsig, xi = free
        if not lp < 0.0:
            return None
        big_l = math.log(-math.log1p(-math.exp(lp)))
        ratio = -big_l if abs(xi) < _XI_ZERO else math.expm1(-xi * big_l) / xi
        return np.array([z - math.exp(lsig) * ratio, lsig, xi])

    def free(self, theta):
        return np.asarray(theta[1:], dtype=float)

    def _edge_bound(self, xi: float, lp: float, z: float) -> float | None:
        """The support's edge of a profile point at (log p, z) with shape xi > 0: its lower end
        point mu - sigma/xi = z - sigma y^(-xi)/xi (y = -log(1 - p), from :meth:`from_logp`)
        must lie below the smallest observation, so log sigma > log(xi (z - min x)) + xi log y,
        this bound (the same operations as the compiled objective
        :data:`_GEV_PROFILE_ALONG_EDGE`). None for xi <= 0 (no lower end point), p >= 1 or a
        limit not above the data."""
        gap = z - float(np.min(self.x))
        if not (xi > _XI_ZERO and lp < 0.0 and gap > 0.0):
            return None
        return math.log(xi * gap) + xi * math.log(-math.log1p(-math.exp(lp)))

    def edge_starts(self, free, lp: float, z: float) -> list[np.ndarray]:
        """``free`` = (log sigma, xi) of a profile at (log p, z) moved just inside the support
        (:meth:`_edge_bound`) when it lies outside: the point with its log scale 1e-6 and 1e-3
        above that bound. Empty where there is no bound or the point lies more than 1e-3
        inside. Where the profile's minimum hugs that edge, the optimum of the neighbouring
        profile point falls just outside it, and this is its nearest point inside
        (:func:`_profile_starts`)."""
        lsig, xi = (float(v) for v in free)
        bound = self._edge_bound(xi, lp, z)
        if bound is None or lsig > bound + 1e-3:
            return []
        return [np.array([bound + d, xi]) for d in (1e-6, 1e-3)]

    def edge_coordinates(self, free, lp: float, z: float) -> np.ndarray | None:
        """``free`` = (log sigma, xi) of a profile point at (log p, z) as (t, xi) with log sigma
        = b(xi) + e^t, b the bound of :meth:`_edge_bound`, where it lies inside the support
        within :data:`_EDGE_BAND` of that bound; else None. In these coordinates the narrow
        band next to the edge, where far-limit profiles have their minimum, is a valley of
        ordinary width (:func:`_along_edge`)."""
        lsig, xi = (float(v) for v in free)
        bound = self._edge_bound(xi, lp, z)
        if bound is None or not 0.0 < lsig - bound < _EDGE_BAND:
            return None
        return np.array([math.log(lsig - bound), xi])

    def from_edge_coordinates(self, along, lp: float, z: float) -> np.ndarray:
        """(log sigma, xi) of the point (t, xi) of :meth:`edge_coordinates` (inside the
        support: xi > 0, p < 1, the limit above the data)."""
        t, xi = (float(v) for v in along)
        return np.array([self._edge_bound(xi, lp, z) + math.exp(t), xi])

    def starts(self) -> list[np.ndarray]:
        """The unweighted L-moment estimate (:func:`gev_from_lmoments`) and weighted Gumbel
        moments with xi = +-0.1 (Coles 2001 §3.3.2 suggests starting near the Gumbel).
        The L-moment estimate is closed-form; scipy's ``genextreme.fit``, an unweighted maximum
        likelihood by its own Nelder-Mead, gave the same optima at some twenty times the cost
        (docs/reliability.md)."""
        out = []
        l1, l2, t3 = stats.lmoment(self.x, order=[1, 2, 3])
        start = gev_from_lmoments(l1, l2, t3, shape_min=self.xi_min + 0.05)
        if start is not None:
            mu, sigma, xi = start
            out.append(np.array([mu, np.log(sigma), xi]))
        m = np.average(self.x, weights=self.a)
        sd = np.sqrt(np.average((self.x - m) ** 2, weights=self.a))
        sig = np.sqrt(6.0) * sd / np.pi
        for xi in (0.1, -0.1):
            out.append(np.array([m - _EULER_GAMMA * sig, np.log(sig), xi]))
        return out

    def pit(self, theta) -> tuple[np.ndarray, np.ndarray]:
        mu, lsig, xi = theta
        return stats.genextreme.cdf(self.x, -xi, loc=mu, scale=np.exp(lsig)), self.a

    def simulate(self, theta, size: int, rng) -> "_GEV":
        mu, lsig, xi = theta
        x = stats.genextreme.rvs(-xi, loc=mu, scale=np.exp(lsig), size=size, random_state=rng)
        return _GEV(x, np.ones(size), self.xi_min)

    def resample(self, idx) -> "_GEV":
        return _GEV(self.x[idx], self.a[idx], self.xi_min)

    def shape(self, theta) -> float:
        return float(theta[2])


class _Gumbel(_GEV):
    """Gumbel (the GEV with xi = 0) of the maxima; theta = (mu, log sigma) on standardised data.

    The two-parameter model for short records, where the GEV shape is not identifiable (Coles
    2001 §3.4 and §2.6.7: the Gumbel as the GEV restricted to xi = 0; with fewer than about 20
    maxima the shape's profile interval spans every plausible value). For the light tails of
    the coupled model's maxima (fitted xi of -0.1 to -0.2, docs/reliability.md §11) the Gumbel
    overstates the exceedance probability: a conservative extrapolation.
    """

    name = "Gumbel"

    def edge_starts(self, free, lp: float, z: float) -> list[np.ndarray]:
        """Empty: the Gumbel has no lower end point (:meth:`_GEV.edge_starts`)."""
        return []

    def edge_coordinates(self, free, lp: float, z: float) -> None:
        """None: no lower end point (:meth:`_GEV.edge_coordinates`)."""
        return None

    def logf(self, theta) -> np.ndarray:
        mu, lsig = theta
        y = (self.x - mu) / np.exp(lsig)
        return -lsig - y - np.exp(-y)            # Coles 2001 eq. 3.9 (xi -> 0)

    def kernel_data(self) -> tuple:
        return (_KIND_GUMBEL, *super().kernel_data()[1:])

    def log_p(self, theta, z: float) -> float:
        mu, lsig = theta
        s = np.exp(-(z - mu) / np.exp(lsig))     # -log G(z)
        return float(np.log(-np.expm1(-s))) if s > 0 else -np.inf

    def from_logp(self, lp: float, free, z: float):
        (lsig,) = free
        if not lp < 0.0:
            return None
        big_l = math.log(-math.log1p(-math.exp(lp)))
        return np.array([z + math.exp(lsig) * big_l, lsig])

    def starts(self) -> list[np.ndarray]:
        m = np.average(self.x, weights=self.a)
        sd = np.sqrt(np.average((self.x - m) ** 2, weights=self.a))
        sig = np.sqrt(6.0) * sd / np.pi         # method of moments (Coles 2001 §3.3.2)
        return [np.array([m - _EULER_GAMMA * sig, np.log(sig)])]

    def pit(self, theta) -> tuple[np.ndarray, np.ndarray]:
        mu, lsig = theta
        return stats.gumbel_r.cdf(self.x, loc=mu, scale=np.exp(lsig)), self.a

    def simulate(self, theta, size: int, rng) -> "_Gumbel":
        mu, lsig = theta
        x = stats.gumbel_r.rvs(loc=mu, scale=np.exp(lsig), size=size, random_state=rng)
        return _Gumbel(x, np.ones(size), self.xi_min)

    def resample(self, idx) -> "_Gumbel":
        return _Gumbel(self.x[idx], self.a[idx], self.xi_min)

    def shape(self, theta) -> float:
        return 0.0


class _POT:
    """Peaks over u: theta = (logit zeta, log sigma, xi); the likelihood is the binomial
    likelihood of zeta times the GPD likelihood of the excesses (Coles 2001 §4.3-4.4)."""

    name = "POT"

    def __init__(self, x: np.ndarray, a: np.ndarray, u: float, xi_min: float = _XI_MIN) -> None:
        self.x, self.a, self.u, self.xi_min = x, a, u, xi_min
        self.above = x > u
        self.e = np.where(self.above, x - u, 0.0)

    def logf(self, theta) -> np.ndarray:
        eta, lsig, xi = theta
        if not self.xi_min <= xi < _XI_MAX:
            return np.full(self.x.shape, -np.inf)
        l, ok = _log1p_ratio(xi, self.e / np.exp(lsig))
        gpd = np.where(ok, -lsig - (1.0 + xi) * l, -np.inf)      # Coles 2001 eq. 4.10
        return np.where(self.above, -np.logaddexp(0.0, -eta) + gpd, -np.logaddexp(0.0, eta))

    def kernel_data(self) -> tuple:
        return (_KIND_POT, _NO_VALUES, np.ascontiguousarray(self.a, dtype=float),
                np.ascontiguousarray(self.above, dtype=np.bool_),
                np.ascontiguousarray(self.e, dtype=float), float(self.xi_min), float(self.u))

    def _log_survival(self, lsig, xi, d: float) -> float:
        # one value: the compiled objective's own function and the C library's exp, so that
        # log_p and from_logp give its values bit for bit on every CPU (numpy's SIMD exp and
        # log1p differ from the C library's in the last bits where the CPU has AVX-512)
        l = _log1p_over_xi(xi, d / math.exp(lsig))
        return -np.inf if np.isnan(l) else float(-l)

    def log_p(self, theta, z: float) -> float:
        eta, lsig, xi = theta
        return float(-np.logaddexp(0.0, -eta) + self._log_survival(lsig, xi, z - self.u))

    def from_logp(self, lp: float, free, z: float):
        lsig, xi = free
        log_zeta = lp - self._log_survival(lsig, xi, z - self.u)
        if not (np.isfinite(log_zeta) and log_zeta < 0.0):
            return None
        return np.array([log_zeta - math.log(-math.expm1(log_zeta)), lsig, xi])

    def free(self, theta):
        return np.asarray(theta[1:], dtype=float)

    def edge_starts(self, free, lp: float, z: float) -> list[np.ndarray]:
        """Empty: the GPD's profile points are not moved to its upper end point (xi < 0); the
        raised-scale candidates of :func:`_profile_starts` bring them back inside."""
        return []

    def edge_coordinates(self, free, lp: float, z: float) -> None:
        """None: the GPD's profile is not followed along its upper end point."""
        return None

    def starts(self) -> list[np.ndarray]:
        """scipy's unweighted GPD fit (``c = xi``, location 0) and the weighted method of moments
        ``xi = (1 - m^2/s^2)/2, sigma = m (m^2/s^2 + 1)/2`` (Hosking & Wallis 1987 eq. 7)."""
        e, a = self.e[self.above], self.a[self.above]
        zeta = a.sum() / self.a.sum()
        eta = np.log(zeta) - np.log1p(-zeta)
        out = []
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            try:
                c, _, scale = stats.genpareto.fit(e, floc=0.0)
                if np.isfinite([c, scale]).all() and scale > 0:
                    out.append(np.array([eta, np.log(scale), c]))
            except Exception:   # moments follow
                pass
        m = np.average(e, weights=a)
        v = np.average((e - m) ** 2, weights=a)
        xi = float(np.clip(0.5 * (1.0 - m * m / v), self.xi_min + 0.05, 0.9))
        out.append(np.array([eta, np.log(0.5 * m * (m * m / v + 1.0)), xi]))
        return out

    def pit(self, theta):
        _, lsig, xi = theta
        return (stats.genpareto.cdf(self.e[self.above], xi, scale=np.exp(lsig)),
                self.a[self.above])

    def simulate(self, theta, size: int, rng) -> "_POT":
        """``size`` excesses from the GPD above u, with the sample's points below u (they carry
        only zeta, which the goodness of fit of the GPD does not test)."""
        _, lsig, xi = theta
        e = stats.genpareto.rvs(xi, scale=np.exp(lsig), size=size, random_state=rng)
        below = self.x[~self.above]
        x = np.concatenate([below, self.u + np.maximum(e, 1e-12)])
        return _POT(x, np.ones(x.size), self.u, self.xi_min)

    def resample(self, idx) -> "_POT":
        return _POT(self.x[idx], self.a[idx], self.u, self.xi_min)

    def shape(self, theta) -> float:
        return float(theta[2])


# --- fitting -----------------------------------------------------------------------------------

#: Nelder-Mead's iteration and evaluation budgets (SciPy's ``maxiter``, ``maxfev``).
_NM_MAXITER, _NM_MAXFEV = 4000, 8000
_NM_MESSAGES = ("Optimization terminated successfully.",
                "Maximum number of function evaluations has been exceeded.",
                "Maximum number of iterations has been exceeded.")


class _Objective:
    """A model's likelihood, or with ``profile = (log p, z)`` its profile objective in the free
    parameters (:func:`_objective`: ``nll(from_logp(log p, free, z))``; with ``along_edge``,
    the GEV's in the coordinates of :meth:`_GEV.edge_coordinates`), compiled; called at a point
    it gives the value, :meth:`minimise` runs the compiled Nelder-Mead on it."""

    def __init__(self, model, profile: tuple[float, float] | None = None,
                 along_edge: bool = False) -> None:
        kind, *self._data = model.kernel_data()
        self._kind = kind + (_PROFILE if profile is not None else 0)
        self._lp, self._z = (0.0, 0.0) if profile is None else map(float, profile)
        if along_edge:    # the GEV profile in (t, xi); its threshold slot carries min x
            if kind != _KIND_GEV or profile is None:
                raise ValueError("along_edge: a GEV profile objective only")
            self._kind = _GEV_PROFILE_ALONG_EDGE
            self._data[-1] = float(np.min(self._data[0]))

    def __call__(self, v) -> float:
        return float(_objective(self._kind, *self._data, self._lp, self._z,
                                np.asarray(v, dtype=float)))

    def at(self, points) -> np.ndarray:
        """The objective at each row of ``points`` (the same values as calling it on each)."""
        return _objective_at(self._kind, *self._data, self._lp, self._z,
                             np.ascontiguousarray(points, dtype=float))

    def solve(self, start, tol: float, maxiter: int = _NM_MAXITER, maxfev: int = _NM_MAXFEV):
        """One compiled Nelder-Mead run from ``start`` (``xatol = fatol = tol``), as SciPy's
        ``OptimizeResult`` (x, fun, nit, nfev, status, success, message)."""
        x, f, nit, nfev, status = _nelder_mead(self._kind, *self._data, self._lp, self._z,
                                               np.array(start, dtype=float), tol, tol,
                                               maxiter, maxfev)
        return optimize.OptimizeResult(x=x, fun=float(f), nit=nit, nfev=nfev, status=status,
                                       success=status == 0, message=_NM_MESSAGES[status])

    def minimise(self, starts, tol: float = 1e-8, restart: bool = True):
        """Nelder-Mead from each feasible start, restarted once at the best point (a simplex
        that collapsed early is rebuilt there; Nelder & Mead 1965 restarts as in Press et al.
        §10.5). ``restart=False``: no restart (a start at the generating parameters of a
        simulated sample). None when no start is feasible."""
        best = None
        for s in starts:
            if not np.isfinite(self(s)):
                continue
            res = self.solve(s, tol)
            if best is None or res.fun < best.fun:
                best = res
        if best is None:
            return None
        if not restart:
            return best
        again = self.solve(best.x, tol)
        return again if again.fun <= best.fun else best


def _fit(model, starts, min_shape: float, tol: float = 1e-8, restart: bool = True):
    res = _Objective(model).minimise(starts, tol, restart)
    if res is None or not np.isfinite(res.fun):
        raise TailNotEstimable(f"{model.name} fit failed: no starting value inside the support")
    if not res.success:
        raise TailNotEstimable(f"{model.name} weighted maximum likelihood did not converge "
                               f"({res.message})")
    xi = model.shape(res.x)
    if xi < min_shape + 1e-3:   # at the bound of the parameter space the optimiser was given
        raise TailNotEstimable(
            f"{model.name} shape xi = {xi:.2f} at or below {min_shape:g}: the maxima look bounded and the "
            "maximum-likelihood estimator is not regular there (Smith 1985; Coles 2001 §3.3.2)")
    return res.x, float(res.fun)


def _derivatives(fun_vec, psi, a):
    """Per-observation gradients (n x k) of ``fun_vec`` and the Hessian of ``a . fun_vec`` at psi
    by central differences."""
    k = psi.size
    h = 1e-4 * np.maximum(1.0, np.abs(psi))
    grads = np.empty((a.size, k))
    for j in range(k):
        e = np.zeros(k)
        e[j] = h[j]
        grads[:, j] = (fun_vec(psi + e) - fun_vec(psi - e)) / (2.0 * h[j])
    total = lambda p: float(np.dot(a, fun_vec(p)))
    hess = np.empty((k, k))
    f0 = total(psi)
    for i in range(k):
        ei = np.zeros(k)
        ei[i] = h[i]
        hess[i, i] = (total(psi + ei) - 2.0 * f0 + total(psi - ei)) / h[i] ** 2
        for j in range(i + 1, k):
            ej = np.zeros(k)
            ej[j] = h[j]
            hess[i, j] = hess[j, i] = (total(psi + ei + ej) - total(psi + ei - ej)
                                       - total(psi - ei + ej) + total(psi - ei - ej)) / (
                                           4.0 * h[i] * h[j])
    return grads, hess


def _weighted_ad(u: np.ndarray, w: np.ndarray) -> float:
    """Anderson-Darling ``A^2 = n_eff int_0^1 (F_n(t) - t)^2 / (t (1 - t)) dt`` for the weighted
    step function F_n of the PIT values u, integrated exactly per step with
    ``(c - t)^2/(t(1-t)) = -1 + c^2/t + (1 - c)^2/(1 - t)``; equals the classical
    ``-n - sum (2i-1)/n [ln u_i + ln(1 - u_(n+1-i))]`` for equal weights."""
    order = np.argsort(u)
    u = np.clip(u[order], 1e-300, 1.0 - 1e-16)
    w = w[order] / w.sum()
    edges = np.concatenate([[0.0], u, [1.0]])
    c = np.concatenate([[0.0], np.cumsum(w)])
    c[-1] = 1.0
    lo, hi = edges[:-1], edges[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(c > 0, c * c * (np.log(hi) - np.log(np.where(lo > 0, lo, 1.0))), 0.0)
        t2 = np.where(c < 1, (1 - c) ** 2 * (np.log1p(-lo) - np.log1p(-np.where(hi < 1, hi, 0.0))),
                      0.0)
    integral = float(np.sum(-(hi - lo) + t1 + t2))
    n_eff = 1.0 / np.sum(w * w)
    return n_eff * integral


def _kish(a: np.ndarray) -> float:
    return float(a.sum() ** 2 / np.dot(a, a))


# --- the estimate ------------------------------------------------------------------------------

def _check_data(x, weights, settings: TailSettings) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(x, dtype=float).ravel()
    if weights is None:
        w = np.ones(x.size)
    else:
        w = np.asarray(weights, dtype=float).ravel()
        if w.shape != x.shape:
            raise ValueError(f"{w.size} weights for {x.size} maxima")
        if not (np.isfinite(w).all() and (w > 0).all()):
            raise ValueError("weights must be finite and > 0")
    bad = ~np.isfinite(x)
    if bad.any():
        raise TailNotEstimable(f"{int(bad.sum())} of {x.size} maxima are not finite (NaN or inf)")
    short = settings.model in ("gev", "gumbel") and settings.short_record_model == "gumbel"
    needed = settings.min_samples_short if short else settings.min_samples
    if x.size < needed:
        raise TailNotEstimable(f"{x.size} samples, fewer than the {needed} a tail fit needs "
                               "(limits.tail.min_samples" + ("_short" if short else "") + ")")
    distinct = np.unique(x).size
    if distinct == 1:
        raise TailNotEstimable(f"all {x.size} maxima are equal ({x[0]:.6g}): zero variance, "
                               "no tail to fit")
    if distinct < min(settings.min_distinct, x.size):
        raise TailNotEstimable(f"only {distinct} distinct values among {x.size} maxima (fewer "
                               f"than {min(settings.min_distinct, x.size)}): the maxima are not "
                               "continuous")
    return x, w / w.mean()


def _pot_threshold(x, a, settings: TailSettings) -> float:
    """The weighted ``threshold_quantile``, lowered to the order statistic that leaves
    ``min_exceedances`` samples above it when the quantile leaves fewer."""
    u = float(weighted_quantile(x, a, [settings.threshold_quantile])[0])
    xs = np.sort(x)
    if np.sum(x > u) < settings.min_exceedances:
        if x.size <= settings.min_exceedances:
            raise TailNotEstimable(f"{x.size} samples: peaks over threshold needs more than "
                                   f"{settings.min_exceedances} (limits.tail.min_exceedances)")
        u = float(xs[x.size - settings.min_exceedances - 1])
    if np.sum(x > u) < settings.min_exceedances:   # ties at u
        raise TailNotEstimable(f"only {int(np.sum(x > u))} samples above the POT threshold "
                               f"{u:.6g} (ties): fewer than {settings.min_exceedances}")
    return u


def estimate_tail(x, limit: float, weights=None,
                  settings: TailSettings = TailSettings()) -> TailEstimate:
    """``P(X > limit)`` from the tail model of the maxima ``x`` (weights optional).

    Raises :class:`TailNotEstimable` (with the reason) when the data do not support a tail
    estimate, ``ValueError`` for invalid arguments.
    """
    if settings.model == "none":
        raise TailNotEstimable("tail model disabled (limits.tail.model: none)")
    limit = float(limit)
    if not np.isfinite(limit):
        raise ValueError(f"limit must be finite, got {limit}")
    x, a = _check_data(x, weights, settings)
    # Standardise so that the optimiser's simplex has a sensible size whatever the unit.
    centre, spread = float(np.median(x)), float(np.std(x))
    xs, zs = (x - centre) / spread, (limit - centre) / spread
    level = settings.confidence_level
    model_name = settings.model
    if model_name == "gev" and x.size < settings.min_samples:
        model_name = "gumbel"      # _check_data let it through: short_record_model is gumbel
        short_note = (f" (xi = 0: {x.size} samples, fewer than the {settings.min_samples} the "
                      "GEV shape needs)")
    else:
        short_note = ""
    if model_name == "gev":
        model = _GEV(xs, a, settings.min_shape)
        threshold = np.nan
        label = "GEV"
    elif model_name == "gumbel":
        model = _Gumbel(xs, a, settings.min_shape)
        threshold = np.nan
        label = "Gumbel" + short_note
    else:
        us = (_pot_threshold(x, a, settings) - centre) / spread
        if zs <= us:
            raise TailNotEstimable(
                f"the limit {limit:.6g} is not above the POT threshold {centre + spread * us:.6g} "
                f"(the {settings.threshold_quantile:g} quantile): the counting estimate applies")
        model = _POT(xs, a, us, settings.min_shape)
        threshold = centre + spread * us
        label = (f"POT (GPD above the {settings.threshold_quantile:g} quantile, "
                 f"{int(model.above.sum())} exceedances)")
    theta, nll_hat = _fit(model, model.starts(), settings.min_shape)
    lp_hat = model.log_p(theta, zs)
    weighted = not np.allclose(a, 1.0, rtol=1e-12, atol=0.0)
    notes: list[str] = []

    # Curvature and sandwich in the model's own parametrisation (well conditioned), carried to
    # log p by the delta method: var(log p) = g' V g with g the gradient of log p(theta).
    free_hat = model.free(theta)
    theta = np.asarray(theta, float)
    grads, hess = _derivatives(lambda t: model.logf(t), theta, a)
    info = -hess
    if not (np.isfinite(info).all() and np.isfinite(grads).all()):
        raise TailNotEstimable(f"{model.name} likelihood not differentiable at the optimum "
                               "(an observation at the support's end)")
    try:
        np.linalg.cholesky(info)
    except np.linalg.LinAlgError:
        raise TailNotEstimable(f"{model.name} likelihood curvature at the optimum is not "
                               "positive definite: no interval") from None
    inv = np.linalg.inv(info)
    sg = grads * a[:, None]
    sand = inv @ (sg.T @ sg) @ inv
    var_lp, c_adj = np.nan, 1.0
    if np.isfinite(lp_hat) and lp_hat < 0:
        h = 1e-5 * np.maximum(1.0, np.abs(theta))
        glp = np.array([(model.log_p(theta + h[j] * e, zs) - model.log_p(theta - h[j] * e, zs))
                        / (2.0 * h[j]) for j, e in enumerate(np.eye(theta.size))])
        if np.isfinite(glp).all():
            v_model, v_sand = float(glp @ inv @ glp), float(glp @ sand @ glp)
            var_lp = v_sand if weighted else v_model
            if weighted and v_model > 0:
                c_adj = v_sand / v_model
    elif weighted:
        # log p at -inf (limit beyond the fitted end point): the conservative bound of the ratio
        # over all directions, the largest eigenvalue of I^-1 J.
        c_adj = max(float(np.max(np.real(np.linalg.eigvals(inv @ (sg.T @ sg))))), 1.0)

    n = int(x.size)
    if settings.interval == "profile":
        cutoff = c_adj * float(stats.chi2.ppf(level, 1))
        low, high = _profile_interval(model, zs, lp_hat, free_hat, nll_hat, cutoff, var_lp,
                                      model.log_p(theta, float(np.max(xs))))
        with np.errstate(over="ignore"):   # inf: the estimate is uncertain by decades
            cov = float(np.sqrt(np.expm1(var_lp))) if np.isfinite(var_lp) else np.nan
        how = f"profile-likelihood {100 * level:g} %" + (
            f", sandwich-adjusted (c = {c_adj:.2f})" if weighted else "")
    else:
        low, high, cov, failed = _bootstrap_interval(model, zs, theta, settings)
        how = f"bootstrap {100 * level:g} % ({settings.n_bootstrap} resamples, seed {settings.seed})"
        if failed:
            notes.append(f"{failed} of {settings.n_bootstrap} bootstrap refits failed")
    p_hat = float(np.exp(lp_hat))

    u_pit, w_pit = model.pit(theta)
    gof = _weighted_ad(np.asarray(u_pit, float), np.asarray(w_pit, float))
    gof_p, gof_how = _gof_pvalue(model, theta, gof, _kish(w_pit), settings)

    # Return period of the largest observation under the fit, against the limit's.
    lp_max = model.log_p(theta, float(np.max(xs)))
    ratio = float(np.exp(lp_max - lp_hat)) if np.isfinite(lp_max) else np.nan
    extrapolation = bool(p_hat == 0.0 or (np.isfinite(ratio)
                                          and ratio > settings.extrapolation_factor))
    status = "fitted"
    if p_hat == 0.0:
        status += ("; the limit lies beyond the fitted upper end point of the maxima"
                   if model.shape(theta) < 0 else
                   "; P at the limit is below the smallest representable probability")
    if extrapolation:
        status += (f"; extrapolation far beyond the data (return period > "
                   f"{settings.extrapolation_factor:g} x that of the largest observation"
                   + (f": {ratio:.3g} x" if np.isfinite(ratio) and p_hat > 0 else "") + ")")
    for note in notes:
        status += f"; {note}"
    if model_name in ("gev", "gumbel"):
        loc, zeta, n_exc = centre + spread * theta[0], np.nan, n
    else:
        loc = threshold
        zeta = float(np.sum(a[model.above]) / np.sum(a))
        n_exc = int(model.above.sum())
    return TailEstimate(
        limit=limit, probability=p_hat, ci_low=low, ci_high=high, cov=cov, n_evaluations=n,
        model=model_name,
        method=f"{label}, {'weighted ' if weighted else ''}MLE, {how}",
        gof_statistic=gof, gof_pvalue=gof_p, gof_method=gof_how, extrapolation=extrapolation,
        status=status, location=float(loc), scale=float(spread * np.exp(theta[1])),
        shape=model.shape(theta), threshold=float(threshold), zeta=float(zeta),
        n_exceedances=n_exc, return_period_ratio=ratio, notes=tuple(notes))


#: how far beyond an interval end, in log p, the profile is checked from just inside it, and how
#: many ends of one side may fail that check before the interval is given up
#: (:func:`_profile_interval`): twice Brent's tolerance, so a true crossing lies between the two
_END_CHECK, _END_CHECKS = 2e-3, 20

#: log-scale increments of the raised starts of a profile point, and how many of the best
#: candidates a profile point's Nelder-Mead also starts from where the previous optimum lies
#: outside the support (one elsewhere; :func:`_profile_starts`)
_SCALE_RAISES = tuple(0.25 * 2.0 ** k for k in range(8))
_PROFILE_CANDIDATE_STARTS = 3


def _profile_starts(fun, previous, fixed, grid, edge) -> list[np.ndarray]:
    """The starting points of a profile point's Nelder-Mead runs (``fun``: its objective;
    ``grid``: candidate points, one per row): the previous profile point's optimum and the
    estimate's where they lie inside the support, and the candidate of least ``fun`` among
    ``grid`` and those two points with their log-scale raised step by step
    (:data:`_SCALE_RAISES`), the :data:`_PROFILE_CANDIDATE_STARTS` least where the previous
    optimum lies outside the support. ``edge``: the model's points just inside the support next
    to a given one (the models' ``edge_starts``), for the previous optimum and the estimate's
    where they lie outside.

    Why more than the previous optimum: when the limit lies far above the data, the profile's
    minimum lies in a narrow band next to the support's edge (for xi > 0 the GEV's lower end
    point mu - sigma/xi just below the smallest observation; for the GPD with xi < 0 the upper
    end point just above the largest excess), and a simplex started from the neighbouring
    profile point can stall at that edge far above the minimum; a start from another side
    reaches it. As the probability at the limit grows the previous optimum leaves the support;
    a larger scale brings a point back, which is why the raised points are candidates (a grid
    alone finds inside the support only short-tailed points, worse by dozens of orders of
    magnitude). Why several candidates: the previous optimum hugs the support's edge, so a step
    of 1e-3 in log p can already put it outside, and the simplex from the single best candidate
    can stall at the edge too (a value several units too high, read as the interval's end).
    An empty list: no candidate inside the support."""
    given = [(point, bool(np.isfinite(fun(point)))) for point in (previous, fixed)]
    starts = [point for point, inside in given if inside]
    if len(starts) == 2 and np.array_equal(*starts):   # the first point of each end
        starts.pop()
    for point, inside in given:
        if not inside:
            starts += [s for s in edge(point) if np.isfinite(fun(s))][:1]
    raise_scale = np.outer(_SCALE_RAISES, np.eye(previous.size)[0])
    candidates = np.vstack((grid, previous + raise_scale, fixed + raise_scale))
    values = fun.at(candidates)
    # several candidates only where the continuation broke off (the previous optimum outside
    # the support): from inside it the path's own start is the one that reaches the minimum
    previous_inside = given[0][1]
    best = np.argsort(values, kind="stable")[:1 if previous_inside else _PROFILE_CANDIDATE_STARTS]
    starts += [candidates[k] for k in best if np.isfinite(values[k])]
    return starts


#: how close to the GEV support's edge, in log sigma, a profile point's optimum must lie to be
#: followed along the edge (:func:`_along_edge`)
_EDGE_BAND = 1e-2


def _along_edge(model, lp: float, z: float, res):
    """``res`` (a profile point's Nelder-Mead result at (log p, z)) improved by a second run
    along the support's edge where its optimum lies within :data:`_EDGE_BAND` of it (the models'
    ``edge_coordinates``; GEV with xi > 0 only). Far beyond the data the profile's minimum lies
    in a band next to the edge whose width in log sigma shrinks with the distance to the limit;
    a simplex in (log sigma, xi) that meets the edge contracts across the band and stops short
    of the minimum along it (values some 0.02 too high, enough to end an interval 1 % early),
    while in (t, xi), log sigma = edge + e^t, that band is a valley of ordinary width."""
    if res is None or not np.isfinite(res.fun):
        return res
    along = model.edge_coordinates(res.x, lp, z)
    if along is None:
        return res
    polished = _Objective(model, profile=(lp, z), along_edge=True).minimise([along], tol=1e-6)
    if polished is None or not polished.fun < res.fun:
        return res
    return optimize.OptimizeResult(x=model.from_edge_coordinates(polished.x, lp, z),
                                   fun=polished.fun, nit=res.nit + polished.nit,
                                   nfev=res.nfev + polished.nfev, status=polished.status,
                                   success=polished.success, message=polished.message)


def _profile_point(model, lp: float, z: float, start, fixed, grid):
    """The Nelder-Mead result (None: no start inside the support) of one profile point at
    (log p, z): the runs from the starts of :func:`_profile_starts` (``start``: the warm start,
    ``fixed``: the estimate's free parameters, ``grid``: :func:`_profile_grid`'s candidates),
    followed along the support's edge where the optimum lies next to it (:func:`_along_edge`)."""
    fun = _Objective(model, profile=(lp, z))
    edge = functools.partial(model.edge_starts, lp=lp, z=z)
    return _along_edge(model, lp, z,
                       fun.minimise(_profile_starts(fun, start, fixed, grid, edge), tol=1e-6))


def _profile_grid(fixed: np.ndarray, xi_min: float) -> np.ndarray:
    """The candidate starts of every profile point (one per row; :func:`_profile_starts`)
    around the estimate's free parameters ``fixed``: its scale moved by -3 .. 2 in log, and for
    the GEV and the GPD also shapes -0.3 .. 2 (those >= ``xi_min``) at scales up to e^9 times
    the estimate's: a short-tailed shape with a large scale is where a start reaches the
    profile's narrow band from outside."""
    steps = (-3.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0)
    if fixed.size == 1:      # Gumbel: the scale is the only other parameter
        return np.array([fixed + ds for ds in steps])
    grid = [fixed + np.array([ds, 0.0]) for ds in steps]
    grid += [np.array([fixed[0] + ds, xi])
             for ds in (-2.0, -1.0, 0.0, 1.0, 2.0, 4.0, 6.0, 9.0)
             for xi in (-0.3, -0.15, 0.0, 0.15, 0.3, 0.6, 1.0, 2.0) if xi >= xi_min]
    return np.array(grid)


def _profile_interval(model, z, lp_hat, free_hat, nll_hat, cutoff, var_lp, lp_top):
    """Both ends of ``{log p : 2 (nll_prof(log p) - nll_hat) <= cutoff}`` (Coles 2001 §2.6.6):
    bracket by growing steps from the estimate, then Brent's method to 1e-3 in log p. Each
    profile point is the best of Nelder-Mead runs from the optimum at the nearest point
    evaluated so far (a continuous path), the estimate's and the best few of a grid
    (:func:`_profile_starts`); a point where none of them lies inside the support is a failed
    search, not a crossing (:class:`TailNotEstimable`). When the estimate is p = 0 the upper
    end is approached from ``lp_top`` (log p at the largest observation).

    Each end is accepted only when the profile just beyond it, followed from the optimum at the
    nearest point inside, is beyond the cutoff (:data:`_END_CHECK`). A failed minimisation can
    only give too high a value, so a false crossing always ends the interval too early: the
    bracket's outer point is reached by a jump of several units in log p, where the previous
    optimum usually lies outside the support and a simplex started elsewhere can stall at the
    support's edge. When the check fails, the search goes on outwards from there."""
    fixed = np.asarray(free_hat, float)
    grid = _profile_grid(fixed, model.xi_min)

    # log p -> (g, the profile's optimum there), over both ends
    cache: dict[float, tuple[float, np.ndarray]] = {}

    def nearest(lp, inside: bool = False) -> np.ndarray:
        """The optimum at the evaluated point nearest ``lp`` (only among those inside the
        interval with ``inside``), the estimate's before any: the warm start of a profile
        point, a continuous path wherever Brent's method jumps."""
        evaluated = [k for k, (value, _) in cache.items() if not inside or value <= 0]
        if not evaluated:
            return fixed
        return cache[min(evaluated, key=lambda k: abs(k - lp))][1]

    def prof(lp, start):
        res = _profile_point(model, lp, z, start, fixed, grid)
        if res is None or not np.isfinite(res.fun):
            # Not "beyond the cutoff": the profile is finite at every p in (0, 1) (a large
            # enough scale gives every observation and the limit a positive density), so an
            # infinite value is a failed search, and treating it as a crossing would end the
            # interval there, too narrow.
            raise TailNotEstimable(
                f"{model.name} profile likelihood: no parameters inside the support found at "
                f"P = {np.exp(lp):.3g} at the limit; no interval")
        return 2.0 * (res.fun - nll_hat) - cutoff, res.x

    def g(lp):
        if lp not in cache:
            cache[lp] = prof(lp, nearest(lp))
        return cache[lp][0]

    upper_cap = np.log1p(-1e-12)
    se = np.sqrt(var_lp) if np.isfinite(var_lp) and var_lp > 0 else 1.0
    step0 = max(np.sqrt(cutoff) * se, 0.05)

    def brent(a, b):
        lo_end, hi_end = min(a, b), max(a, b)
        if np.sign(g(lo_end)) == np.sign(g(hi_end)):
            raise TailNotEstimable("profile likelihood is not monotone near the interval's end")
        return optimize.brentq(lambda v: np.clip(g(v), -1e6, 1e6), lo_end, hi_end, xtol=1e-3)

    def false_crossing(lp_end, direction: int) -> float | None:
        """None when ``lp_end`` is a crossing along a continuous path; else the point just
        beyond it, inside the interval after all, whose cached value is then corrected and
        every cached value beyond it dropped."""
        beyond = lp_end + direction * _END_CHECK
        if not _LOG_P_FLOOR < beyond < upper_cap:
            return None
        value, optimum = prof(beyond, nearest(lp_end, inside=True))
        if value > 0:
            return None
        for lp in [k for k in cache if direction * (k - beyond) >= 0]:
            del cache[lp]
        cache[beyond] = (value, optimum)
        return beyond

    def bracket(inner, direction: int) -> float:
        """The end beyond ``inner`` (inside the interval): growing steps, then Brent's method."""
        step = step0
        for _ in range(60):
            outer = inner + direction * step
            if direction > 0 and outer >= upper_cap:
                outer = upper_cap
                if g(outer) <= 0:
                    return upper_cap
                break
            if direction < 0 and outer <= _LOG_P_FLOOR:
                outer = _LOG_P_FLOOR
                if g(outer) <= 0:
                    return _LOG_P_FLOOR
                break
            if g(outer) > 0:
                break
            inner = outer
            step *= 1.8
        else:
            raise TailNotEstimable("profile likelihood did not reach the cutoff")
        return brent(inner, outer)

    def end(direction: int) -> float:
        inner = lp_hat
        lp_end = None
        if not np.isfinite(lp_hat):   # p_hat = 0: the lower end is 0
            if direction < 0:
                return _LOG_P_FLOOR
            inner = min(lp_top, upper_cap)
            if g(inner) > 0:          # descend from the largest observation's probability
                step = 1.0
                for _ in range(60):
                    outer = max(inner - step, _LOG_P_FLOOR)
                    if g(outer) <= 0:
                        lp_end = brent(outer, inner)
                        break
                    if outer <= _LOG_P_FLOOR:
                        return _LOG_P_FLOOR   # every p above the floor is implausible
                    inner, step = outer, step * 1.8
                else:
                    raise TailNotEstimable("profile likelihood did not reach the cutoff")
        for _ in range(_END_CHECKS):
            if lp_end is None:
                lp_end = bracket(inner, direction)
            inner = false_crossing(lp_end, direction)
            if inner is None:
                return lp_end
            lp_end = None
        raise TailNotEstimable(f"{model.name} profile likelihood: no crossing of the cutoff "
                               f"confirmed along a continuous path after {_END_CHECKS} tries")

    low, high = end(-1), end(+1)
    low_p = 0.0 if low <= _LOG_P_FLOOR else float(np.exp(low))
    high_p = 1.0 if high >= upper_cap else float(np.exp(high))
    return low_p, high_p


def _bootstrap_interval(model, z, theta, settings: TailSettings):
    """Percentile interval of p over refits on samples of the (x_i, a_i) pairs drawn with
    replacement (Efron & Tibshirani 1993, ch. 13; the pairs are i.i.d. from the sampling
    distribution, so this is valid for importance weights), seeded."""
    rng = np.random.default_rng(settings.seed)
    n = model.x.size
    ps, failed = [], 0
    for _ in range(settings.n_bootstrap):
        sub = model.resample(rng.integers(0, n, n))
        try:
            if isinstance(sub, _POT) and sub.above.sum() < 5:
                raise TailNotEstimable("too few exceedances")
            t, _ = _fit(sub, [theta], _XI_MIN, tol=1e-6)
            ps.append(np.exp(sub.log_p(t, z)))
        except TailNotEstimable:
            failed += 1
    if len(ps) < 0.9 * settings.n_bootstrap:
        raise TailNotEstimable(f"{failed} of {settings.n_bootstrap} bootstrap refits failed")
    ps = np.asarray(ps)
    alpha = 1.0 - settings.confidence_level
    low, high = np.quantile(ps, [alpha / 2, 1 - alpha / 2])
    p_hat = float(np.exp(model.log_p(theta, z)))
    cov = float(np.std(ps, ddof=1) / p_hat) if p_hat > 0 else np.nan
    return float(low), float(high), cov, failed


def _gof_pvalue(model, theta, statistic: float, n_eff: float, settings: TailSettings):
    """Parametric-bootstrap p-value of the Anderson-Darling statistic at Kish's effective size
    (exact resampling scheme for equal weights, approximate for weighted samples)."""
    b = settings.gof_bootstrap
    what = "Anderson-Darling A² of the fitted " + (model.name if isinstance(model, _GEV) else
                                                   "GPD of the excesses")
    if b <= 0:
        return np.nan, what + "; no p-value (limits.tail.gof_bootstrap = 0)"
    rng = np.random.default_rng(settings.seed + 1)
    size = max(int(round(n_eff)), 5)
    hits, done = 0, 0
    for _ in range(b):
        sim = model.simulate(theta, size, rng)
        try:
            # started at the parameters it was drawn from, next to its optimum: no restart
            t, _ = _fit(sim, [theta], _XI_MIN, tol=1e-6, restart=False)
        except TailNotEstimable:
            continue
        u, w = sim.pit(t)
        hits += _weighted_ad(np.asarray(u, float), np.asarray(w, float)) >= statistic
        done += 1
    if done == 0:
        return np.nan, what + "; parametric bootstrap failed"
    return (1.0 + hits) / (1.0 + done), what + f"; p-value from {done} parametric bootstrap refits"
