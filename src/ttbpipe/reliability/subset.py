"""Subset simulation (Au & Beck 2001) with adaptive conditional sampling, as an ask/tell machine.

Method (Au & Beck 2001, Probab. Eng. Mech. 16:263). The failure event F = {g(u) <= 0} of a
standard-normal vector u is reached through nested intermediate events F_j = {g(u) <= b_j},
b_1 > b_2 > ... > 0, each with conditional probability about ``p0``:

* level 0: ``N`` independent standard-normal points (plain Monte Carlo); b_1 is the ``p0``
  quantile of their g values;
* level j >= 1: the ``Nc = p0 N`` points with g <= b_j seed ``Nc`` Markov chains of ``Ns = 1/p0``
  states each (the seed is the first state), whose stationary distribution is the standard
  normal conditional on F_j; b_{j+1} is again the ``p0`` quantile of their N g values;
* it stops at the first level whose ``p0`` quantile is <= 0: ``P = p0^m * P_m``, with ``P_m``
  the fraction of the last level's points with g <= 0.

Markov chain: the adaptive conditional sampler (aCS) of Papaioannou, Betz, Zwirglmaier & Straub
(2015, Probab. Eng. Mech. 41:89, Algorithm 5). Per component i, the candidate is
``v_i = rho_i u_i + sqrt(1 - rho_i^2) xi_i``, ``xi_i ~ N(0, 1)``, with
``sqrt(1 - rho_i^2) = sigma_i = min(1, lambda s_i)`` and ``s_i`` the standard deviation of
component i over the level's seeds. This proposal is reversible with respect to the standard
normal, so the candidate is accepted if and only if it lies in F_j: the acceptance rate does not
collapse with the dimension as it does for the component-wise Metropolis sampler of Au & Beck
(its proposal is a preconditioned Crank-Nicolson step; Cotter et al. 2013, Stat. Sci. 28:424).
``lambda`` is adapted towards the acceptance rate 0.44 (Papaioannou et al., eq. 23:
``ln lambda <- ln lambda + (a_hat - a*) / sqrt(k)`` after the k-th adaptation). Here the chains
advance in lockstep, so each chain step is one vectorised evaluation of ``Nc`` candidates and
``lambda`` is adapted after every step from that step's acceptance; a level starts from the
previous level's final ``lambda`` (restarting at 0.6 was measured no better).

Second sampler, ``sampler="plane"`` (opt-in; docs/reliability.md section 10, ``plane-trunc``
of benchmarks/subset_kernel_variants.py). The least-squares plane ``g ~ b0 + b.u`` is fitted
through every point evaluated so far (its sums accumulated in evaluation order). Where it
explains g (adjusted coefficient of determination >= ``plane_min_r2``, default 0.99: a flat
boundary) and rests on at least twice as many points as coefficients, every chain step draws
the component along ``d = -b/|b|`` from the standard normal truncated below at the plane's
own boundary of the level, ``(b0 - b_j)/|b|``, less ``plane_margin`` standard deviations of the
plane's residuals, and moves the rest by a pCN step. No seed enters that proposal; the candidate
is accepted iff the current state lies beyond the truncation and the candidate in F_j (the
Metropolis-Hastings ratio of a proposal proportional to the prior). Elsewhere the level runs aCS.

Coefficient of variation. Per level, Au & Beck (2001, eqs. 19-29): for a level estimate
``p_j`` from N correlated chain states, ``delta_j^2 = (1 - p_j)/(N p_j) (1 + gamma_j)``, with
``gamma_j = 2 sum_{k=1}^{Ns-1} (1 - k Nc/N) rho_j(k)`` and ``rho_j(k)`` the lag-k correlation of
the indicator ``1[g <= b_{j+1}]`` along the chains (eq. 27, estimated from the chains); gamma = 0
at level 0 (the levels table's ``cov``). Summing ``delta_j^2`` over the levels (Au & Beck's
uncorrelated-levels value, ``details["cov_au_beck"]``) misses the correlation that the chains
carry from level to level: a level's seeds are states of the previous level's chains, so an
excess of deep states in one lineage shows again in its descendants. The reported c.o.v. is
therefore :func:`lineage_variance`'s: the first-order (delta-method) expansion
``ln P_hat - ln P = sum_j sum_i (I_ji - p_j)/(N p_j)`` with the states grouped by their ancestor
chain ``lag`` levels back, groups independent, states within a group arbitrarily correlated
(a cluster-robust variance over lineages). The fully correlated upper bound
``(sum_j delta_j)^2`` is kept in ``details["cov_upper_bound"]``. The interval is lognormal with
the reported c.o.v. (:func:`ttbpipe.reliability.result.lognormal_interval`).
docs/reliability.md section 10 has the measured coverage of both.

Determinism: level-0 point i is drawn from ``SeedSequence([seed, RARE_EVENT, RARE_EVENT_SUBSET,
0, i])``; the chain started from the c-th seed of level j (seeds in ascending g, ties by index)
from its own generator ``SeedSequence([seed, RARE_EVENT, RARE_EVENT_SUBSET, j, c])``. Results
therefore depend on the seed and the settings only, never on how a caller batches the points.

Ask/tell: :meth:`SubsetSimulation.ask` returns the points to evaluate next (all N at level 0,
the ``Nc`` candidates of one chain step afterwards); :meth:`SubsetSimulation.tell` takes their
g values. :meth:`SubsetSimulation.save` / :meth:`SubsetSimulation.load` persist the whole state
(including asked but untold points and the chains' generators), written to a temporary file and
renamed, so a killed run resumes exactly where it stopped and gives the same answer.
"""

