"""Tables over per-sample extremes and history statistics (the paper's Table 1, Fig. 17).

* :func:`weighted_mean_std` / :func:`weighted_quantile`: weighted moments and exact weighted
  quantiles of one column (the same definitions as the streaming reductions of
  :mod:`ttbpipe.stats.streaming`);
* :func:`standard_deviation_table`: Table 1, the weighted standard deviation of each index per
  scenario; :func:`max_std_table`: Table 1 as the paper reads it, the maximum over position of
  the standard-deviation curve of each time-history quantity;
* :func:`forecast_envelope`: weighted mean and lower/upper quantiles of an index per forecast
  scenario (Fig. 17).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from .schema import response_columns
from .streaming import HistoryStatistics, WeightedMoments


def weighted_mean_std(values: np.ndarray, weights: np.ndarray,
                      kind: str = "reliability") -> tuple[float, float]:
    """Weighted mean and std of one column (same definitions as :class:`WeightedMoments`)."""
    m = WeightedMoments(1)
    m.update(np.asarray(values, dtype=float)[:, None], weights)
    return float(m.mean[0]), float(m.std(kind)[0])


def weighted_quantile(values: np.ndarray, weights: np.ndarray, q: Sequence[float]) -> np.ndarray:
    """Exact weighted inverted-CDF quantiles (numpy ``method='inverted_cdf'`` with weights)."""
    return np.percentile(np.asarray(values, dtype=float), 100 * np.asarray(q, dtype=float),
                         weights=np.asarray(weights, dtype=float), method="inverted_cdf")


def standard_deviation_table(extremes: pd.DataFrame, columns: Sequence[str] | None = None,
                             scenarios: Sequence[str] | None = None,
                             kind: str = "reliability") -> pd.DataFrame:
    """The paper's Table 1 from per-sample extremes: weighted std of each index per scenario.

    Rows: response indices (with units in their names); columns: scenarios (randomness
    conditions C1..C4 in the paper). See :func:`max_std_table` for the time-history variant.
    """
    columns = list(columns) if columns is not None else response_columns(extremes)
    scenarios = list(scenarios) if scenarios is not None else sorted(extremes["scenario"].unique())
    table = pd.DataFrame(index=pd.Index(columns, name="index"), columns=scenarios, dtype=float)
    for scenario in scenarios:
        block = extremes[extremes["scenario"] == scenario]
        if block.empty:
            raise ValueError(f"no samples for scenario {scenario!r}")
        for col in columns:
            if col in block.columns:
                table.loc[col, scenario] = weighted_mean_std(block[col], block["weight"], kind)[1]
    return table


def max_std_table(results: dict[tuple[str, str], HistoryStatistics]) -> pd.DataFrame:
    """Table 1 as the paper reads it: maximum over time/position of the std curve per scenario."""
    rows = {}
    for (scenario, quantity), r in results.items():
        rows.setdefault(quantity, {})[scenario] = float(np.nanmax(r.std))
    table = pd.DataFrame.from_dict(rows, orient="index")
    table.index.name = "quantity"
    return table[sorted(table.columns)]


def forecast_envelope(extremes: pd.DataFrame, column: str, scenarios: Sequence[str] | None = None,
                      lower: float = 0.05, upper: float = 0.95) -> pd.DataFrame:
    """Per scenario (e.g. forecast horizon): weighted mean and lower/upper quantiles of an index.

    Fig. 17 of the paper ("general, upper and lower limits"). Scenario order: as given, else
    sorted (ISO dates sort chronologically).
    """
    scenarios = list(scenarios) if scenarios is not None else sorted(extremes["scenario"].unique())
    rows = []
    for scenario in scenarios:
        block = extremes[extremes["scenario"] == scenario]
        if block.empty:
            raise ValueError(f"no samples for scenario {scenario!r}")
        values, weights = block[column].to_numpy(dtype=float), block["weight"].to_numpy(dtype=float)
        mean, std = weighted_mean_std(values, weights)
        lo, hi = weighted_quantile(values, weights, [lower, upper])
        rows.append({"scenario": scenario, "mean": mean, "std": std, "lower": lo, "upper": hi,
                     "n_samples": len(block)})
    env = pd.DataFrame(rows)
    env.attrs.update(column=column, lower_q=lower, upper_q=upper)
    return env
