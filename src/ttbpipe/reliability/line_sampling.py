"""Line sampling along an important direction found by a short subset simulation.

Method (Koutsourelakis, Pradlwarter & Schueller 2004, Probab. Eng. Mech. 19:409; Schueller,
Pradlwarter & Koutsourelakis 2004, Probab. Eng. Mech. 19:463). With a unit *important
direction* alpha pointing from the origin towards the failure domain, every standard-normal
point splits into ``u = u_perp + c alpha``. For each of ``n_lines`` independent points
``u_perp,i`` (a standard normal projected onto the hyperplane orthogonal to alpha) the line
``u_perp,i + c alpha`` crosses the limit state at ``c_i`` (a root of ``g``), and
``p_i = Phi(-c_i)`` is the exact failure probability *along that line* when the line fails
beyond ``c_i`` only. ``P = mean(p_i)`` is then unbiased for any alpha (the lines are independent
and alpha is fixed before they are drawn); its variance ``var(p_i) / n_lines`` vanishes for a
linear limit state with alpha its normal and stays small when alpha is close to the direction
of the design point. A line without a root in ``[-c_max, c_max]`` contributes 0 (safe) or
``Phi(c_max)`` (failed throughout); both are counted in ``details``.

Scope: one dominant failure direction (a component-like limit state, smooth and roughly
planar near the design point). A failure domain that is a union of many half-spaces in
different directions (a series system; the maximum of a response over time or over many
locations, as the coupled model's indices are) is missed by any single direction: most lines
never cross it and the estimate is far too low with a confident-looking interval (measured:
a 20-component series system at P = 6.3e-4 gave 1e-5 to 1e-13; the coupled model's maximum
wheel unloading ratio at P ~ 1e-3 gave 2.5e-9, docs/reliability.md section 12). So the
estimator stops with that diagnosis when more than ``max_missing_fraction`` of the estimating
lines do not cross within ``c_max``; subset simulation is the method for those limit states.

Important direction (``direction="subset"``, the default): a short subset simulation
(``direction_levels`` levels of ``direction_n_per_level`` points) walks towards the failure
domain; the least-squares plane through every point it evaluated (ridge regression with the
penalty from generalised cross-validation) gives the first direction, its steepest descent.
``direction_lines`` lines along it add points at and around the limit state, the plane is
fitted again through all points so far, and its direction is the one the estimating lines use.
The linear-regression direction replaces the conditional mean of the Markov-chain states that
Koutsourelakis et al. (2004, section 4) propose, which was measured too noisy in hundreds of
dimensions (:func:`important_direction`). Or an array given by the caller (a design point from
FORM, engineering insight; no refinement). Every evaluation is counted in ``n_evaluations``;
the estimating lines are drawn after the direction is fixed, so (for lines that cross once)
the estimate is unbiased whatever the direction's error, which shows only in the c.o.v.

Root search: per line, a bracketed secant iteration (the Illinois variant of regula falsi,
Dowell & Jarratt 1971, BIT 11:168) from ``c = c_start`` and ``c_start + 1``, where
``c_start`` is the reliability index of the subset simulation's deepest event (for the
estimating lines: the refinement lines' median crossing; 3 for a given direction), expanded by
steps of 1.5 until the sign changes; all open lines are evaluated together, so that each iteration is
one vectorised call of ``g`` (one batch of coupled runs). Stops at ``|dc| < root_tolerance``.

C.o.v. and interval: ``cov = std(p_i) / (sqrt(n_lines) P)``, the interval lognormal with that
c.o.v. (:func:`ttbpipe.reliability.result.lognormal_interval`), as for subset simulation.

Determinism: line i is drawn from ``SeedSequence([seed, RARE_EVENT, RARE_EVENT_LINE, i])``
(ttbpipe.streams); the direction's subset simulation from its own stream with the same seed.

Why not a library: UQpy (4.x) and OpenTURNS ship subset simulation and (OpenTURNS) directional
sampling, but neither fits the important direction through subset simulation's evaluated
points nor stops on a failure domain that no single direction reaches; the estimator itself is
the mean of Phi(-c_i) over vectorised root searches (docs/reliability.md section 12).
"""