from __future__ import annotations

import json
import logging
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd
from scipy.special import log_ndtr, ndtri_exp

from .. import streams
from .monte_carlo import evaluate_limit_state
from .result import FailureProbability, lognormal_interval

__all__ = ["SubsetSettings", "SubsetSimulation", "subset_simulation", "indicator_gamma",
           "lineage_variance"]

log = logging.getLogger(__name__)

STATE_VERSION = 2
#: Markov chain samplers of :class:`SubsetSimulation` (module docstring).
SAMPLERS = ("acs", "plane")


@dataclass(frozen=True)
class SubsetSettings:
    """Settings of subset simulation.

    ``n_per_level`` N and ``level_probability`` p0 (N p0 and 1/p0 integers; Au & Beck recommend
    p0 = 0.1, Zuev et al. 2012 show 0.1-0.3 near-optimal); ``max_levels`` stops a run that does
    not reach the failure domain; ``target_acceptance`` and ``initial_scale`` (lambda) of the
    aCS sampler (Papaioannou et al. 2015: 0.44, 0.6); ``lineage_lag``, how many levels back the
    c.o.v. groups the states by common ancestor (:func:`lineage_variance`; 2 measured best,
    docs/reliability.md section 10); ``sampler`` ``"acs"`` or ``"plane"`` (module docstring),
    with ``plane_min_r2`` and ``plane_margin``.
    """

    n_per_level: int = 1000
    level_probability: float = 0.1
    max_levels: int = 20
    target_acceptance: float = 0.44
    initial_scale: float = 0.6
    confidence_level: float = 0.95
    lineage_lag: int = 2
    sampler: str = "acs"
    plane_min_r2: float = 0.99
    plane_margin: float = 2.0

    def __post_init__(self) -> None:
        p0, n = float(self.level_probability), int(self.n_per_level)
        if not 0.0 < p0 <= 0.5:
            raise ValueError(f"level_probability must be in (0, 0.5], got {p0}")
        n_chains = round(p0 * n)
        if n_chains < 2 or abs(p0 * n - n_chains) > 1e-9 or n % n_chains:
            raise ValueError(f"n_per_level * level_probability must be an integer >= 2 that "
                             f"divides n_per_level (chains of equal length); got N = {n}, p0 = {p0}")
        if not 0.0 < self.target_acceptance < 1.0 or not self.initial_scale > 0.0:
            raise ValueError("target_acceptance must be in (0, 1) and initial_scale > 0")
        if int(self.max_levels) < 1:
            raise ValueError("max_levels must be >= 1")
        if int(self.lineage_lag) < 0:
            raise ValueError("lineage_lag must be >= 0")
        if self.sampler not in SAMPLERS:
            raise ValueError(f"sampler must be one of {SAMPLERS}, got {self.sampler!r}")
        if not 0.0 <= float(self.plane_min_r2) <= 1.0 or not float(self.plane_margin) >= 0.0:
            raise ValueError("plane_min_r2 must be in [0, 1] and plane_margin >= 0")

    @property
    def n_chains(self) -> int:
        return round(self.level_probability * self.n_per_level)

    @property
    def chain_length(self) -> int:
        return self.n_per_level // self.n_chains


