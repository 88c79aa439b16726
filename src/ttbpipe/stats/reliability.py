"""Probability of exceeding a limit, its confidence interval, convergence and sample-size verdict.

For each limit and scenario the estimate is ``P(max index > limit)`` from the per-sample
extremes (``docs/reliability.md``):

* equal weights (plain Monte Carlo): :class:`BinomialExceedance`, ``p = k/N`` with the Wilson
  score or Clopper-Pearson interval of :func:`scipy.stats.binomtest`;
* unequal weights (TIPM representative samples): :class:`WeightedExceedance`,
  ``p = sum(w 1[x > limit]) / sum(w)`` with the same interval evaluated at an effective sample
  size (linearisation / Korn-Graubard by default, Kish's ``(sum w)^2 / sum w^2`` on request)
  and ``k_eff = p n_eff``.

:class:`SampleSizeCriterion` decides whether the samples sufficed. :func:`assess_limits` and
:func:`convergence_curve` apply all this to an extremes table.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd
from scipy import special, stats

from ..parallel import process_map
from ..reliability.tail import TailNotEstimable, TailSettings, estimate_tail, reliability_index
from .limits import (Limit, LimitContext, LimitNotEvaluable, applied_threshold_text,
                     limits_from_config)

log = logging.getLogger(__name__)

INTERVAL_METHODS = ("wilson", "clopper-pearson")

#: Default target per-passage exceedance probability: a one-year return period at 100 train
#: pairs a day, 1 / (100 x 365) = 2.74e-5 (docs/reliability.md §9).
DEFAULT_TARGET_PROBABILITY = 1.0 / (100 * 365)

#: Columns the tail estimate adds to the reliability table (docs/studies.md).
TAIL_COLUMNS = ("tail_model", "tail_probability", "tail_ci_low", "tail_ci_high", "tail_cov",
                "tail_reliability_index", "tail_n_evaluations", "tail_method",
                "tail_gof_statistic", "tail_gof_pvalue", "tail_gof_method", "tail_extrapolation",
                "tail_status")
#: Columns of the target verdict (see :func:`target_verdict`).
VERDICT_COLUMNS = ("reliability_index", "target_probability", "verdict_basis", "target_verdict",
                   "target_text")
#: Target verdicts in words.
MET, NOT_MET, NOT_SHOWN = "met", "not met", "not shown"


def probability_text(p: float) -> str:
    """A probability or bound as every page writes it: 3 significant digits, exponent below 1e-3."""
    if p == 0:
        return "0"
    return f"{p:.3g}" if p >= 1e-3 else f"{p:.2e}"


@dataclass(frozen=True)
class ExceedanceEstimate:
    """One exceedance probability with its two-sided confidence interval.

    ``upper_one_sided`` is the one-sided upper confidence bound at the same level (used for the
    zero-exceedance verdict); ``lower_one_sided`` the one-sided lower bound (all exceed).
    """

    n_samples: int
    n_exceed: int
    n_effective: float
    probability: float
    ci_low: float
    ci_high: float
    upper_one_sided: float
    lower_one_sided: float
    confidence_level: float
    method: str

    @property
    def half_width(self) -> float:
        return 0.5 * (self.ci_high - self.ci_low)


def _wilson(k: np.ndarray, n: np.ndarray, z: float) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval (Wilson 1927, JASA 22:209; Newcombe 1998 eq. 3), vectorised.

    Same formula and end conventions (lower 0 at k = 0, upper 1 at k = n) as
    ``scipy.stats.binomtest(...).proportion_ci(method='wilson')``, but valid for the non-integer
    k and n of an effective sample.
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        denom = 2.0 * (n + z * z)
        center = (2.0 * n * p + z * z) / denom
        delta = z / denom * np.sqrt(np.maximum(4.0 * n * p * (1.0 - p), 0.0) + z * z)
    low = np.where(k <= 0.0, 0.0, center - delta)
    high = np.where(k >= n, 1.0, center + delta)
    return low, high


def _clopper_pearson(k: np.ndarray, n: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """Clopper-Pearson interval from beta quantiles (Clopper & Pearson 1934), vectorised.

    ``[B(alpha; k, n-k+1), B(1-alpha; k+1, n-k)]`` with ``alpha`` the tail probability on each
    side; for non-integer k, n this is Korn & Graubard's (1998) effective-sample version.
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        low = np.where(k <= 0.0, 0.0, special.betaincinv(np.maximum(k, 1e-300), n - k + 1.0, alpha))
        high = np.where(k >= n, 1.0,
                        special.betaincinv(k + 1.0, np.maximum(n - k, 1e-300), 1.0 - alpha))
    return low, high


