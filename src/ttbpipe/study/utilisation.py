"""Margins to the limits of a study: each assessed index's utilisation against its limit.

A study's extremes carry, for every sample, the processed indices of the assessment profiles and
their utilisation = index / limit (:mod:`ttbpipe.assessment.columns`). This module turns them
into what the report leads with:

* :func:`assessed_limits`: one :class:`~ttbpipe.stats.limits.ConstantLimit` per assessed index,
  "utilisation > 1", so that its exceedance probability, interval and sample-size verdict come
  from the same estimator as every other probability of the study
  (:func:`ttbpipe.stats.reliability.assess_limits`, one interval method for all);
* :func:`utilisation_table`: per scenario and index the weighted median, 95th percentile and
  maximum utilisation, the sample that reached the maximum, the limit (its range over the
  samples) and P(utilisation > 1) with its interval and method;
* :func:`margins`: the governing scenario of each index (largest maximum utilisation), the one
  row per index of the report's first page;
* :func:`plot_section`: one figure per report section, every sample's utilisation of every index
  of the section against the limit line (utilisation 1).
"""

from __future__ import annotations

import re
from typing import Sequence

import numpy as np
import pandas as pd

from ..assessment.columns import OTHER_SECTION, SECTIONS, AssessedIndex, display_name
from ..stats.limits import ConstantLimit
from ..stats.reliability import TAIL_COLUMNS, VERDICT_COLUMNS
from ..stats.tables import weighted_quantile

#: The utilisation at which an index reaches its limit.
AT_LIMIT = 1.0
#: Percentile of the utilisation the report states besides the median and the maximum.
UPPER_PERCENTILE = 0.95

#: Tail estimate and target verdict of P(utilisation > 1), from the reliability table.
RELIABILITY_EXTRA = (*TAIL_COLUMNS, *VERDICT_COLUMNS)

TABLE_COLUMNS = ("scenario", "section", "profile", "index", "standard", "clause", "category",
                 "unit", "n_samples", "median_utilisation", "p95_utilisation", "max_utilisation",
                 "max_sample_index", "max_value", "limit_low", "limit_high", "limit_source",
                 "probability", "ci_low", "ci_high", "upper_one_sided", "n_exceed", "method",
                 "confidence_level", "sufficient", "status", *RELIABILITY_EXTRA)


def limit_name(a: AssessedIndex) -> str:
    """Name of an assessed index's limit in the reliability table (``gb5599_wheel_unloading_ratio``)."""
    return a.value


def assessed_limits(indices: Sequence[AssessedIndex]) -> list[ConstantLimit]:
    """'utilisation > 1' of every assessed index with a limit (categories limit and grade)."""
    out = []
    for a in indices:
        if a.utilisation is None or a.category not in ("limit", "grade"):
            continue
        source = "; ".join(p for p in (f"{a.standard} {a.clause}".strip(), a.limit_source) if p)
        out.append(ConstantLimit(limit_name(a), a.utilisation, AT_LIMIT, "1", source or a.profile,
                                 f"{display_name(a.index)} ({a.profile})", category=a.category))
    return out


def utilisation_table(extremes: pd.DataFrame, indices: Sequence[AssessedIndex],
                      reliability: pd.DataFrame) -> pd.DataFrame:
    """Per (scenario, assessed index with a limit): the utilisation statistics and
    P(utilisation > 1) of the ``reliability`` table (:func:`assessed_limits` rows)."""
    by_limit = ({} if reliability.empty else
                {(r["scenario"], r["limit"]): r for _, r in reliability.iterrows()})
    rows = []
    for scenario, block in extremes.groupby("scenario", sort=True):
        weights = block["weight"].to_numpy(float)
        for a in indices:
            if a.utilisation is None:
                continue
            u = block[a.utilisation].to_numpy(float)
            lim = block[a.limit].to_numpy(float) if a.limit else np.full(u.size, np.nan)
            median, p95 = weighted_quantile(u, weights, [0.5, UPPER_PERCENTILE])
            k = int(np.argmax(u))
            rel = by_limit.get((scenario, limit_name(a)), {})
            rows.append({
                "scenario": str(scenario), "section": a.section, "profile": a.profile,
                "index": a.index, "standard": a.standard, "clause": a.clause,
                "category": a.category, "unit": a.unit, "n_samples": int(u.size),
                "median_utilisation": float(median), "p95_utilisation": float(p95),
                "max_utilisation": float(u[k]),
                "max_sample_index": int(block["sample_index"].iloc[k]),
                "max_value": float(block[a.value].iloc[k]),
                "limit_low": float(np.nanmin(lim)) if np.isfinite(lim).any() else np.nan,
                "limit_high": float(np.nanmax(lim)) if np.isfinite(lim).any() else np.nan,
                "limit_source": a.limit_source,
                **{c: rel.get(c, np.nan) for c in ("probability", "ci_low", "ci_high",
                                                   "upper_one_sided", "n_exceed", "method",
                                                   "confidence_level", "sufficient", "status",
                                                   *RELIABILITY_EXTRA)},
            })
    return pd.DataFrame(rows, columns=list(TABLE_COLUMNS))