from __future__ import annotations

import logging
from typing import Any, Callable

import numpy as np
from scipy import stats

from .. import streams
from .monte_carlo import evaluate_limit_state, indexed_points
from .result import FailureProbability, lognormal_interval
from .subset import SubsetSettings, SubsetSimulation

__all__ = ["line_sampling", "important_direction", "line_points"]

log = logging.getLogger(__name__)


def line_points(seed: int, n_dims: int, indices: np.ndarray) -> np.ndarray:
    """Standard-normal points of the lines with the given indices, shape (len, n_dims)."""
    return indexed_points(seed, streams.RARE_EVENT_LINE, n_dims, indices)


class _Recorded:
    """``g`` (checked by :func:`evaluate_limit_state`) keeping every point it evaluated and its
    value, for the direction's regression."""

    def __init__(self, g: Callable[[np.ndarray], np.ndarray], what: str) -> None:
        self.g, self.what = g, what
        self.points: list[np.ndarray] = []
        self.values: list[np.ndarray] = []

    def __call__(self, points: np.ndarray) -> np.ndarray:
        values = evaluate_limit_state(self.g, points, self.what)
        self.points.append(np.array(points, dtype=float, copy=True))
        self.values.append(values.copy())
        return values

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        return np.concatenate(self.points), np.concatenate(self.values)