class _IntervalMixin:
    """Shared interval code: ``confidence_level`` and ``method`` are set by the subclasses."""

    confidence_level: float
    method: str

    def _check(self) -> None:
        if self.method not in INTERVAL_METHODS:
            raise ValueError(f"interval method must be one of {INTERVAL_METHODS}, got {self.method!r}")
        if not 0.0 < self.confidence_level < 1.0:
            raise ValueError(f"confidence_level must be in (0, 1), got {self.confidence_level}")

    def interval(self, k: Any, n: Any) -> tuple[np.ndarray, np.ndarray]:
        """Two-sided interval for k exceedances out of n (arrays; k, n may be non-integer)."""
        alpha = 1.0 - self.confidence_level
        if self.method == "wilson":
            return _wilson(k, n, float(stats.norm.ppf(1.0 - alpha / 2.0)))
        return _clopper_pearson(k, n, alpha / 2.0)

    def one_sided_bounds(self, k: Any, n: Any) -> tuple[np.ndarray, np.ndarray]:
        """One-sided (lower, upper) Clopper-Pearson bounds at ``confidence_level``.

        At k = 0 the upper bound is ``1 - (1 - c)^(1/n)``, about 3/n at c = 0.95 (the "rule of
        three", Hanley & Lippman-Hand 1983, JAMA 249:1743); used for the zero-exceedance verdict
        whichever two-sided method is chosen.
        """
        return _clopper_pearson(k, n, 1.0 - self.confidence_level)


class BinomialExceedance(_IntervalMixin):
    """Equal-weight estimator: ``p = k/N``, interval from :func:`scipy.stats.binomtest`.

    ``method``: ``'wilson'`` (score interval, Wilson 1927) or ``'clopper-pearson'`` (exact,
    Clopper & Pearson 1934; scipy's ``'exact'``).
    """

    def __init__(self, confidence_level: float = 0.95, method: str = "wilson") -> None:
        self.confidence_level = float(confidence_level)
        self.method = method
        self._check()

    def estimate(self, exceeded: np.ndarray) -> ExceedanceEstimate:
        exceeded = np.asarray(exceeded, dtype=bool)
        n = int(exceeded.size)
        if n == 0:
            raise ValueError("no samples: cannot estimate an exceedance probability")
        k = int(exceeded.sum())
        ci = stats.binomtest(k, n).proportion_ci(
            confidence_level=self.confidence_level,
            method="wilson" if self.method == "wilson" else "exact")
        lo1, hi1 = self.one_sided_bounds(k, n)
        return ExceedanceEstimate(n, k, float(n), k / n, float(ci.low), float(ci.high),
                                  float(hi1), float(lo1), self.confidence_level, self.method)

    def convergence(self, exceeded: np.ndarray) -> pd.DataFrame:
        """Estimate and interval after the first 1, 2, ..., N samples (in the given order)."""
        exceeded = np.asarray(exceeded, dtype=bool)
        n = np.arange(1, exceeded.size + 1, dtype=float)
        k = np.cumsum(exceeded, dtype=float)
        low, high = self.interval(k, n)
        lo1, hi1 = self.one_sided_bounds(k, n)
        return pd.DataFrame({"n_samples": n.astype(np.int64), "n_exceed": k.astype(np.int64),
                             "n_effective": n, "probability": k / n, "ci_low": low,
                             "ci_high": high, "upper_one_sided": hi1, "lower_one_sided": lo1})


