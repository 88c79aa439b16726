"""The report's first page: which limits are exceeded, how likely, and whether the samples sufficed.

:func:`first_page_rst` turns the table of :func:`ttbpipe.stats.reliability.assess_limits` into
reStructuredText (for the Snakemake report); :func:`write_first_page` writes it atomically.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

import pandas as pd

from ..io import write_text


def _fmt_p(p: float) -> str:
    if p == 0:
        return "0"
    return f"{p:.3g}" if p >= 1e-3 else f"{p:.2e}"


def _ci(row) -> str:
    return f"[{_fmt_p(row['ci_low'])}, {_fmt_p(row['ci_high'])}]"


def _heading(text: str, char: str) -> str:
    return f"{text}\n{char * len(text)}\n"


def _escape(text: str) -> str:
    """Escape characters that reStructuredText would read as markup in table cells."""
    return str(text).replace("\\", "\\\\").replace("*", "\\*").replace("`", "\\`").replace("|", "\\|")


def _list_table(header: list[str], rows: Iterable[list[str]], widths: list[int] | None = None) -> str:
    lines = [".. list-table::", "   :header-rows: 1"]
    if widths:
        lines.append("   :widths: " + " ".join(str(w) for w in widths))
    lines.append("")
    for row in [header, *rows]:
        lines.append(f"   * - {row[0]}")
        lines += [f"     - {cell}" for cell in row[1:]]
    return "\n".join(lines) + "\n"


def _exceedance_line(r, pct: str) -> str:
    return (f"- scenario ``{r['scenario']}``: **{_escape(r['description'])}** > "
            f"{_escape(r['threshold'])}: P = {_fmt_p(r['probability'])}, {pct} CI {_ci(r)} "
            f"({int(r['n_exceed'])} of {int(r['n_samples'])} samples"
            + (f", n_eff = {r['n_effective']:.1f}" if r.get("weighted") else "")
            + f"; {_escape(r['source'])}).")


def first_page_rst(assessment: pd.DataFrame, *, title: str = "Reliability summary",
                   study: str | None = None, intro: str | None = None) -> str:
    """reStructuredText summary of an :func:`~ttbpipe.stats.reliability.assess_limits` table.

    Sections: limits exceeded (probability and confidence interval per scenario); whether the
    number of samples sufficed; the full table per scenario; limits that could not be evaluated.
    """
    if assessment.empty:
        raise ValueError("empty assessment: no scenario or no limit")
    evaluated = assessment[assessment["status"].str.startswith("not evaluated") == False]  # noqa: E712
    skipped = assessment[assessment["status"].str.startswith("not evaluated")]
    level = float(evaluated["confidence_level"].iloc[0]) if len(evaluated) else 0.95
    pct = f"{100 * level:g} %"
    out = [_heading(title + (f": {study}" if study else ""), "=")]
    out.append(intro.strip() + "\n" if intro else
               f"Probability that a sample's maximum response index exceeds its limit, "
               f"P(max index > limit), per scenario, with two-sided {pct} confidence intervals "
               f"(method: {evaluated['method'].iloc[0] if len(evaluated) else 'n/a'}; weighted "
               "samples use an effective sample size). Details: docs/reliability.md.\n")

    out.append(_heading("Limits exceeded", "-"))
    category = evaluated["category"] if "category" in evaluated else pd.Series("limit", evaluated.index)
    limits_only = evaluated[category == "limit"]
    if "n_exceed" not in limits_only:  # nothing could be evaluated
        limits_only = limits_only.assign(n_exceed=pd.Series(dtype="int64"))
    exceeded = limits_only[limits_only["n_exceed"] > 0]
    if exceeded.empty:
        out.append(f"No sample exceeded any evaluated limit ({len(limits_only)} limit-scenario "
                   "pairs).\n")
    else:
        for _, r in exceeded.sort_values(["scenario", "probability"],
                                         ascending=[True, False]).iterrows():
            out.append(_exceedance_line(r, pct))
        out.append("")
    grades = evaluated[category == "grade"]
    if not grades.empty:
        out.append(_heading("Ride-quality grades", "-"))
        out.append("Probability of exceeding a grade boundary (not a limit):\n")
        for _, r in grades.iterrows():
            out.append(_exceedance_line(r, pct))
        out.append("")

    out.append(_heading("Did the number of samples suffice?", "-"))
    if len(evaluated) == 0:
        out.append("No limit could be evaluated.\n")
    else:
        short = evaluated[~evaluated["sufficient"].astype(bool)]
        if short.empty:
            out.append(f"Yes, for all {len(evaluated)} evaluated limit-scenario pairs.\n")
        else:
            out.append(f"No, for {len(short)} of {len(evaluated)} limit-scenario pairs:\n")
            for _, r in short.iterrows():
                out.append(f"- {_escape(r['description'])}, scenario ``{r['scenario']}``: "
                           f"{_escape(r['status'])}.")
            out.append("")

    out.append(_heading("All limits", "-"))
    for scenario, block in evaluated.groupby("scenario", sort=True):
        first = block.iloc[0]
        size = f"{int(first['n_samples'])} samples"
        if first.get("weighted"):
            size += f", effective {first['n_effective']:.1f} (weighted)"
        out.append(f"Scenario ``{scenario}`` ({size}).\n")
        rows = [[_escape(r["description"]), _escape(r["threshold"]), str(int(r["n_exceed"])),
                 _fmt_p(r["probability"]), _ci(r), "yes" if r["sufficient"] else "no",
                 _escape(r["source"])] for _, r in block.iterrows()]
        out.append(_list_table(["Index", "Limit", "Exceeding samples", "P(exceed)", f"{pct} CI",
                                "Samples sufficed", "Source"], rows, [22, 14, 9, 9, 14, 8, 24]))
    if not skipped.empty:
        out.append(_heading("Not evaluated", "-"))
        for _, r in skipped.iterrows():
            out.append(f"- {_escape(r['description'])}, scenario ``{r['scenario']}``: "
                       f"{_escape(r['status'].removeprefix('not evaluated: '))}.")
        out.append("")
    return "\n".join(out).rstrip() + "\n"


def write_first_page(assessment: pd.DataFrame, path: str | os.PathLike[str], **kwargs) -> Path:
    """Write :func:`first_page_rst` atomically to ``path``."""
    return write_text(first_page_rst(assessment, **kwargs), path)
