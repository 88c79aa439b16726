"""Streaming reductions of per-batch result files, memory independent of the number of samples.

* :func:`read_extremes` concatenates the per-sample extremes of all batches (one row per sample:
  small) after validating each file.
* :func:`aggregate_histories` computes, per scenario and quantity, the weighted mean, standard
  deviation and percentiles against time or position from long-format time-history files,
  reading **one batch file at a time**. Its state is :class:`WeightedMoments` (five arrays of the
  grid length) and :class:`HistogramQuantiles` (``n_points x n_bins``); neither depends on the
  number of samples. :func:`statistics_frame` turns its result into one long table.

Tables over the reduced results (Table 1, forecast envelopes): :mod:`ttbpipe.stats.tables`.

Percentile accuracy: each grid point gets ``n_bins`` equal bins between the smallest and largest
value seen there (first pass); a percentile is read from the weighted cumulative histogram by
linear interpolation inside the bin where the cumulative weight crosses ``q`` (second pass).
The exact weighted inverted-CDF percentile lies in the same bin, so the error is at most one bin
width ``(max - min) / n_bins`` at that point (returned as ``bin_width``).
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from .schema import (ResultsSchemaError, history_abscissa, history_quantities, read_validated,
                     sample_starts, validate_extremes)

log = logging.getLogger(__name__)

STD_KINDS = ("reliability", "population")


# --- per-sample extremes --------------------------------------------------------------------

def read_extremes(paths: Iterable[str | os.PathLike[str]]) -> pd.DataFrame:
    """Validate and concatenate per-batch extremes tables, sorted by (scenario, sample_index).

    A (scenario, sample_index) pair found in two files is an error naming both files.
    """
    frames, origin = [], {}
    for path in sorted(Path(p) for p in paths):
        df = read_validated(path, "extremes")
        for key in zip(df["scenario"], df["sample_index"]):
            if key in origin:
                raise ResultsSchemaError(
                    f"{path}: column 'sample_index': sample {key[1]} of scenario {key[0]!r} is "
                    f"also in {origin[key]}")
            origin[key] = path
        frames.append(df)
    if not frames:
        raise ResultsSchemaError("no extremes files given")
    table = pd.concat(frames, ignore_index=True)
    table = table.sort_values(["scenario", "sample_index"], kind="stable").reset_index(drop=True)
    return validate_extremes(table, "concatenated extremes")


# --- streaming weighted moments ---------------------------------------------------------------

@dataclass
class WeightedMoments:
    """Streaming weighted mean and variance per grid point.

    Each batch's weighted mean and centred sum of squares are merged into the running state with
    the pairwise update of Chan, Golub & LeVeque (1979, 1983) in West's (1979, CACM 22:532)
    weighted form: with ``W = Wa + Wb`` and ``d = mean_b - mean_a``,
    ``mean = mean_a + d Wb / W`` and ``M2 = M2a + M2b + d^2 Wa Wb / W``. Also keeps
    ``sum w^2`` (for the reliability-weight variance and Kish's effective size), the sample count
    and the per-point minimum and maximum.
    """

    n_points: int
    count: int = 0
    total_weight: float = 0.0
    total_weight_sq: float = 0.0
    mean: np.ndarray = field(default=None)  # type: ignore[assignment]
    m2: np.ndarray = field(default=None)  # type: ignore[assignment]
    minimum: np.ndarray = field(default=None)  # type: ignore[assignment]
    maximum: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.mean = np.zeros(self.n_points)
        self.m2 = np.zeros(self.n_points)
        self.minimum = np.full(self.n_points, np.inf)
        self.maximum = np.full(self.n_points, -np.inf)

    def update(self, values: np.ndarray, weights: np.ndarray) -> None:
        """Add a batch: ``values`` (n_samples, n_points), ``weights`` (n_samples,) > 0."""
        values = np.asarray(values, dtype=float)
        weights = np.asarray(weights, dtype=float)
        if values.ndim != 2 or values.shape[1] != self.n_points or weights.shape != values.shape[:1]:
            raise ValueError(f"batch of shape {values.shape} with {weights.shape} weights does not "
                             f"fit {self.n_points} grid points")
        if values.shape[0] == 0:
            return
        wb = float(weights.sum())
        mean_b = weights @ values / wb
        m2_b = weights @ (values - mean_b) ** 2
        wa = self.total_weight
        total = wa + wb
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (wb / total)
        self.m2 = self.m2 + m2_b + delta * delta * (wa * wb / total)
        self.total_weight = total
        self.total_weight_sq += float(weights @ weights)
        self.count += values.shape[0]
        np.minimum(self.minimum, values.min(axis=0), out=self.minimum)
        np.maximum(self.maximum, values.max(axis=0), out=self.maximum)

    @property
    def n_effective(self) -> float:
        """Kish's effective sample size ``(sum w)^2 / sum w^2`` (Kish 1965)."""
        return self.total_weight ** 2 / self.total_weight_sq if self.total_weight_sq else 0.0

    def variance(self, kind: str = "reliability") -> np.ndarray:
        """Weighted variance per point.

        ``'reliability'``: ``M2 / (W - sum w^2 / W)``, unbiased for independent samples with
        reliability weights; equals numpy's ``ddof=1`` variance for equal weights.
        ``'population'``: ``M2 / W``, the variance of the weighted discrete distribution (the TIPM
        reading: the representative samples *are* the distribution).
        """
        if kind not in STD_KINDS:
            raise ValueError(f"kind must be one of {STD_KINDS}, got {kind!r}")
        if kind == "population":
            return self.m2 / self.total_weight
        denom = self.total_weight - self.total_weight_sq / self.total_weight
        if denom <= 0.0:
            return np.full(self.n_points, np.nan)
        return self.m2 / denom

    def std(self, kind: str = "reliability") -> np.ndarray:
        return np.sqrt(np.maximum(self.variance(kind), 0.0))

    @property
    def nbytes(self) -> int:
        """Bytes of state (independent of the number of samples)."""
        return sum(a.nbytes for a in (self.mean, self.m2, self.minimum, self.maximum))


@dataclass
class HistogramQuantiles:
    """Weighted fixed-bin histograms per grid point for bounded-memory percentiles.

    ``lower``/``upper`` (n_points,) fix the bin range per point before the data pass (from
    :class:`WeightedMoments` minimum/maximum); values outside are clipped into the end bins.
    """

    lower: np.ndarray
    upper: np.ndarray
    n_bins: int = 256
    counts: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.lower = np.asarray(self.lower, dtype=float)
        self.upper = np.asarray(self.upper, dtype=float)
        if self.n_bins < 2:
            raise ValueError("n_bins must be at least 2")
        self.counts = np.zeros((self.lower.size, self.n_bins))
        span = self.upper - self.lower
        # A point where all values are equal gets width 0; its percentiles are that value.
        self._width = np.where(span > 0, span / self.n_bins, 0.0)
        self._inv_width = np.where(span > 0, self.n_bins / np.where(span > 0, span, 1.0), 0.0)

    @property
    def bin_width(self) -> np.ndarray:
        """Bin width per point: the bound on the percentile error."""
        return self._width

    def update(self, values: np.ndarray, weights: np.ndarray) -> None:
        """Add a batch: ``values`` (n_samples, n_points), ``weights`` (n_samples,)."""
        values = np.asarray(values, dtype=float)
        n_points = self.lower.size
        idx = np.floor((values - self.lower) * self._inv_width).astype(np.int64)
        np.clip(idx, 0, self.n_bins - 1, out=idx)
        flat = (idx + np.arange(n_points) * self.n_bins).ravel()
        w = np.broadcast_to(np.asarray(weights, dtype=float)[:, None], values.shape).ravel()
        self.counts += np.bincount(flat, weights=w, minlength=n_points * self.n_bins).reshape(
            n_points, self.n_bins)

    def quantiles(self, q: Sequence[float]) -> np.ndarray:
        """Weighted quantiles, shape (len(q), n_points); q in [0, 1]."""
        q = np.atleast_1d(np.asarray(q, dtype=float))
        if ((q < 0) | (q > 1)).any():
            raise ValueError(f"quantiles must lie in [0, 1], got {q}")
        cum = np.cumsum(self.counts, axis=1)
        total = cum[:, -1]
        out = np.empty((q.size, self.lower.size))
        rows = np.arange(self.lower.size)
        for i, qi in enumerate(q):
            target = qi * total
            # First bin whose cumulative weight reaches the target (inverted CDF).
            j = (cum < target[:, None] * (1 - 1e-12)).sum(axis=1)
            j = np.minimum(j, self.n_bins - 1)
            before = np.where(j > 0, cum[rows, np.maximum(j - 1, 0)], 0.0)
            inside = self.counts[rows, j]
            frac = np.where(inside > 0, (target - before) / np.where(inside > 0, inside, 1.0), 0.0)
            out[i] = self.lower + (j + np.clip(frac, 0.0, 1.0)) * self._width
        return out

    @property
    def nbytes(self) -> int:
        return self.counts.nbytes + self.lower.nbytes + self.upper.nbytes


# --- time histories ---------------------------------------------------------------------------

@dataclass
class HistoryStatistics:
    """Statistics of one quantity of one scenario against time or position."""

    scenario: str
    quantity: str
    abscissa_name: str
    abscissa: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    quantiles: dict[float, np.ndarray]
    bin_width: np.ndarray
    minimum: np.ndarray
    maximum: np.ndarray
    n_samples: int
    total_weight: float
    n_effective: float
    std_kind: str

    def to_frame(self) -> pd.DataFrame:
        """Long table: abscissa, mean, std, q<percent>, bin_width, min, max."""
        data = {self.abscissa_name: self.abscissa, "mean": self.mean, "std": self.std}
        for q, values in self.quantiles.items():
            data[f"q{100 * q:g}"] = values
        data.update(bin_width=self.bin_width, minimum=self.minimum, maximum=self.maximum)
        df = pd.DataFrame(data)
        df.insert(0, "quantity", self.quantity)
        df.insert(0, "scenario", self.scenario)
        return df


@dataclass
class AggregationTrace:
    """Instrumentation of one :func:`aggregate_histories` run (for tests and benchmarks)."""

    files_read: int = 0
    max_rows_in_memory: int = 0
    state_nbytes: int = 0
    samples: dict[str, int] = field(default_factory=dict)


def _batch_matrices(df: pd.DataFrame, path: Path, abscissa: str, quantities: list[str]):
    """Yield (scenario, grid, sample_index, weights, {quantity: (n_samples, n_points)}) per scenario.

    Relies on the layout :func:`validate_histories` checked: rows of a sample contiguous, the
    same grid for every sample of a scenario. Samples come out sorted by ``sample_index``: the
    callers add them one at a time in that order, so that floating-point round-off, and hence
    the result, does not depend on how the samples were split into batch files.
    """
    codes, scenarios = pd.factorize(df["scenario"], sort=False)
    index = df["sample_index"].to_numpy()
    x = df[abscissa].to_numpy(dtype=float)
    weight = df["weight"].to_numpy(dtype=float)
    columns = {q: df[q].to_numpy(dtype=float) for q in quantities}
    starts = sample_starts(codes, index)
    for code, scenario in enumerate(scenarios):
        rows = None if len(scenarios) == 1 else np.flatnonzero(codes == code)
        pick = (lambda a: a) if rows is None else (lambda a, rows=rows: a[rows])
        first = np.flatnonzero(pick(starts))
        n_points = (len(index) if rows is None else rows.size) // first.size
        values = {q: pick(col).reshape(first.size, n_points) for q, col in columns.items()}
        sample_index = pick(index)[first]
        order = np.argsort(sample_index, kind="stable")
        yield (str(scenario), pick(x)[:n_points], sample_index[order], pick(weight)[first][order],
               {q: v[order] for q, v in values.items()})


def _files_in_sample_order(paths: list[Path]) -> list[Path]:
    """Order batch files by (first scenario, smallest sample index) they hold.

    Batches are runs of consecutive sample indices, so this visits every scenario's samples in
    index order whatever the batch size (a batch size changes only where the files split).
    """
    keys = []
    for path in paths:
        head = pq.read_table(path, columns=["scenario", "sample_index"]).to_pandas()
        if head.empty:
            keys.append(("", -1, str(path)))
            continue
        first = head.sort_values(["scenario", "sample_index"]).iloc[0]
        keys.append((str(first["scenario"]), int(first["sample_index"]), str(path)))
    return [Path(k[2]) for k in sorted(keys)]


def _read_batch(path: Path, columns: list[str] | None, trace: AggregationTrace,
                validate: bool) -> pd.DataFrame:
    if validate:
        df = read_validated(path, "histories", columns=columns)
    else:  # second pass over a file the first pass validated
        df = pq.read_table(path, columns=columns).to_pandas()
    trace.files_read += 1
    trace.max_rows_in_memory = max(trace.max_rows_in_memory, len(df))
    return df


def aggregate_histories(paths: Iterable[str | os.PathLike[str]], *,
                        quantities: Sequence[str] | None = None,
                        quantiles: Sequence[float] = (0.05, 0.5, 0.95),
                        n_bins: int = 256, std_kind: str = "reliability",
                        max_state_mb: float = 1024.0,
                        trace: AggregationTrace | None = None) -> dict[tuple[str, str], HistoryStatistics]:
    """Weighted mean, std and percentiles per scenario and quantity over time-history batch files.

    Two passes over the files, each holding one file at a time: pass 1 accumulates
    :class:`WeightedMoments` (which also fixes the per-point histogram range), pass 2 the
    :class:`HistogramQuantiles`. Weights come from the ``weight`` column (TIPM probabilities).
    A sample seen twice, or a grid differing between files, is an error naming the file.
    The histogram state is ``scenarios x quantities x points x n_bins x 8`` bytes; above
    ``max_state_mb`` the call stops before allocating it and names the remedies (fewer bins,
    fewer quantities per call). ``quantiles=()`` skips the histograms and the second pass.
    Returns ``{(scenario, quantity): HistoryStatistics}``.
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ResultsSchemaError("no time-history files given")
    paths = _files_in_sample_order(paths)
    trace = trace if trace is not None else AggregationTrace()
    schema_names = pq.read_schema(paths[0]).names
    abscissa = history_abscissa(schema_names)
    quantities = list(quantities) if quantities is not None else history_quantities(schema_names)
    columns = ["scenario", "sample_index", "weight", abscissa] + quantities

    grids: dict[str, np.ndarray] = {}
    moments: dict[tuple[str, str], WeightedMoments] = {}
    # Sample indices already read, per scenario, to detect a sample in two files: the only state
    # that grows with the number of samples (8 bytes per sample).
    seen: dict[str, np.ndarray] = {}
    for path in paths:  # pass 1: moments and range
        names = pq.read_schema(path).names
        absent = [c for c in columns if c not in names]
        if absent:
            raise ResultsSchemaError(f"{path}: missing column(s) {absent} present in {paths[0]}")
        df = _read_batch(path, columns, trace, validate=True)
        for scenario, grid, index, weights, values in _batch_matrices(df, path, abscissa, quantities):
            if scenario not in grids:
                grids[scenario] = grid
                seen[scenario] = np.empty(0, dtype=np.int64)
            elif grid.shape != grids[scenario].shape or not np.allclose(grid, grids[scenario],
                                                                         rtol=1e-9, atol=0.0):
                raise ResultsSchemaError(f"{path}: column {abscissa!r}: scenario {scenario!r} uses "
                                         "a different grid than in the earlier files")
            repeated = index[np.isin(index, seen[scenario])]
            if repeated.size:
                raise ResultsSchemaError(f"{path}: column 'sample_index': sample(s) "
                                         f"{sorted(repeated.tolist())[:5]} of scenario {scenario!r} "
                                         "already read from an earlier file")
            seen[scenario] = np.union1d(seen[scenario], index)
            for q in quantities:
                key = (scenario, q)
                if key not in moments:
                    moments[key] = WeightedMoments(grid.size)
                for i in range(index.size):  # one sample at a time, in index order (see above)
                    moments[key].update(values[q][i:i + 1], weights[i:i + 1])
        del df

    state_mb = sum(m.n_points for m in moments.values()) * n_bins * 8 / 1e6
    if quantiles and state_mb > max_state_mb:
        raise MemoryError(
            f"percentile histograms would take {state_mb:.0f} MB ({len(moments)} scenario-quantity "
            f"pairs x {n_bins} bins) > max_state_mb = {max_state_mb:g}: lower n_bins (the percentile "
            "error bound grows as 1/n_bins), pass fewer quantities per call, or raise max_state_mb")
    histograms = ({key: HistogramQuantiles(m.minimum, m.maximum, n_bins)
                   for key, m in moments.items()} if quantiles else {})
    for path in (paths if quantiles else []):  # pass 2: histograms
        df = _read_batch(path, columns, trace, validate=False)
        for scenario, _, _, weights, values in _batch_matrices(df, path, abscissa, quantities):
            for q in quantities:
                for i in range(weights.size):
                    histograms[(scenario, q)].update(values[q][i:i + 1], weights[i:i + 1])
        del df

    trace.state_nbytes = sum(m.nbytes for m in moments.values()) + sum(
        h.nbytes for h in histograms.values())
    trace.samples = {s: int(v.size) for s, v in seen.items()}
    results = {}
    for (scenario, q), m in moments.items():
        h = histograms.get((scenario, q))
        qs = h.quantiles(quantiles) if h is not None else np.empty((0, m.n_points))
        results[(scenario, q)] = HistoryStatistics(
            scenario=scenario, quantity=q, abscissa_name=abscissa, abscissa=grids[scenario],
            mean=m.mean, std=m.std(std_kind),
            quantiles={float(p): qs[i] for i, p in enumerate(quantiles)},
            bin_width=h.bin_width if h is not None else np.full(m.n_points, np.nan),
            minimum=m.minimum, maximum=m.maximum, n_samples=m.count,
            total_weight=m.total_weight, n_effective=m.n_effective, std_kind=std_kind)
    log.info("aggregated %d files, %s samples per scenario, state %.1f MB",
             len(paths), trace.samples, trace.state_nbytes / 1e6)
    return results


def statistics_frame(results: dict[tuple[str, str], HistoryStatistics]) -> pd.DataFrame:
    """All :class:`HistoryStatistics` as one long table (for ``ttbpipe.io.write_table``)."""
    return pd.concat([r.to_frame() for r in results.values()], ignore_index=True)