class WeightedExceedance(_IntervalMixin):
    """Weighted estimator for probability-weighted (TIPM) samples.

    ``p = sum(w_i 1[x_i > limit]) / sum(w_i)`` (self-normalised: weights need not sum to 1). The
    interval is the Wilson or Clopper-Pearson interval evaluated at an effective sample size
    ``n_eff`` with ``k_eff = p n_eff`` (Korn & Graubard 1998, Survey Methodology 24:193):

    * ``effective_size='linearized'`` (default): ``n_eff = p(1-p) / v``, with ``v`` the
      linearisation (delta-method) variance of the ratio estimator,
      ``v = sum w_i^2 (1_i - p)^2 / (sum w)^2`` (Cochran 1977, *Sampling Techniques*, eq. 6.13).
      It accounts for weights correlated with exceedance, as TIPM and importance weights are.
      When no sample or every sample exceeds, ``v = 0`` and Kish's size is used instead;
    * ``effective_size='kish'``: ``n_eff = (sum w)^2 / sum w^2`` (Kish 1965, *Survey Sampling*,
      section 11.7), which ignores that correlation; measured coverage can then be far from
      nominal (docs/reliability.md).

    With equal weights both reduce exactly to :class:`BinomialExceedance`.
    """

    EFFECTIVE_SIZES = ("linearized", "kish")

    def __init__(self, confidence_level: float = 0.95, method: str = "wilson",
                 effective_size: str = "linearized") -> None:
        self.confidence_level = float(confidence_level)
        self.method = method
        if effective_size not in self.EFFECTIVE_SIZES:
            raise ValueError(f"effective_size must be one of {self.EFFECTIVE_SIZES}")
        self.effective_size = effective_size
        self._check()

    def _cumulative(self, exceeded: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, ...]:
        """Running (count, n_eff, p, k_eff) after 1, 2, ..., N samples."""
        exceeded = np.asarray(exceeded, dtype=bool)
        weights = np.asarray(weights, dtype=float)
        if weights.shape != exceeded.shape:
            raise ValueError(f"{weights.size} weights for {exceeded.size} samples")
        if not (np.isfinite(weights).all() and (weights > 0).all()):
            raise ValueError("weights must be finite and > 0")
        w = np.cumsum(weights)
        w2 = np.cumsum(weights * weights)
        wk = np.cumsum(np.where(exceeded, weights, 0.0))
        w2k = np.cumsum(np.where(exceeded, weights * weights, 0.0))
        p = np.clip(wk / w, 0.0, 1.0)
        kish = w * w / w2
        count = np.cumsum(exceeded)
        n = np.arange(1, count.size + 1)
        between = (count > 0) & (count < n)
        if self.effective_size == "linearized":
            # sum w^2 (1_i - p)^2 = (1 - 2p) sum_{exceeding} w^2 + p^2 sum w^2
            var = ((1.0 - 2.0 * p) * w2k + p * p * w2) / (w * w)
            n_eff = np.where(between & (var > 0),
                             p * (1.0 - p) / np.where(var > 0, var, 1.0), kish)
        else:
            n_eff = kish
        # Exact end cases: avoids k_eff = 0.9999999 n_eff by rounding.
        k_eff = np.where(count == 0, 0.0, np.where(count == n, n_eff, p * n_eff))
        return count, n_eff, p, k_eff

    def estimate(self, exceeded: np.ndarray, weights: np.ndarray) -> ExceedanceEstimate:
        if np.asarray(exceeded).size == 0:
            raise ValueError("no samples: cannot estimate an exceedance probability")
        count, n_eff, p, k_eff = (a[-1] for a in self._cumulative(exceeded, weights))
        low, high = self.interval(k_eff, n_eff)
        lo1, hi1 = self.one_sided_bounds(k_eff, n_eff)
        return ExceedanceEstimate(int(np.asarray(exceeded).size), int(count), float(n_eff),
                                  float(p), float(low), float(high), float(hi1), float(lo1),
                                  self.confidence_level, f"{self.method}, {self.effective_size} n_eff")

    def convergence(self, exceeded: np.ndarray, weights: np.ndarray) -> pd.DataFrame:
        """Estimate and interval after the first 1, 2, ..., N samples (in the given order)."""
        count, n_eff, p, k_eff = self._cumulative(exceeded, weights)
        low, high = self.interval(k_eff, n_eff)
        lo1, hi1 = self.one_sided_bounds(k_eff, n_eff)
        return pd.DataFrame({"n_samples": np.arange(1, count.size + 1, dtype=np.int64),
                             "n_exceed": count.astype(np.int64), "n_effective": n_eff,
                             "probability": p, "ci_low": low, "ci_high": high,
                             "upper_one_sided": hi1, "lower_one_sided": lo1})