def _regression_gradient(points: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Slope b of the least-squares plane ``g ~ b0 + b . u`` through the evaluated points.

    Ridge regression on the centred data with the penalty chosen by generalised
    cross-validation (Golub, Heath & Wahba 1979, Technometrics 21:215), computed from one SVD:
    with more points than dimensions and a nearly linear g the penalty goes to ~0 (ordinary
    least squares); with fewer (a coupled model of thousands of inputs) it keeps the slope
    defined."""
    x = points - points.mean(axis=0)
    y = values - values.mean()
    u_, s_, vt = np.linalg.svd(x, full_matrices=False)
    uty = u_.T @ y
    n = x.shape[0]
    resid0 = float(y @ y - uty @ uty)           # the part of y outside the column space
    best = None
    for lam in np.concatenate([[0.0], np.logspace(-8, 2, 41) * float(s_[0] ** 2)]):
        shrink = s_ ** 2 / (s_ ** 2 + lam) if lam > 0.0 else (s_ > 1e-12 * s_[0]).astype(float)
        resid = resid0 + float(np.sum(((1.0 - shrink) * uty) ** 2))
        dof = float(shrink.sum())
        if n - dof <= 0.5:
            continue
        gcv = n * resid / (n - dof) ** 2
        if best is None or gcv < best[0]:
            best = (gcv, shrink)
    if best is None:
        raise RuntimeError("line sampling: too few points to fit the direction")
    _, shrink = best
    with np.errstate(divide="ignore", invalid="ignore"):
        coef = np.where(s_ > 1e-12 * s_[0], shrink * uty / s_, 0.0)
    return vt.T @ coef


def important_direction(g: Callable[[np.ndarray], np.ndarray], n_dims: int, seed: int,
                        n_per_level: int, levels: int
                        ) -> tuple[np.ndarray, float, int, dict, np.ndarray, np.ndarray]:
    """Unit direction towards failure from a short subset simulation: (alpha, the reliability
    index of its last level's event, evaluations spent, its levels table as a dict, every
    evaluated point and its g value).

    The subset simulation stops after ``levels`` levels or when it reaches failure. alpha is
    the direction of steepest descent of the least-squares plane through *every* point it
    evaluated (accepted or not: :func:`_regression_gradient`), turned to the side of its
    deepest states. The normalised mean of the deepest states alone (Koutsourelakis et al.
    2004) was measured too noisy in hundreds of dimensions: the chains of a level share few
    lineages, so their mean carries about sqrt(n_dims / 20) of noise beside a signal of 3
    (cosine 0.73 to the true normal of a linear limit state in 200 dimensions, line-sampling
    estimates 0.43 of the exact value on average over 20 seeds; docs/reliability.md section 12)."""
    recording = _Recorded(g, "line sampling, direction search")
    sus = SubsetSimulation(n_dims, seed, SubsetSettings(n_per_level=n_per_level,
                                                        max_levels=int(levels)))
    sus.run(recording)
    states, values = sus.last_level()
    table = sus.levels_table()
    # the deepest event the states were drawn in has probability p0^m (all levels but the
    # last); its reliability index starts the root search
    p_region = float(np.prod(table["conditional_probability"].iloc[:-1]))
    points, g_values = recording.arrays()
    alpha = _fitted_direction(points, g_values, states.mean(axis=0))
    return alpha, float(stats.norm.isf(p_region)), int(sus.n_evaluations), \
        {"levels": table, "g_min": float(values.min())}, points, g_values


def _fitted_direction(points: np.ndarray, values: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """Unit steepest-descent direction of the fitted plane, on the side of ``towards``."""
    slope = _regression_gradient(points, values)
    norm = float(np.linalg.norm(slope))
    if not norm > 0.0:
        raise RuntimeError("line sampling: the limit state has no mean slope over the evaluated "
                           "points, so there is no important direction (a limit state symmetric "
                           "about the origin, e.g. a sphere): use method='subset'")
    alpha = -slope / norm
    return -alpha if float(towards @ alpha) < 0.0 else alpha


def _roots(g: Callable[[np.ndarray], np.ndarray], base: np.ndarray, alpha: np.ndarray,
           c_start: float, c_max: float, tolerance: float, max_iterations: int
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """Crossings ``c`` of ``g(base_i + c alpha) = 0`` for every line at once.

    Returns (c, status, evaluations): status 0 a root, +1 no failure up to ``c_max`` (c = inf),
    -1 failed down to ``-c_max`` (c = -inf), 2 a root with the line failing towards the origin
    (against the method's assumption; reported)."""
    n = base.shape[0]
    evaluations = 0

    def evaluate(rows: np.ndarray, c: np.ndarray, what: str) -> np.ndarray:
        nonlocal evaluations
        evaluations += rows.size
        return evaluate_limit_state(g, base[rows] + c[:, None] * alpha[None, :], what)

    rows = np.arange(n)
    lo_c = np.full(n, float(c_start))
    lo_g = evaluate(rows, lo_c, "line sampling, first point of each line")
    hi_c = lo_c + 1.0
    hi_g = evaluate(rows, hi_c, "line sampling, second point of each line")
    status = np.zeros(n, dtype=int)
    # bracket: failure (g <= 0) beyond the root; step outwards by 1.5 until the sign changes
    step = 0
    while True:
        up = (lo_g > 0.0) & (hi_g > 0.0) & (status == 0)       # both safe: go further out
        down = (lo_g <= 0.0) & (hi_g <= 0.0) & (status == 0)   # both failed: come back in
        status[up & (hi_c >= c_max)] = 1
        status[down & (lo_c <= -c_max)] = -1
        up &= status == 0
        down &= status == 0
        if not (up.any() or down.any()):
            break
        step += 1
        if step > 4 * int(np.ceil(2.0 * c_max / 1.5)):
            raise RuntimeError("line sampling: bracketing did not terminate")
        r = np.flatnonzero(up)
        if r.size:
            new_c = np.minimum(hi_c[r] + 1.5, c_max)
            new_g = evaluate(r, new_c, "line sampling, bracketing outwards")
            lo_c[r], lo_g[r] = hi_c[r], hi_g[r]
            hi_c[r], hi_g[r] = new_c, new_g
        r = np.flatnonzero(down)
        if r.size:
            new_c = np.maximum(lo_c[r] - 1.5, -c_max)
            new_g = evaluate(r, new_c, "line sampling, bracketing inwards")
            hi_c[r], hi_g[r] = lo_c[r], lo_g[r]
            lo_c[r], lo_g[r] = new_c, new_g
    # Illinois regula falsi inside [lo, hi]: g(lo) > 0 >= g(hi) with lo < hi (failure beyond
    # the crossing); a line failed at lo and safe at hi fails towards the origin, against the
    # method's assumption: counted (status 2), its crossing still found
    reversed_ = (status == 0) & (lo_g <= 0.0) & (hi_g > 0.0)
    c = np.where(status == 1, np.inf, np.where(status == -1, -np.inf, np.nan))
    open_rows = np.flatnonzero(status == 0)
    side = np.zeros(n, dtype=int)            # which end the last trial replaced (Illinois)
    last = np.full(n, np.nan)
    for _ in range(int(max_iterations)):
        if open_rows.size == 0:
            break
        r = open_rows
        trial = hi_c[r] - hi_g[r] * (hi_c[r] - lo_c[r]) / (hi_g[r] - lo_g[r])
        trial = np.clip(trial, lo_c[r], hi_c[r])
        done = np.abs(trial - last[r]) < tolerance
        c[r[done]] = trial[done]
        r, trial = r[~done], trial[~done]
        if r.size == 0:
            open_rows = r
            break
        last[r] = trial
        value = evaluate(r, trial, "line sampling, root search")
        exact = value == 0.0
        c[r[exact]] = trial[exact]
        # replace the end of the same sign as the trial (sign taken relative to lo's); when
        # the same end is replaced twice running, halve the other end's g (Illinois)
        same_as_lo = (np.sign(value) == np.sign(lo_g[r])) & ~exact
        rl = r[same_as_lo]
        lo_c[rl], lo_g[rl] = trial[same_as_lo], value[same_as_lo]
        hi_g[rl[side[rl] == 1]] *= 0.5
        side[rl] = 1
        same_as_hi = ~same_as_lo & ~exact
        rh = r[same_as_hi]
        hi_c[rh], hi_g[rh] = trial[same_as_hi], value[same_as_hi]
        lo_g[rh[side[rh] == -1]] *= 0.5
        side[rh] = -1
        open_rows = r[~exact]
    status[reversed_] = 2
    if open_rows.size:
        log.warning("line sampling: %d of %d lines not converged to %.1e after %d iterations; "
                    "their last bracket midpoint is used", open_rows.size, n, tolerance,
                    max_iterations)
        c[open_rows] = 0.5 * (lo_c[open_rows] + hi_c[open_rows])
    return c, status, evaluations


def _start(c_start: float, c_max: float) -> float:
    """The root search's first point, kept a step inside [-c_max, c_max]."""
    return float(np.clip(c_start, -c_max + 1.0, c_max - 1.0))


def line_sampling(g: Callable[[np.ndarray], np.ndarray], n_dims: int, *, seed: int = 0,
                  n_lines: int = 200, direction: Any = "subset",
                  direction_n_per_level: int = 500, direction_levels: int = 4,
                  direction_lines: int = 100,
                  c_max: float = 10.0, root_tolerance: float = 1.0e-3,
                  max_iterations: int = 30, confidence_level: float = 0.95,
                  max_missing_fraction: float = 0.1) -> FailureProbability:
    """Line sampling of ``P(g(U) <= 0)``; see the module docstring for the method.

    ``direction``: ``"subset"`` (found by a subset simulation of ``direction_levels`` levels of
    ``direction_n_per_level`` points, then refined with ``direction_lines`` lines) or an array
    of ``n_dims`` (normalised here; no refinement)."""
    n_dims, n_lines = int(n_dims), int(n_lines)
    if n_lines < 2:
        raise ValueError(f"n_lines must be >= 2, got {n_lines}")
    if not c_max > 0.0 or not root_tolerance > 0.0:
        raise ValueError("c_max and root_tolerance must be > 0")
    spent = 0
    info: dict[str, Any] = {}
    first = 0                                   # index of the first estimating line
    if isinstance(direction, str):
        if direction != "subset":
            raise ValueError(f"direction must be 'subset' or an array, got {direction!r}")
        alpha, c_start, spent, info, seen_u, seen_g = important_direction(
            g, n_dims, seed, int(direction_n_per_level), int(direction_levels))
        first = max(0, int(direction_lines))
        if first:
            # refinement: lines along the first direction add points near the limit state
            # (their crossings bracketed from both sides); the plane is fitted again through
            # every point so far. Lines 0 .. first-1 serve the direction only.
            recording = _Recorded(g, "line sampling, direction lines")
            z = line_points(seed, n_dims, np.arange(first))
            c_pilot, _, used = _roots(recording, z - np.outer(z @ alpha, alpha), alpha,
                                      _start(c_start, c_max), float(c_max),
                                      float(root_tolerance), int(max_iterations))
            spent += used
            pilot_u, pilot_g = recording.arrays()
            seen_u, seen_g = np.concatenate([seen_u, pilot_u]), np.concatenate([seen_g, pilot_g])
            alpha = _fitted_direction(seen_u, seen_g, alpha)
            finite = np.isfinite(c_pilot)
            if finite.any():
                c_start = float(np.median(c_pilot[finite]))
        if seen_u.shape[0] < 2 * n_dims:
            log.warning("line sampling: the direction is fitted through %d points in %d "
                        "dimensions; for a curved limit state it may be poor and the interval "
                        "may under-cover (docs/reliability.md section 12): raise "
                        "direction_n_per_level or direction_lines, or give a direction",
                        seen_u.shape[0], n_dims)
        source = (f"direction from a {int(direction_levels)}-level subset simulation "
                  f"(N = {int(direction_n_per_level)}) refined by {first} lines")
    else:
        alpha = np.asarray(direction, dtype=float).reshape(-1)
        if alpha.size != n_dims or not np.all(np.isfinite(alpha)) or \
                not np.linalg.norm(alpha) > 0.0:
            raise ValueError(f"direction must be a finite, non-zero array of {n_dims} values")
        alpha = alpha / np.linalg.norm(alpha)
        c_start, source = 3.0, "direction given"
    z = line_points(seed, n_dims, np.arange(first, first + n_lines))
    base = z - np.outer(z @ alpha, alpha)
    c, status, evaluations = _roots(g, base, alpha, _start(c_start, c_max), float(c_max),
                                    float(root_tolerance), int(max_iterations))
    reversed_lines = status == 2
    if reversed_lines.any():
        log.warning("line sampling: %d of %d lines fail towards the origin and are safe beyond "
                    "their crossing (counted as Phi(c) each); an important direction should "
                    "not give such lines: check it", int(reversed_lines.sum()), n_lines)
    missing = int(np.count_nonzero(status == 1))
    if missing > max_missing_fraction * n_lines:
        raise RuntimeError(
            f"line sampling: {missing} of {n_lines} lines do not reach the failure domain within "
            f"c = {c_max:g} along the important direction, so the failure domain does not lie in "
            "one direction (a maximum over time or over many locations fails in many directions "
            "at once) or P < Phi(-c_max). The estimate would be far too low: use "
            "method='subset' (or raise c_max if P may truly be that small)")
    p_line = np.where(reversed_lines, stats.norm.cdf(c), stats.norm.sf(c))  # inf->0, -inf->1
    probability = float(p_line.mean())
    if probability > 0.0:
        cov = float(p_line.std(ddof=1) / (np.sqrt(n_lines) * probability))
    else:
        cov = float("inf")
    low, high = lognormal_interval(probability, cov, confidence_level)
    if probability == 0.0:
        high = float(stats.norm.sf(c_max))
    method = (f"line sampling (Koutsourelakis et al. 2004), {n_lines} lines, {source}, "
              "lognormal interval with the lines' c.o.v.")
    details = {"direction": alpha, "line_probabilities": p_line, "crossings": c,
               "n_no_crossing_safe": int(np.count_nonzero(status == 1)),
               "n_no_crossing_failed": int(np.count_nonzero(status == -1)),
               "n_reversed": int(np.count_nonzero(status == 2)),
               "n_direction_evaluations": spent, "n_line_evaluations": evaluations,
               "seed": int(seed), **info}
    return FailureProbability(probability, low, high, cov, spent + evaluations, method,
                              confidence_level, details)