def margins(table: pd.DataFrame) -> pd.DataFrame:
    """One row per index (report order kept): the scenario with the largest maximum utilisation."""
    if table.empty:
        return table
    order = list(dict.fromkeys(zip(table["profile"], table["index"])))
    rank = {key: k for k, key in enumerate(order)}
    worst = table.loc[table.groupby(["profile", "index"], sort=False)["max_utilisation"].idxmax()]
    return (worst.assign(_rank=[rank[(p, i)] for p, i in zip(worst["profile"], worst["index"])])
            .sort_values("_rank").drop(columns="_rank").reset_index(drop=True))


def figure_name(section: str) -> str:
    """File stem of a section's figure, numbered in report order (``1_running_safety``)."""
    order = [*SECTIONS, OTHER_SECTION]
    number = order.index(section) + 1 if section in order else len(order) + 1
    return f"{number}_" + re.sub(r"[^a-z0-9]+", "_", section.lower()).strip("_")


def plot_section(extremes: pd.DataFrame, indices: Sequence[AssessedIndex], section: str,
                 scenarios: Sequence[str] | None = None):
    """Every sample's utilisation of each index of ``section`` (one row per index, scenarios
    side by side and coloured, a box from the weighted 5th to 95th percentile with the median),
    against the limit line at utilisation 1."""
    from matplotlib.figure import Figure

    mine = [a for a in indices if a.section == section and a.utilisation is not None]
    if not mine:
        raise ValueError(f"no assessed index with a limit in section {section!r}")
    scenarios = list(scenarios) if scenarios is not None else sorted(extremes["scenario"].unique())
    n_idx, n_sc = len(mine), len(scenarios)
    fig = Figure(figsize=(8.5, 0.9 + 0.32 * n_idx * max(n_sc, 2) ** 0.6 + 0.6), layout="constrained")
    ax = fig.subplots()
    height = 0.8 / n_sc
    largest = 0.0
    rng = np.random.default_rng(0)   # jitter only: the positions of the dots, not the data
    for j, scenario in enumerate(scenarios):
        block = extremes[extremes["scenario"] == scenario]
        w = block["weight"].to_numpy(float)
        for i, a in enumerate(mine):
            y = n_idx - 1 - i + 0.4 - (j + 0.5) * height
            u = block[a.utilisation].to_numpy(float)
            largest = max(largest, float(u.max()))
            lo, med, hi = weighted_quantile(u, w, [0.05, 0.5, 0.95])
            ax.add_patch(_box(lo, hi, y, 0.8 * height, f"C{j % 10}"))
            ax.plot([med, med], [y - 0.4 * height, y + 0.4 * height], color=f"C{j % 10}", lw=2)
            ax.scatter(u, y + (rng.random(u.size) - 0.5) * 0.5 * height, s=6,
                       color=f"C{j % 10}", alpha=0.6, linewidths=0,
                       label=f"{scenario} (n = {u.size})" if i == 0 else None)
    ax.axvline(AT_LIMIT, color="k", lw=1.5, ls="--", label="limit (utilisation 1)")
    ax.set_yticks(range(n_idx))
    ax.set_yticklabels([f"{display_name(a.index)}{' (grade)' if a.category == 'grade' else ''}"
                        f"\n{a.standard}" for a in reversed(mine)], fontsize=7)
    ax.set_ylim(-0.6, n_idx - 0.4)
    ax.set_xlim(0.0, max(1.1, 1.05 * largest))
    ax.set_xlabel("utilisation = processed index / limit (–); box: 5 %-95 % of the samples, "
                  "bar: median", fontsize=8)
    ax.set_title(f"{section}: largest utilisation {largest:.3g} "
                 f"({'above' if largest > AT_LIMIT else 'below'} the limit)", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return fig


def _box(lo: float, hi: float, y: float, height: float, color: str):
    from matplotlib.patches import Rectangle

    return Rectangle((lo, y - 0.5 * height), max(hi - lo, 1e-9), height, facecolor=color,
                     alpha=0.25, edgecolor=color)


def sections_present(indices: Sequence[AssessedIndex]) -> list[str]:
    """Report sections (in order) with at least one assessed index with a limit."""
    have = {a.section for a in indices if a.utilisation is not None}
    return [s for s in [*SECTIONS, *sorted(have - set(SECTIONS))] if s in have]