def estimator_for(weights: np.ndarray, confidence_level: float = 0.95, method: str = "wilson",
                  effective_size: str = "linearized") -> BinomialExceedance | WeightedExceedance:
    """:class:`BinomialExceedance` when all weights are equal, else :class:`WeightedExceedance`."""
    weights = np.asarray(weights, dtype=float)
    if weights.size and np.allclose(weights, weights[0], rtol=1e-12, atol=0.0):
        return BinomialExceedance(confidence_level, method)
    return WeightedExceedance(confidence_level, method, effective_size)


def _estimate(estimator, exceeded, weights) -> ExceedanceEstimate:
    if isinstance(estimator, WeightedExceedance):
        return estimator.estimate(exceeded, weights)
    return estimator.estimate(exceeded)


@dataclass(frozen=True)
class SampleSizeCriterion:
    """Did the samples suffice? (``docs/reliability.md``)

    * some but not all samples exceed: sufficient when the two-sided interval's half-width is at
      most ``max(relative_half_width * p, absolute_half_width)``;
    * no sample exceeds: sufficient when the one-sided upper bound (Clopper-Pearson,
      ``1 - (1-c)^(1/n_eff)``, about 3/n at 95 %: the rule of three) is at most
      ``zero_exceedance_upper_bound``, i.e. the study shows ``P < bound`` at the confidence level;
    * every sample exceeds: sufficient when ``1 - lower one-sided bound`` is at most the same bound.
    """

    relative_half_width: float = 0.25
    absolute_half_width: float = 0.01
    zero_exceedance_upper_bound: float = 0.01

    def judge(self, est: ExceedanceEstimate) -> tuple[bool, str]:
        level = f"{100 * est.confidence_level:g} %"
        bound = self.zero_exceedance_upper_bound
        if est.n_exceed == 0:
            ok = est.upper_one_sided <= bound
            needed = _zero_exceedance_samples(est.confidence_level, bound)
            return ok, (f"no exceedance; P < {est.upper_one_sided:.3g} at {level} (one-sided); "
                        + ("sufficient" if ok else
                           f"needs upper bound <= {bound:g}, about {needed} effective samples"))
        if est.n_exceed == est.n_samples:
            ok = 1.0 - est.lower_one_sided <= self.zero_exceedance_upper_bound
            return ok, (f"every sample exceeds; P > {est.lower_one_sided:.3g} at {level} (one-sided); "
                        + ("sufficient" if ok else "more samples needed"))
        tolerance = max(self.relative_half_width * est.probability, self.absolute_half_width)
        ok = est.half_width <= tolerance
        return ok, (f"CI half-width {est.half_width:.3g} "
                    + ("<=" if ok else ">") + f" tolerance {tolerance:.3g}"
                    + ("" if ok else f"; about {_samples_needed(est, tolerance)} effective samples needed"))


def _zero_exceedance_samples(confidence_level: float, bound: float) -> int:
    """Smallest n with ``1 - (1-c)^(1/n) <= bound`` (exact one-sided Clopper-Pearson at k = 0)."""
    return int(np.ceil(np.log(1.0 - confidence_level) / np.log1p(-bound)))