def indicator_gamma(indicator: np.ndarray) -> float:
    """Au & Beck's (2001) eq. 27-29 correlation factor gamma of one level.

    ``indicator``: shape (Ns, Nc), the failure indicator of chain c's state t (t = 0 the seed).
    ``R(k) = sum_c sum_{t<Ns-k} I_{t,c} I_{t+k,c} / (N - k Nc) - p^2``, ``rho(k) = R(k)/R(0)``,
    ``gamma = 2 sum_{k=1}^{Ns-1} (1 - k Nc/N) rho(k)``; 0 when the indicator is constant.
    """
    ind = np.asarray(indicator, dtype=float)
    n_steps, n_chains = ind.shape
    n = ind.size
    p = ind.mean()
    r0 = p * (1.0 - p)
    if r0 <= 0.0:
        return 0.0
    gamma = 0.0
    for k in range(1, n_steps):
        r_k = float(np.sum(ind[:-k] * ind[k:])) / (n - k * n_chains) - p * p
        gamma += 2.0 * (1.0 - k * n_chains / n) * (r_k / r0)
    return float(gamma)


def _chain_ids(level: int, n_states: int, n_chains: int) -> np.ndarray:
    """Chain of each state of a level: level 0 points are their own chains; at level j >= 1 row
    ``t * Nc + c`` is state t of chain c."""
    ids = np.arange(n_states)
    return ids if level == 0 else ids % n_chains


def lineage_variance(indicators: list[np.ndarray], parents: list[np.ndarray | None],
                     probabilities: list[float], n_chains: int, lag: int = 2) -> float:
    """Variance of ``ln P_hat`` of subset simulation from the lineages of its states.

    ``indicators[j]``: level j's indicator ``1[g <= b_{j+1}]`` (the last level: ``1[g <= 0]``),
    rows as in :func:`_chain_ids`; ``parents[j]`` (j >= 1): for each chain of level j, the chain
    of level j-1 its seed was a state of (level 0: the point's index); ``probabilities[j]``: the
    level's estimate ``p_j``.

    First order (delta method), ``ln P_hat - ln P = sum_j Z_j``, ``Z_j = sum_i z_ji``,
    ``z_ji = (I_ji - p_j)/(N p_j)`` (Au & Beck 2001, eq. 19: the level's relative error). The
    states are grouped by their ancestor chain at level ``a = max(0, j - lag)``; groups are taken
    as independent and the states within one group as arbitrarily correlated, so that
    ``Var = sum_j sum_{j <= j' <= j + lag} (2 - [j = j']) K/(K-1) sum_k W_jk W_j'k``, with
    ``W_jk`` the sum of ``z_ji`` over the states of level j descending from chain k of level a and
    K the number of groups. This is the cluster-robust ("sandwich") variance of Liang & Zeger
    (1986, Biometrika 73:13, with the small-sample factor K/(K-1)) with the clusters chosen, as
    in the lag-based variance estimators of particle systems (Olsson & Douc 2019, Bernoulli
    25:1504), by the ancestor a fixed number of generations back, which keeps enough groups
    where the grouping by the first generation (Chan & Lai 2013, Ann. Stat. 41:2877; Lee &
    Whiteley 2018, Biometrika 105:609) would leave a handful. With ``lag = 0`` the groups are the
    chains of each level alone, close to Au & Beck's uncorrelated-levels value. ``inf`` when a
    level estimate is 0.
    """
    m = len(indicators)
    if m == 0:
        return float("nan")
    z = []
    for j in range(m):
        p = float(probabilities[j])
        if not p > 0.0:
            return float("inf")
        ind = np.asarray(indicators[j], dtype=float)
        z.append((ind - p) / (ind.size * p))

    def ancestors(j: int, a: int) -> np.ndarray:
        ids = _chain_ids(j, z[j].size, n_chains)
        for k in range(j, a, -1):
            ids = np.asarray(parents[k])[ids]
        return ids

    total = 0.0
    for j in range(m):
        a = max(0, j - int(lag))
        ids_j = ancestors(j, a)
        for jp in range(j, min(m, j + int(lag) + 1)):
            ids_jp = ids_j if jp == j else ancestors(jp, a)
            size = int(max(ids_j.max(), ids_jp.max())) + 1
            w_j = np.bincount(ids_j, weights=z[j], minlength=size)
            w_jp = np.bincount(ids_jp, weights=z[jp], minlength=size)
            groups = int(np.count_nonzero(np.bincount(ids_j, minlength=size)
                                          + np.bincount(ids_jp, minlength=size)))
            factor = groups / (groups - 1.0) if groups > 1 else 1.0
            term = factor * float(np.dot(w_j, w_jp))
            total += term if jp == j else 2.0 * term
    return max(total, 0.0)