def _samples_needed(est: ExceedanceEstimate, tolerance: float) -> int:
    """Normal-approximation size for half-width ``tolerance`` at the current estimate."""
    z = stats.norm.ppf(0.5 + 0.5 * est.confidence_level)
    p = est.probability
    return int(np.ceil(z * z * p * (1.0 - p) / tolerance ** 2))


@dataclass(frozen=True)
class ReliabilitySettings:
    """Confidence level, interval method, sample-size criterion, target probability per passage
    and tail model (``limits:`` in the config; ``limits.tail`` for :class:`TailSettings`)."""

    confidence_level: float = 0.95
    method: str = "wilson"
    effective_size: str = "linearized"
    criterion: SampleSizeCriterion = SampleSizeCriterion()
    target_probability: float = DEFAULT_TARGET_PROBABILITY
    tail: TailSettings = TailSettings()

    def __post_init__(self) -> None:
        if not 0.0 < self.target_probability < 1.0:
            raise ValueError(f"target_probability must be in (0, 1), got {self.target_probability}")

    @classmethod
    def from_config(cls, section: Mapping[str, Any] | None) -> "ReliabilitySettings":
        section = dict(section or {})
        crit = dict(section.get("sufficiency") or {})
        level = float(section.get("confidence_level", 0.95))
        return cls(confidence_level=level,
                   method=section.get("interval", "wilson"),
                   effective_size=section.get("effective_size", "linearized"),
                   criterion=SampleSizeCriterion(**crit),
                   target_probability=float(section.get("target_probability",
                                                        DEFAULT_TARGET_PROBABILITY)),
                   tail=TailSettings.from_config(section.get("tail"), confidence_level=level))


#: How the pages name each tail model.
TAIL_MODEL_NAMES = {"gev": "GEV", "pot": "POT", "gumbel": "Gumbel"}


def tail_columns(values: np.ndarray, thresholds: np.ndarray, weights: np.ndarray,
                 settings: TailSettings, category: str = "limit") -> dict[str, Any]:
    """The :data:`TAIL_COLUMNS` of one (scenario, limit): the tail model of the raw index when
    the threshold is the same for every sample, else of the utilisation index / threshold
    (exceedance at 1); a ``tail_status`` saying why when no estimate is given."""
    empty = dict.fromkeys(TAIL_COLUMNS, np.nan)
    empty["tail_extrapolation"] = False
    if category == "grade":
        return {**empty, "tail_status": "not estimated: grade boundary, not a limit"}
    thresholds = np.broadcast_to(np.asarray(thresholds, dtype=float), np.shape(values))
    constant = bool(np.all(thresholds == thresholds.flat[0]))
    if constant:
        x, z, of = values, float(thresholds.flat[0]), "of the raw index"
    else:
        if not (thresholds > 0).all():
            return {**empty, "tail_status": "not estimated: per-sample thresholds not all > 0"}
        x, z, of = values / thresholds, 1.0, "of index / per-sample threshold"
    try:
        est = estimate_tail(x, z, weights, settings)
    except TailNotEstimable as exc:
        return {**empty, "tail_status": f"no tail estimate: {exc}"}
    return {"tail_model": TAIL_MODEL_NAMES[est.model], "tail_probability": est.probability, "tail_ci_low": est.ci_low,
            "tail_ci_high": est.ci_high, "tail_cov": est.cov,
            "tail_reliability_index": est.reliability_index,
            "tail_n_evaluations": est.n_evaluations, "tail_method": f"{est.method}, {of}",
            "tail_gof_statistic": est.gof_statistic, "tail_gof_pvalue": est.gof_pvalue,
            "tail_gof_method": est.gof_method, "tail_extrapolation": est.extrapolation,
            "tail_status": est.status}


def interval_verdict(p: float, lo: float, hi: float, target: float, how: str) -> tuple[str, str]:
    """(verdict, sentence) of an estimate ``p [lo, hi]`` against a target probability: **met**
    when the interval's upper end is below the target, **not met** when its lower end is above
    it, else **not shown**. ``how`` names the method and the runs, e.g. "GEV tail, 300 runs"."""
    stated = (f"P < {probability_text(hi)}" if p == 0.0 and lo == 0.0 else
              f"P = {probability_text(p)} [{probability_text(lo)}, {probability_text(hi)}]")
    t = probability_text(target)
    if hi < target:
        return MET, f"{MET}: {stated} < target {t} ({how})"
    if lo > target:
        return NOT_MET, (f"{NOT_MET}: the interval's lower end {probability_text(lo)} "
                         f"exceeds the target {t}; {stated} ({how})")
    return NOT_SHOWN, (f"{NOT_SHOWN}: the interval's upper end {probability_text(hi)} "
                       f"exceeds the target {t}; {stated} ({how})")


def target_verdict(row: Mapping[str, Any], target: float) -> dict[str, Any]:
    """Target verdict of one reliability row (the :data:`VERDICT_COLUMNS`).

    The estimate stated and judged is the counting one when at least one sample exceeds (model
    free), else the tail estimate when there is one (counting at k = 0 only bounds P). The
    target is **met** when the interval's upper end is below it, **not met** when its lower end
    is above it, else **not shown** (the interval straddles the target).
    """
    k = int(row["n_exceed"])
    n = int(row["n_samples"])
    tail_ok = np.isfinite(row.get("tail_probability", np.nan))
    basis = "tail" if (k == 0 and tail_ok) else "counting"
    if basis == "tail":
        p, lo, hi = row["tail_probability"], row["tail_ci_low"], row["tail_ci_high"]
        how = f"{row['tail_model']} tail, {n} runs"
    else:
        p, lo, hi = row["probability"], row["ci_low"], row["ci_high"]
        how = f"counting, {k} of {n} runs exceed"
    verdict, text = interval_verdict(p, lo, hi, target, how)
    if basis == "counting" and k == 0:
        text += f"; {row.get('tail_status', 'no tail estimate')}"
    if basis == "tail" and row.get("tail_extrapolation"):
        text += "; extrapolated far beyond the data: rests on the fitted tail shape"
    return {"reliability_index": reliability_index(row["probability"]),
            "target_probability": target, "verdict_basis": basis, "target_verdict": verdict,
            "target_text": text}


def _ordered(df: pd.DataFrame) -> pd.DataFrame:
    return df.sort_values("sample_index", kind="stable").reset_index(drop=True)


def _tail_task(args: tuple) -> dict[str, Any]:
    """:func:`tail_columns` of ``(values, thresholds, weights, settings, category)``: a worker's
    task (each fit is seeded by its settings alone, so the result does not depend on the number
    of workers or the order of the fits)."""
    return tail_columns(*args)