def _generator_state(rng: np.random.Generator) -> dict[str, Any]:
    return rng.bit_generator.state


def _generator_from_state(state: dict[str, Any]) -> np.random.Generator:
    bit = np.random.PCG64()
    bit.state = state
    return np.random.Generator(bit)


class SubsetSimulation:
    """Subset simulation of ``P(g(u) <= 0)``, ``u ~ N(0, I_n_dims)``, driven by ask/tell.

    >>> sus = SubsetSimulation(n_dims=100, seed=1)
    >>> while not sus.done:
    ...     points = sus.ask()
    ...     sus.tell(3.5 - points.sum(axis=1) / 10.0)     # P = Phi(-3.5)
    >>> result = sus.result()
    """

    def __init__(self, n_dims: int, seed: int = 0,
                 settings: SubsetSettings = SubsetSettings()) -> None:
        if int(n_dims) < 1:
            raise ValueError(f"n_dims must be >= 1, got {n_dims}")
        self.n_dims = int(n_dims)
        self.seed = int(seed)
        self.settings = settings
        self.level = 0
        self.n_evaluations = 0
        self.done = False
        # current level: its N points (rows t*Nc + c for chain c, state t) and their g values
        self._u = np.empty((settings.n_per_level, self.n_dims))
        self._g = np.full(settings.n_per_level, np.nan)
        self._step = 0                      # chain state being generated (0 = seeds)
        self._pending: np.ndarray | None = None
        self._threshold = np.inf            # b_j of the current level (inf at level 0)
        self._scale = settings.initial_scale
        self._adaptations = 0
        self._sigma = np.ones(self.n_dims)
        self._rngs: list[np.random.Generator] = []
        self._accepted: list[float] = []
        self._levels: list[dict[str, Any]] = []
        self._final: dict[str, Any] | None = None
        # lineage of the closed levels, for the c.o.v. (lineage_variance): each level's indicator
        # and, from level 1 on, the previous-level chain of each chain's seed
        self._indicators: list[np.ndarray] = []
        self._parents: list[np.ndarray | None] = [None]
        # the plane sampler: least-squares sums over every evaluated point (rows [1, u]), and
        # the level's direction and truncation (direction None: the level runs aCS only)
        n_coef = self.n_dims + 1 if settings.sampler == "plane" else 0
        self._xtx = np.zeros((n_coef, n_coef))
        self._xtg = np.zeros(n_coef)
        self._gsum = np.zeros(2)                 # sum g, sum g^2
        self._direction: np.ndarray | None = None
        self._plane_low = 0.0
        self._plane_scale = settings.initial_scale
        self._plane_adaptations = 0
        self._plane_start_ok = np.zeros(0, dtype=bool)
        self._plane_r2 = float("nan")

    # --- the machine ----------------------------------------------------------------------
    def ask(self) -> np.ndarray:
        """The points whose g values :meth:`tell` expects next, shape (n, n_dims)."""
        if self.done:
            raise RuntimeError("subset simulation is finished: call result()")
        if self._pending is None:
            self._pending = self._level0_points() if self.level == 0 else self._candidates()
        return self._pending.copy()

    def tell(self, values: np.ndarray) -> None:
        """g values of the points of the last :meth:`ask`, in the same order."""
        if self._pending is None:
            raise RuntimeError("tell() without a pending ask()")
        values = np.asarray(values, dtype=float)
        if values.shape != (self._pending.shape[0],):
            raise ValueError(f"expected {self._pending.shape[0]} g values, got shape {values.shape}")
        if not np.all(np.isfinite(values)):
            raise FloatingPointError(
                f"subset level {self.level}, step {self._step}: {int((~np.isfinite(values)).sum())}"
                " non-finite g values; a failed model run cannot be placed in or out of the "
                "failure domain: fix the run or make g finite")
        points, self._pending = self._pending, None
        self.n_evaluations += values.size
        s = self.settings
        if s.sampler == "plane":
            rows = np.hstack([np.ones((points.shape[0], 1)), points])
            self._xtx += rows.T @ rows
            self._xtg += rows.T @ values
            self._gsum += (values.sum(), values @ values)
        if self.level == 0:
            self._u[:], self._g[:] = points, values
            self._close_level()
            return
        accept = values <= self._threshold
        plane_step = self._plane_step()
        if plane_step:
            accept &= self._plane_start_ok
        previous = slice((self._step - 1) * s.n_chains, self._step * s.n_chains)
        current = slice(self._step * s.n_chains, (self._step + 1) * s.n_chains)
        self._u[current] = np.where(accept[:, None], points, self._u[previous])
        self._g[current] = np.where(accept, values, self._g[previous])
        rate = float(accept.mean())
        self._accepted.append(rate)
        if plane_step:
            self._plane_adaptations += 1
            self._plane_scale = float(np.exp(np.log(self._plane_scale) + (
                rate - s.target_acceptance) / np.sqrt(self._plane_adaptations)))
        else:
            self._adaptations += 1
            self._scale = float(np.exp(np.log(self._scale) + (
                rate - s.target_acceptance) / np.sqrt(self._adaptations)))
        self._step += 1
        if self._step == s.chain_length:
            self._close_level()

    def run(self, g: Callable[[np.ndarray], np.ndarray]) -> FailureProbability:
        """Drive the machine with a vectorised ``g`` to the end; returns :meth:`result`."""
        while not self.done:
            points = self.ask()
            self.tell(evaluate_limit_state(g, points, f"subset level {self.level}, step {self._step}"))
        return self.result()

    # --- levels -----------------------------------------------------------------------------
    def _level0_points(self) -> np.ndarray:
        out = np.empty((self.settings.n_per_level, self.n_dims))
        for i in range(out.shape[0]):
            seq = np.random.SeedSequence([self.seed, streams.RARE_EVENT,
                                          streams.RARE_EVENT_SUBSET, 0, i])
            out[i] = np.random.default_rng(seq).standard_normal(self.n_dims)
        return out

    def _plane_step(self) -> bool:
        """Whether the current chain step is a plane step (every step of a plane level)."""
        return self._direction is not None

    def _candidates(self) -> np.ndarray:
        s = self.settings
        current = self._u[(self._step - 1) * s.n_chains:self._step * s.n_chains]
        if self._plane_step():
            return self._plane_candidates(current)
        sigma = np.minimum(1.0, self._scale * self._sigma)
        rho = np.sqrt(1.0 - sigma * sigma)
        xi = np.stack([rng.standard_normal(self.n_dims) for rng in self._rngs])
        return rho * current + sigma * xi

    def _plane_candidates(self, current: np.ndarray) -> np.ndarray:
        """A plane step: along d the standard normal beyond the truncation, the rest by pCN."""
        d = self._direction
        along = current @ d
        self._plane_start_ok = along >= self._plane_low
        sigma = min(1.0, self._plane_scale)
        log_tail = float(log_ndtr(-self._plane_low))
        out = np.empty_like(current)
        for c, rng in enumerate(self._rngs):
            xi = rng.standard_normal(self.n_dims)
            xi -= (xi @ d) * d
            s_new = -float(ndtri_exp(log_tail + np.log(rng.random())))
            out[c] = np.sqrt(1.0 - sigma * sigma) * (current[c] - along[c] * d) + sigma * xi \
                + s_new * d
        return out

    def _fit_plane(self) -> None:
        """The next level's direction and truncation, or None where the plane cannot carry it."""
        self._direction = None
        n_points, n_coef = self.n_evaluations, self._xtx.shape[0]
        if n_points < 2 * n_coef:
            self._plane_r2 = float("nan")
            return
        try:
            coef = np.linalg.solve(self._xtx, self._xtg)
        except np.linalg.LinAlgError:
            self._plane_r2 = float("nan")
            return
        sum_g, sum_g2 = self._gsum
        total = sum_g2 - sum_g * sum_g / n_points
        residual = max(float(sum_g2 - 2.0 * coef @ self._xtg + coef @ self._xtx @ coef), 0.0)
        # adjusted R^2: in-sample R^2 of n_coef coefficients on n points takes about
        # n_coef / n of the unexplained variance from noise (docs/reliability.md section 10)
        self._plane_r2 = (float(1.0 - residual / total * (n_points - 1) / (n_points - n_coef))
                          if total > 0.0 else float("nan"))
        norm = float(np.linalg.norm(coef[1:]))
        if not (norm > 0.0 and self._plane_r2 >= self.settings.plane_min_r2):
            return
        residual_sd = np.sqrt(residual / (n_points - n_coef))
        self._direction = -coef[1:] / norm
        # the plane's boundary of the level: b0 - |b| s = b_j
        self._plane_low = float((coef[0] - self._threshold) / norm
                                - self.settings.plane_margin * residual_sd / norm)

    def _close_level(self) -> None:
        """The level's N points are complete: next threshold, its statistics, next seeds."""
        s = self.settings
        order = np.lexsort((np.arange(self._g.size), self._g))      # ascending g, ties by row
        g_sorted = self._g[order]
        nc = s.n_chains
        n_fail = int(np.count_nonzero(self._g <= 0.0))
        # chain-state layout (Ns, Nc) for gamma; level 0 is i.i.d. (gamma = 0)
        final = g_sorted[nc - 1] <= 0.0 or self.level + 1 >= s.max_levels
        if final:
            indicator = self._g <= 0.0
            threshold, p_level = 0.0, n_fail / self._g.size
        else:
            # Au & Beck: b_{j+1} between the Nc-th and (Nc+1)-th smallest g, P(F_{j+1}|F_j) = p0.
            # Rejected chain moves repeat a state, so equal g values here are usually one point
            # twice, not a flat limit state; the Nc smallest are the seeds either way.
            threshold = 0.5 * (g_sorted[nc - 1] + g_sorted[nc])
            indicator = np.zeros(self._g.size, dtype=bool)
            indicator[order[:nc]] = True
            p_level = nc / self._g.size
            if threshold >= self._threshold:
                raise RuntimeError(
                    f"subset level {self.level}: the intermediate threshold {threshold:.6g} did "
                    f"not fall below the previous one {self._threshold:.6g}; the chains are stuck "
                    "on a plateau of g (a g that is constant over a region, e.g. a clipped or "
                    "saturated index): give g a continuous measure of the distance to failure")
        gamma = 0.0 if self.level == 0 else indicator_gamma(indicator.reshape(s.chain_length, nc))
        self._indicators.append(indicator.copy())
        if p_level > 0.0:
            delta = float(np.sqrt((1.0 - p_level) / (self._g.size * p_level) * (1.0 + gamma)))
        else:
            delta = float("inf")
        self._levels.append({
            "level": self.level, "threshold": float(threshold),
            "conditional_probability": float(p_level), "cov": delta, "gamma": gamma,
            "acceptance_rate": float(np.mean(self._accepted)) if self._accepted else float("nan"),
            "scale": float(self._scale) if self.level else float("nan"),
            "n_evaluations": int(self.n_evaluations),
            "g_min": float(g_sorted[0]), "g_median": float(np.median(self._g)),
        })
        log.info("subset level %d: threshold %.4g, P_level %.4g, c.o.v. %.3g, %d evaluations",
                 self.level, threshold, p_level, delta, self.n_evaluations)
        if final:
            if g_sorted[nc - 1] > 0.0:
                log.warning("subset simulation stopped at max_levels = %d before reaching the "
                            "failure domain; the estimate rests on %d failed points of the last "
                            "level", s.max_levels, n_fail)
            self.done = True
            return
        seeds = order[:nc]
        # the chain each seed belongs to (level 0: the point itself), for lineage_variance
        self._parents.append(seeds.copy() if self.level == 0 else seeds % nc)
        seed_u = self._u[seeds].copy()
        seed_g = self._g[seeds].copy()
        self._sigma = seed_u.std(axis=0, ddof=1) if nc > 1 else np.ones(self.n_dims)
        self._threshold = float(threshold)
        if s.sampler == "plane":
            self._fit_plane()
            self._levels[-1]["next_sampler"] = "plane" if self._direction is not None else "acs"
            self._levels[-1]["plane_r2"] = self._plane_r2
            self._plane_adaptations = 0
        self.level += 1
        self._u[:nc], self._g[:nc] = seed_u, seed_g
        self._g[nc:] = np.nan
        self._step = 1
        self._accepted = []
        self._adaptations = 0
        self._rngs = [np.random.default_rng(np.random.SeedSequence(
            [self.seed, streams.RARE_EVENT, streams.RARE_EVENT_SUBSET, self.level, c]))
            for c in range(nc)]

    def last_level(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the finished run's last-level states and their g values (N, n_dims), (N,):
        all lie in the deepest intermediate event (or the failure domain)."""
        if not self.done:
            raise RuntimeError("subset simulation not finished: keep calling ask()/tell()")
        return self._u.copy(), self._g.copy()

    # --- result -----------------------------------------------------------------------------
    def levels_table(self) -> pd.DataFrame:
        """One row per level: threshold, conditional probability, c.o.v., gamma, acceptance."""
        return pd.DataFrame(self._levels)

    def result(self) -> FailureProbability:
        if not self.done:
            raise RuntimeError("subset simulation not finished: keep calling ask()/tell()")
        table = self.levels_table()
        probability = float(np.prod(table["conditional_probability"]))
        deltas = table["cov"].to_numpy()
        cov_au_beck = float(np.sqrt(np.sum(deltas ** 2)))
        cov_upper = float(np.sum(deltas))
        cov = float(np.sqrt(lineage_variance(
            self._indicators, self._parents, list(table["conditional_probability"]),
            self.settings.n_chains, self.settings.lineage_lag)))
        low, high = lognormal_interval(probability, cov, self.settings.confidence_level)
        if probability == 0.0:
            # the last level saw no failure: only a bound, from its N points conditionally
            n_last = self.settings.n_per_level
            upper = float(np.prod(table["conditional_probability"].iloc[:-1])) * \
                (1.0 - (1.0 - self.settings.confidence_level) ** (1.0 / n_last))
            low, high = 0.0, upper
        s = self.settings
        sampler = ("aCS sampler" if s.sampler == "acs" else "plane sampler where the adjusted "
                   f"R^2 >= {s.plane_min_r2:g}, else aCS")
        method = (f"subset simulation (Au & Beck 2001; {sampler}), N = {s.n_per_level} per "
                  f"level, p0 = {s.level_probability:g}, {len(table)} levels, lognormal interval "
                  f"with the lineage c.o.v. (lag {s.lineage_lag})")
        return FailureProbability(probability, low, high, cov, int(self.n_evaluations), method,
                                  s.confidence_level,
                                  {"levels": table, "cov_au_beck": cov_au_beck,
                                   "cov_upper_bound": cov_upper, "seed": self.seed})

    # --- persistence ------------------------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the whole state to ``path`` (``.npz``), atomically (temporary file + rename)."""
        path = Path(path)
        meta = {
            "version": STATE_VERSION, "n_dims": self.n_dims, "seed": self.seed,
            "settings": asdict(self.settings), "level": self.level,
            "n_evaluations": self.n_evaluations, "done": self.done, "step": self._step,
            "threshold": self._threshold, "scale": self._scale, "adaptations": self._adaptations,
            "accepted": self._accepted, "levels": self._levels,
            "rngs": [_generator_state(r) for r in self._rngs],
            "has_pending": self._pending is not None,
            "n_indicators": len(self._indicators), "n_parents": len(self._parents),
            "plane_low": self._plane_low, "plane_scale": self._plane_scale,
            "plane_adaptations": self._plane_adaptations,
            "plane_r2": self._plane_r2,
            "has_direction": self._direction is not None,
        }
        arrays = {"u": self._u, "g": self._g, "sigma": self._sigma,
                  "pending": self._pending if self._pending is not None else np.empty((0, 0))}
        arrays.update({f"indicator_{j}": ind for j, ind in enumerate(self._indicators)})
        arrays.update({f"parent_{j}": par for j, par in enumerate(self._parents) if j > 0})
        if self.settings.sampler == "plane":
            arrays.update(xtx=self._xtx, xtg=self._xtg, gsum=self._gsum,
                          plane_start_ok=self._plane_start_ok)
            if self._direction is not None:
                arrays["direction"] = self._direction
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, meta=np.array(json.dumps(meta)), **arrays)
        os.replace(tmp, path)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "SubsetSimulation":
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta.get("version") != STATE_VERSION:
                raise ValueError(f"{path}: subset-simulation state version {meta.get('version')}, "
                                 f"this code reads version {STATE_VERSION}; rerun from the start")
            self = cls(meta["n_dims"], meta["seed"], SubsetSettings(**meta["settings"]))
            self._u[:] = data["u"]
            self._g[:] = data["g"]
            self._sigma = data["sigma"].copy()
            self._pending = data["pending"].copy() if meta["has_pending"] else None
            self._indicators = [data[f"indicator_{j}"].copy() for j in range(meta["n_indicators"])]
            self._parents = [None] + [data[f"parent_{j}"].copy()
                                      for j in range(1, meta["n_parents"])]
            if self.settings.sampler == "plane":
                self._xtx, self._xtg = data["xtx"].copy(), data["xtg"].copy()
                self._gsum = data["gsum"].copy()
                self._plane_start_ok = data["plane_start_ok"].copy()
                self._direction = data["direction"].copy() if meta["has_direction"] else None
                self._plane_low, self._plane_scale = meta["plane_low"], meta["plane_scale"]
                self._plane_adaptations = meta["plane_adaptations"]
                self._plane_r2 = meta["plane_r2"]
        self.level, self.n_evaluations, self.done = meta["level"], meta["n_evaluations"], meta["done"]
        self._step, self._threshold, self._scale = meta["step"], meta["threshold"], meta["scale"]
        self._adaptations, self._accepted = meta["adaptations"], list(meta["accepted"])
        self._levels = list(meta["levels"])
        self._rngs = [_generator_from_state(s) for s in meta["rngs"]]
        return self


def subset_simulation(g: Callable[[np.ndarray], np.ndarray], n_dims: int, *, seed: int = 0,
                      **settings: Any) -> FailureProbability:
    """Subset simulation of a vectorised limit state (settings: :class:`SubsetSettings`)."""
    return SubsetSimulation(n_dims, seed, SubsetSettings(**settings)).run(g)