def assess_limits(extremes: pd.DataFrame, limits: Iterable[Limit],
                  context: LimitContext = LimitContext(),
                  settings: ReliabilitySettings = ReliabilitySettings(),
                  workers: int = 1) -> pd.DataFrame:
    """Exceedance probability, interval and verdict for every (scenario, limit).

    Limits whose column is absent, or that need an input nobody gives, appear with
    ``status`` 'not evaluated: ...' (and a logged warning) instead of being dropped. Every
    evaluated row also carries the tail estimate (:data:`TAIL_COLUMNS`, :func:`tail_columns`;
    skipped for grades), the reliability index of the counting estimate and the target verdict
    (:data:`VERDICT_COLUMNS`, :func:`target_verdict`). ``workers``: processes for the tail
    fits (the results do not depend on it).
    """
    rows = []
    tail_tasks: list[tuple] = []
    tail_of: list[int] = []
    for scenario, block in extremes.groupby("scenario", sort=True):
        block = _ordered(block)
        weights = block["weight"].to_numpy(dtype=float)
        estimator = estimator_for(weights, settings.confidence_level, settings.method,
                                  settings.effective_size)
        for limit in limits:
            base = {"scenario": scenario, "limit": limit.name, "column": limit.column,
                    "threshold": limit.threshold_text(), "rule": limit.threshold_text(),
                    "category": limit.category, "source": limit.source,
                    "description": limit.description}
            if limit.column not in block.columns:
                reason = f"not evaluated: column {limit.column} absent from the results"
                log.warning("scenario %s, limit %s: %s", scenario, limit.name, reason)
                rows.append({**base, "status": reason})
                continue
            try:
                thresholds = limit.thresholds(block, context)
            except LimitNotEvaluable as exc:
                log.warning("scenario %s: %s", scenario, exc)
                rows.append({**base, "status": f"not evaluated: {exc}"})
                continue
            base["threshold"] = applied_threshold_text(limit, thresholds)
            values = block[limit.column].to_numpy(dtype=float)
            exceeded = values > thresholds
            est = _estimate(estimator, exceeded, weights)
            ok, reason = settings.criterion.judge(est)
            tail_of.append(len(rows))
            tail_tasks.append((values, thresholds, weights, settings.tail, limit.category))
            rows.append({**base, **asdict(est), "half_width": est.half_width,
                         "weighted": isinstance(estimator, WeightedExceedance),
                         "sufficient": ok, "status": reason})
    for i, tail in zip(tail_of, process_map(_tail_task, tail_tasks, workers)):
        row = {**rows[i], **tail}
        rows[i] = {**row, **target_verdict(row, settings.target_probability)}
    return pd.DataFrame(rows)


def convergence_curve(extremes: pd.DataFrame, limit: Limit, context: LimitContext = LimitContext(),
                      settings: ReliabilitySettings = ReliabilitySettings(),
                      scenario: str | None = None) -> pd.DataFrame:
    """Estimate and interval against the number of samples, in sample-index order.

    Sample-index order makes the curve reproducible whatever the batching. One scenario (the
    only one when ``scenario`` is None). Columns as :meth:`BinomialExceedance.convergence` plus
    ``sample_index`` and ``sufficient``.
    """
    if scenario is None:
        scenarios = extremes["scenario"].unique()
        if len(scenarios) != 1:
            raise ValueError(f"several scenarios {list(scenarios)}: pass scenario=")
        scenario = scenarios[0]
    block = _ordered(extremes[extremes["scenario"] == scenario])
    if block.empty:
        raise ValueError(f"no samples for scenario {scenario!r}")
    weights = block["weight"].to_numpy(dtype=float)
    exceeded = block[limit.column].to_numpy(dtype=float) > limit.thresholds(block, context)
    estimator = estimator_for(weights, settings.confidence_level, settings.method,
                                  settings.effective_size)
    curve = (estimator.convergence(exceeded, weights)
             if isinstance(estimator, WeightedExceedance) else estimator.convergence(exceeded))
    curve.insert(1, "sample_index", block["sample_index"].to_numpy())
    crit = settings.criterion
    half = 0.5 * (curve["ci_high"] - curve["ci_low"])
    tol = np.maximum(crit.relative_half_width * curve["probability"], crit.absolute_half_width)
    zero = curve["n_exceed"] == 0
    full = curve["n_exceed"] == curve["n_samples"]
    curve["sufficient"] = np.where(
        zero, curve["upper_one_sided"] <= crit.zero_exceedance_upper_bound,
        np.where(full, 1.0 - curve["lower_one_sided"] <= crit.zero_exceedance_upper_bound,
                 half <= tol))
    curve.attrs.update(scenario=scenario, limit=limit.name, column=limit.column,
                       description=limit.description,
                       threshold=applied_threshold_text(limit, limit.thresholds(block, context)),
                       method=settings.method,
                       confidence_level=settings.confidence_level)
    return curve


def assess_from_config(extremes: pd.DataFrame, limits_section: Mapping[str, Any] | None) -> pd.DataFrame:
    """:func:`assess_limits` with limits and settings from the ``limits:`` config section."""
    limits, context = limits_from_config(limits_section)
    return assess_limits(extremes, limits, context, ReliabilitySettings.from_config(limits_section))
