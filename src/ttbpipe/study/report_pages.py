"""Every text page of the study's report: one summary, computed once, and the pages that state it.

:func:`summarize` reduces the table of :func:`ttbpipe.stats.reliability.assess_limits` (and,
for a study, its extremes and design) to a :class:`StudySummary`: the evaluated limits and
grades, the limits exceeded, the pairs whose samples did not suffice and the sample size the
criterion asks for, the one-sided upper bounds, the scenarios and their sample counts. Every page
reads its counts and bounds from that one object, so that no two places can state them
differently. Probabilities are written by one formatter (:func:`probability_text`).

Pages (reStructuredText for the Snakemake report, HTML for its report items):

* :func:`main_page_rst`: ``summary.rst``, the few lines the report's main page embeds;
* :func:`compact_page_rst`: the first part of ``report/summary.html`` (limits exceeded, the
  limit x scenario matrix of P(exceed), whether the samples sufficed);
* :func:`first_page_rst`: the full first page (limits exceeded, grades, sample sufficiency, every
  limit per scenario, what could not be evaluated); ``report/summary.html`` continues with it;
* :func:`reliability_html`, :func:`table1_html`, :func:`table1_history_html`,
  :func:`configuration_html`: the tables and the configuration as report pages;
* :func:`study_pages`: all of them for one study, keyed like the files of
  :data:`ttbpipe.study.outputs.STUDY_FILES` (which writes them).
"""

from __future__ import annotations

import html
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from ..assessment.columns import display_name
from ..io import jsonable, write_text
from ..stats.reliability import (DEFAULT_TARGET_PROBABILITY, MET, NOT_MET, NOT_SHOWN,
                                 TAIL_COLUMNS, VERDICT_COLUMNS, probability_text)

#: Report category that holds the full summary (the main page points there).
SUMMARY_CATEGORY = "0. Summary"


# --- the summary ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class StudySummary:
    """What the summary pages state, computed once by :func:`summarize`.

    Row tables keep the order of the assessment table. ``limits`` are the evaluated rows of
    category 'limit', ``grades`` those of category 'grade' (quality grade boundaries, not
    limits), ``skipped`` the rows 'not evaluated'. ``scenarios`` (index: scenario) has
    ``n_samples`` (from the extremes when given, else from the assessment), ``kind`` (from the
    design, else empty), ``weighted`` and ``n_effective`` (from the assessment).
    """

    study: str | None
    assessment: pd.DataFrame
    evaluated: pd.DataFrame    # every evaluated row, limits and grades
    limits: pd.DataFrame
    grades: pd.DataFrame
    skipped: pd.DataFrame
    scenarios: pd.DataFrame
    confidence: str            # the confidence level as the pages write it, e.g. "95 %"
    method: str                # interval method, "n/a" when nothing was evaluated
    exceeded: pd.DataFrame     # limits with at least one exceeding sample
    insufficient: pd.DataFrame         # limits whose number of samples did not suffice
    insufficient_grades: pd.DataFrame  # the same for the grades
    samples_needed: int | None  # largest effective sample size the criterion asks for
    upper_bounds: pd.Series    # per scenario: largest upper end of the P intervals over the limits
    utilisation: pd.DataFrame  # ttbpipe.study.utilisation.utilisation_table (empty without)
    margins: pd.DataFrame      # its governing scenario per index (utilisation.margins)
    target: float = DEFAULT_TARGET_PROBABILITY  # target probability per passage

    def verdicts(self, verdict: str) -> pd.DataFrame:
        """The limit-scenario pairs with target verdict ``verdict`` (met / not met / not shown)."""
        return self.limits[self.limits["target_verdict"] == verdict]

    @property
    def exceeded_by_probability(self) -> pd.DataFrame:
        """The limits exceeded, most probable first."""
        return self.exceeded.sort_values("probability", ascending=False)

    @property
    def n_limits(self) -> int:
        """Number of distinct limits evaluated."""
        return int(self.limits["limit"].nunique())

    @property
    def limit_scenarios(self) -> list[str]:
        """Scenarios with at least one evaluated limit, sorted."""
        return sorted(self.limits["scenario"].unique())

    @property
    def n_runs(self) -> int:
        """Number of samples (coupled runs) over all scenarios."""
        return int(self.scenarios["n_samples"].sum())


def summarize(assessment: pd.DataFrame, *, study: str | None = None,
              extremes: pd.DataFrame | None = None,
              design: pd.DataFrame | None = None,
              utilisation: pd.DataFrame | None = None) -> StudySummary:
    """The :class:`StudySummary` of an :func:`~ttbpipe.stats.reliability.assess_limits` table
    (its rows of category ``raw``, raw-peak thresholds beside the assessed limits, are listed on
    the reliability page only) and of the study's utilisation table."""
    from .utilisation import TABLE_COLUMNS, margins

    if assessment.empty:
        raise ValueError("empty assessment: no scenario or no limit")
    full = assessment
    if "category" in assessment:
        assessment = assessment[assessment["category"] != "raw"]
    not_evaluated = assessment["status"].str.startswith("not evaluated").astype(bool)
    evaluated = assessment[~not_evaluated]
    category = (evaluated["category"] if "category" in evaluated
                else pd.Series("limit", index=evaluated.index))
    for column, dtype in (("n_exceed", "int64"), ("probability", "float64"),
                          ("upper_one_sided", "float64"), ("sufficient", "bool"),
                          *((c, "object") for c in (*TAIL_COLUMNS, *VERDICT_COLUMNS))):
        if column not in evaluated:  # nothing could be evaluated
            evaluated = evaluated.assign(**{column: pd.Series(dtype=dtype)})
    limits = evaluated[category == "limit"]
    grades = evaluated[category == "grade"]
    level = float(evaluated["confidence_level"].iloc[0]) if len(evaluated) else 0.95
    insufficient = limits[~limits["sufficient"].astype(bool)]
    need = insufficient["status"].str.extract(r"about (\d+) effective samples")[0].dropna()
    if utilisation is None:
        utilisation = pd.DataFrame(columns=list(TABLE_COLUMNS))
    return StudySummary(
        study=study, assessment=full, evaluated=evaluated, limits=limits, grades=grades,
        skipped=assessment[not_evaluated],
        scenarios=_scenarios(evaluated, extremes, design),
        confidence=f"{100 * level:g} %",
        method=str(evaluated["method"].iloc[0]) if len(evaluated) else "n/a",
        exceeded=limits[limits["n_exceed"] > 0],
        insufficient=insufficient,
        insufficient_grades=grades[~grades["sufficient"].astype(bool)],
        samples_needed=int(need.astype(int).max()) if len(need) else None,
        upper_bounds=limits.groupby("scenario")["ci_high"].max() if "ci_high" in limits
        else pd.Series(dtype=float),
        utilisation=utilisation, margins=margins(utilisation),
        target=float(evaluated["target_probability"].dropna().iloc[0])
        if evaluated["target_probability"].notna().any() else DEFAULT_TARGET_PROBABILITY)


def _scenarios(evaluated: pd.DataFrame, extremes: pd.DataFrame | None,
               design: pd.DataFrame | None) -> pd.DataFrame:
    first = evaluated.groupby("scenario", sort=True).first()
    if extremes is not None:
        table = extremes.groupby("scenario", sort=True).size().rename("n_samples").to_frame()
    else:
        table = first[["n_samples"]].astype({"n_samples": "int64"}) if "n_samples" in first \
            else pd.DataFrame({"n_samples": pd.Series(dtype="int64")})
    kinds = {} if design is None else dict(
        design.drop_duplicates("scenario").astype({"scenario": str})[["scenario", "kind"]].values)
    table["kind"] = [str(kinds.get(str(s), "")) for s in table.index]
    # the first evaluated row of each scenario, as the full page has always stated it (with the
    # linearised effective size this is the first limit's n_eff)
    for column, default in (("weighted", False), ("n_effective", np.nan)):
        values = first[column].to_dict() if column in first else {}
        table[column] = [values.get(s, default) for s in table.index]
    return table


# --- formatting -----------------------------------------------------------------------------------

def _ci(row, prefix: str = "") -> str:
    return (f"[{probability_text(row[prefix + 'ci_low'])}, "
            f"{probability_text(row[prefix + 'ci_high'])}]")


def _finite(value) -> bool:
    try:
        return bool(np.isfinite(float(value)))
    except (TypeError, ValueError):
        return False


def _beta_text(beta) -> str:
    """The reliability index beta = -Phi^-1(P) as the pages write it (∞ at P = 0)."""
    try:
        b = float(beta)
    except (TypeError, ValueError):
        return "β n/a"
    return "β = ∞" if b == np.inf else (f"β = {b:.2f}" if np.isfinite(b) else "β n/a")


def target_rst(summary: StudySummary) -> list[str]:
    """'Target probability': the count of limit-scenario pairs met / not shown / not met and the
    verdict of every pair not met or not shown (in words, with P, interval and method)."""
    t = probability_text(summary.target)
    n = len(summary.limits)
    met, short, failed = (summary.verdicts(v) for v in (MET, NOT_SHOWN, NOT_MET))
    out = [f"Target P < {t} per passage (limits.target_probability; shown met only when the "
           f"interval's upper end is below it): met for {len(met)}, not shown for {len(short)}, "
           f"not met for {len(failed)} of {n} limit-scenario pairs.", ""]
    for _, r in pd.concat([failed, short]).iterrows():
        out.append(f"- {_escape(r['description'])}, scenario ``{r['scenario']}``: "
                   f"{_escape(r['target_text'])}.")
    return out + [""]


def stated_text(row) -> str:
    """The probability a page states for a limit (the estimate its target verdict rests on:
    counting when a sample exceeds, else the tail model), its interval, beta, the method and the
    number of runs, with the other estimate beside it."""
    n = int(row["n_samples"])
    counting = f"{int(row['n_exceed'])} of {n} runs exceed"
    tail = _finite(row.get("tail_probability"))
    if row.get("verdict_basis") == "tail" and tail:
        return (f"P {'= ' if row['tail_probability'] > 0 else ''}{_tail_p(row)}, "
                f"{_beta_text(row['tail_reliability_index'])} ({row['tail_model']} tail, {n} "
                f"runs; counting: {counting}, P < {probability_text(row['ci_high'])})")
    out = (f"P = {probability_text(row['probability'])} {_ci(row)}, "
           f"{_beta_text(row.get('reliability_index'))} (counting, {counting})")
    if tail:
        out += f"; {row['tail_model']} tail: {_tail_p(row)}"
    return out


def _tail_p(row) -> str:
    """The tail estimate and interval; P = 0 (the limit beyond what the fit represents) as its
    interval's upper end, ``< U``."""
    if row["tail_probability"] == 0.0:
        return f"< {probability_text(row['tail_ci_high'])}"
    return f"{probability_text(row['tail_probability'])} {_ci(row, 'tail_')}"


def stated_cell(row) -> str:
    """P [CI] of the stated estimate, marked 'tail' when the tail model gives it."""
    if row.get("verdict_basis") == "tail" and _finite(row.get("tail_probability")):
        return f"{_tail_p(row)} (tail)"
    return f"{probability_text(row['probability'])} {_ci(row)}"


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


def _sufficiency_text(summary: StudySummary, separator: str = ": ") -> str:
    """'for all N limit-scenario pairs.' / 'for K of N limit-scenario pairs[<separator>the
    criterion ... needs up to about M effective samples per scenario].'"""
    n, short = len(summary.limits), len(summary.insufficient)
    if not short:
        return f"for all {n} limit-scenario pairs."
    need = summary.samples_needed
    return (f"for {short} of {n} limit-scenario pairs"
            + ("" if need is None else
               f"{separator}the criterion (limits.sufficiency) needs up to "
               f"about {need} effective samples per scenario") + ".")


def _quantity_text(value: float, unit: str) -> str:
    """A limit or value in the unit an engineer reads it in (kN, mm, m/s^2)."""
    if not np.isfinite(value):
        return "n/a"
    scale, shown = {"N": (1e-3, " kN"), "m": (1e3, " mm"), "m/s^2": (1.0, " m/s²")}.get(
        unit, (1.0, ""))
    return f"{value * scale:.3g}{shown}"


def limit_text(row) -> str:
    """The limit of a utilisation row: one value, or the range over the samples."""
    lo, hi = row["limit_low"], row["limit_high"]
    if not np.isfinite(lo):
        return "n/a"
    if np.isclose(lo, hi, rtol=1e-6):
        return _quantity_text(lo, row["unit"])
    return f"{_quantity_text(lo, row['unit'])} - {_quantity_text(hi, row['unit'])}"


def _p_cell(row) -> str:
    if not _finite(row.get("probability", np.nan)):
        return "n/a"
    return stated_cell(row)


def margins_rst(summary: StudySummary) -> str:
    """'Margins to the limits': one row per assessed index in the scenario where it came
    closest to its limit (utilisation = processed index / limit)."""
    m = summary.margins
    if m.empty:
        return ""
    level = summary.confidence
    method = next((str(x) for x in m["method"] if isinstance(x, str)), summary.method)
    worst = m.loc[m["max_utilisation"].idxmax()]
    heading = "Margins to the limits"
    out = [heading, "-" * len(heading), "",
           f"Utilisation = index processed as its standard prescribes / its limit (1 = at the "
           f"limit), in the scenario where each index came closest to its limit; median and 95 "
           f"% over the samples (weighted), the largest with the sample that reached it; "
           f"P(utilisation > 1) with its two-sided {level} interval ({method}). "
           f"**Largest utilisation: {worst['max_utilisation']:.3g}**, "
           f"{_escape(display_name(worst['index']))}, {_escape(worst['standard'])} (scenario "
           f"``{worst['scenario']}``, sample {int(worst['max_sample_index'])}). "
           "Per scenario: *utilisation* page; figures: category *1. Margins to the limits*.", ""]
    rows = []
    for _, r in m.iterrows():
        grade = " (grade)" if r["category"] == "grade" else ""
        rows.append([_escape(r["section"]),
                     f"{_escape(display_name(r['index']))} ({_escape(r['standard'])}){grade}",
                     limit_text(r), f"{r['median_utilisation']:.3f}", f"{r['p95_utilisation']:.3f}",
                     f"**{r['max_utilisation']:.3f}** (``{r['scenario']}`` #{int(r['max_sample_index'])})",
                     _p_cell(r)])
    out.append(_list_table(["Section", "Index (standard)", "Limit", "Median", "95 %",
                            "Max (scenario #sample)", f"P(util. > 1) [{level}]"], rows,
                           [12, 30, 12, 8, 8, 16, 16]))
    return "\n".join(out) + "\n"


def utilisation_html(summary: StudySummary) -> str:
    """``report/utilisation.html``: the utilisation statistics per scenario and assessed index."""
    u = summary.utilisation
    shown = u.assign(limit=[limit_text(r) for _, r in u.iterrows()],
                     P_utilisation_gt_1=[_p_cell(r) for _, r in u.iterrows()])[
        ["scenario", "section", "profile", "index", "clause", "category", "limit", "n_samples",
         "median_utilisation", "p95_utilisation", "max_utilisation", "max_sample_index",
         "max_value", "P_utilisation_gt_1", "method", "tail_method", "target_text", "status",
         "limit_source"]] if len(u) else u
    return table_html(shown, "Utilisation of the limits per scenario and index",
                      "utilisation = processed index / limit (docs/assessment.md); weighted median "
                      "and 95th percentile over the samples; max_value in SI units (index name); "
                      f"P(utilisation > 1) with its two-sided {summary.confidence} interval.")


# --- summary pages ------------------------------------------------------------------------------

def intro_rst(summary: StudySummary) -> str:
    """First paragraph of the summary page: what was simulated."""
    parts = [f"``{scenario}`` ({row['kind']}, {int(row['n_samples'])} samples)"
             for scenario, row in summary.scenarios.iterrows()]
    return (f"Study ``{summary.study}``: {summary.n_runs} coupled train-track-bridge runs in "
            f"{len(summary.scenarios)} scenarios: " + ", ".join(parts) + ". "
            "Each sample is assessed as the standards prescribe (docs/assessment.md); "
            "P(index > limit) per scenario with two-sided confidence intervals "
            "(TIPM-weighted scenarios use an effective sample size); method: "
            "docs/reliability.md, study design: docs/studies.md.")


def main_page_rst(summary: StudySummary, *, details: str = SUMMARY_CATEGORY) -> str:
    """A few lines for the report's main page (which must stay short to display whole):
    the limits exceeded with P and interval, and whether the number of samples sufficed."""
    level, out = summary.confidence, []
    exceeded = summary.exceeded_by_probability
    if exceeded.empty:
        out.append(f"**Limits exceeded: none.** No sample of any scenario exceeded any of the "
                   f"{summary.n_limits} safety and comfort limits ({level} intervals of "
                   "P(exceed) reach at most: " + ", ".join(
                       f"{s} {probability_text(b)}" for s, b in summary.upper_bounds.items())
                   + ").")
    else:
        out.append(f"**Limits exceeded** (P(max index > limit), {level} CI):")
        out.append("")
        for _, r in exceeded.iterrows():
            out.append(f"- **{_escape(r['description'])} > {_escape(r['threshold'])}**, scenario "
                       f"``{r['scenario']}``: P = {probability_text(r['probability'])} {_ci(r)} "
                       f"({int(r['n_exceed'])} of {int(r['n_samples'])})")
    if not summary.margins.empty:
        m = summary.margins
        w = m.loc[m["max_utilisation"].idxmax()]
        out += ["", f"**Largest utilisation {w['max_utilisation']:.3g}** (index / limit): "
                f"{_escape(display_name(w['index']))} ({_escape(w['standard'])}), limit "
                f"{limit_text(w)}, scenario "
                f"``{w['scenario']}`` sample {int(w['max_sample_index'])}. Closest to its limit "
                f"in each section (every index: *{details}*, *Margins to the limits*):", ""]
        rows = []
        for section, block in m.groupby("section", sort=False):
            r = block.loc[block["max_utilisation"].idxmax()]
            rows.append([_escape(section), f"{_escape(display_name(r['index']))} "
                         f"({_escape(r['standard'])})", limit_text(r),
                         f"{r['p95_utilisation']:.3f}", f"**{r['max_utilisation']:.3f}**",
                         _p_cell(r)])
        out.append(_list_table(["Section", "Index", "Limit", "Utilisation, 95 %",
                                "Utilisation, max", f"P(util. > 1) [{level}]"], rows))
    out.append("")
    verdict = "Yes" if summary.insufficient.empty else "No"
    out.append(f"**Did the samples suffice? {verdict}**, {_sufficiency_text(summary)}")
    if len(summary.limits):
        n = len(summary.limits)
        counts = ", ".join(f"{v} {len(summary.verdicts(v))}" for v in (MET, NOT_SHOWN, NOT_MET))
        out += ["", f"**Target P < {probability_text(summary.target)} per passage** "
                f"(limits.target_probability, decided on the interval's upper end): {counts} of "
                f"{n} limit-scenario pairs."]
    out += ["", f"Table per limit and scenario, grades, sources: category *{details}*."]
    return "\n".join(out) + "\n"


def compact_page_rst(summary: StudySummary, *, intro: str,
                     details: str = SUMMARY_CATEGORY) -> str:
    """Short first page: limits exceeded, a limit x scenario matrix of P(exceed) with its
    interval, and whether the samples sufficed (grades, sources and the full verdicts are on
    the full page, :func:`first_page_rst`)."""
    level = summary.confidence
    title = f"Reliability summary: {summary.study}"
    out = [title, "=" * len(title), "", intro, ""]
    margins = margins_rst(summary)
    if margins:
        out += [margins, ""]
    out += ["Limits exceeded", "-" * 15, ""]
    exceeded = summary.exceeded_by_probability
    if exceeded.empty:
        out.append(f"**No sample exceeded any limit** ({summary.n_limits} limits, "
                   f"{len(summary.limit_scenarios)} scenarios).")
    for _, r in exceeded.iterrows():
        out.append(f"- **{_escape(r['description'])} > {_escape(r['threshold'])}**, scenario "
                   f"``{r['scenario']}``: P = {probability_text(r['probability'])}, {level} CI "
                   f"{_ci(r)} ({int(r['n_exceed'])} of {int(r['n_samples'])} samples)")
    if not margins:   # results without assessed indices: the limit x scenario matrix
        out += _matrix_rst(summary)
    out += ["", "Did the number of samples suffice?", "-" * 34, ""]
    verdict = "**Yes**," if summary.insufficient.empty else "**No**"
    out.append(f"{verdict} {_sufficiency_text(summary, '; ')}")
    if len(summary.limits):
        out += ["", "Target probability", "-" * 18, ""] + target_rst(summary)
    if len(summary.skipped):
        out += ["", f"Not evaluated: {', '.join(sorted(summary.skipped['limit'].unique()))} (see "
                "the full summary)."]
    out += ["", f"Grades, sources and verdicts per limit: *{details}*."]
    return "\n".join(out) + "\n"


def _matrix_rst(summary: StudySummary) -> list[str]:
    level = summary.confidence
    heading = f"P(exceed) per limit and scenario ({level} CI)"
    out = ["", heading, "-" * len(heading), ""]
    scenarios = summary.limit_scenarios
    out += [".. list-table::", "   :header-rows: 1", "",
            "   * - limit"] + [f"     - {s}" for s in scenarios]
    for name, block in summary.limits.groupby("limit", sort=False):
        first = block.iloc[0]
        out.append(f"   * - {name} > {_escape(first['threshold'])}")
        by = block.set_index("scenario")
        for s in scenarios:
            if s not in by.index:
                out.append("     - n/a")
                continue
            r = by.loc[s]
            mark = "" if r["sufficient"] else " \\*"
            out.append(f"     - {stated_cell(r)}{mark}")
    out += ["", "\\* the number of samples did not suffice; (tail): no sample exceeded, the "
            "extreme-value tail model gives P.", ""]
    return out


def _tail_cell(r) -> str:
    """P, interval and method of the tail model, or why there is none."""
    if _finite(r.get("tail_probability")):
        flag = "; extrapolated far beyond the data" if r.get("tail_extrapolation") else ""
        gof = (f"; A² = {float(r['tail_gof_statistic']):.2f}"
               + (f", p = {float(r['tail_gof_pvalue']):.2f}" if _finite(r.get("tail_gof_pvalue"))
                  else "") if _finite(r.get("tail_gof_statistic")) else "")
        return (f"{_tail_p(r)} "
                f"({_escape(r['tail_method'])}{gof}{flag})")
    status = r.get("tail_status")
    return _escape(status) if isinstance(status, str) else "n/a"


def _exceedance_line(r, pct: str) -> str:
    return (f"- scenario ``{r['scenario']}``: **{_escape(r['description'])}** > "
            f"{_escape(r['threshold'])}: P = {probability_text(r['probability'])}, {pct} CI "
            f"{_ci(r)} ({int(r['n_exceed'])} of {int(r['n_samples'])} samples"
            + (f", n_eff = {r['n_effective']:.1f}" if r.get("weighted") else "")
            + f"; {_escape(r['source'])}).")


def _verdict_lines(rows: pd.DataFrame) -> list[str]:
    return [f"- {_escape(r['description'])}, scenario ``{r['scenario']}``: "
            f"{_escape(r['status'])}." for _, r in rows.iterrows()] + [""]


def _details(summary: StudySummary) -> list[str]:
    """The sections of the full first page after its title and introduction."""
    pct = summary.confidence
    out = [_heading("Limits exceeded", "-")]
    if summary.exceeded.empty:
        out.append(f"No sample exceeded any evaluated limit ({len(summary.limits)} limit-scenario "
                   "pairs).\n")
    else:
        for _, r in summary.exceeded.sort_values(["scenario", "probability"],
                                                 ascending=[True, False]).iterrows():
            out.append(_exceedance_line(r, pct))
        out.append("")
    if not summary.grades.empty:
        out.append(_heading("Ride-quality grades", "-"))
        out.append("Probability of exceeding a grade boundary (not a limit):\n")
        for _, r in summary.grades.iterrows():
            out.append(_exceedance_line(r, pct))
        out.append("")

    out.append(_heading("Did the number of samples suffice?", "-"))
    n = len(summary.limits)
    if n == 0:
        out.append("No limit could be evaluated.\n")
    elif summary.insufficient.empty:
        out.append(f"Yes, for all {n} evaluated limit-scenario pairs.\n")
    else:
        out.append(f"No, for {len(summary.insufficient)} of {n} limit-scenario pairs:\n")
        out += _verdict_lines(summary.insufficient)
    if not summary.grades.empty:
        m, short = len(summary.grades), summary.insufficient_grades
        if short.empty:
            out.append(f"Ride-quality grades: yes, for all {m} evaluated grade-scenario pairs.\n")
        else:
            out.append(f"Ride-quality grades: no, for {len(short)} of {m} grade-scenario pairs:\n")
            out += _verdict_lines(short)

    if len(summary.limits):
        out.append(_heading("Target probability", "-"))
        out += target_rst(summary)

    out.append(_heading("All limits", "-"))
    out.append("P stated: the counting estimate when a sample exceeded, else the extreme-value "
               "tail model of the per-sample maxima (docs/reliability.md §9); β = −Φ⁻¹(P).\n")
    for scenario, block in summary.evaluated.groupby("scenario", sort=True):
        sizes = summary.scenarios.loc[scenario]
        size = f"{int(sizes['n_samples'])} samples"
        if sizes["weighted"]:
            size += f", effective {sizes['n_effective']:.1f} (weighted)"
        out.append(f"Scenario ``{scenario}`` ({size}).\n")
        rows = [[_escape(r["description"]), _escape(r["threshold"]), str(int(r["n_exceed"])),
                 probability_text(r["probability"]), _ci(r), _tail_cell(r),
                 _beta_text(r["tail_reliability_index"] if r.get("verdict_basis") == "tail"
                            else r.get("reliability_index")),
                 _escape(r.get("target_verdict") if isinstance(r.get("target_verdict"), str)
                         else "n/a"),
                 "yes" if r["sufficient"] else "no", _escape(r["source"])]
                for _, r in block.iterrows()]
        out.append(_list_table(["Index", "Limit", "Exceeding samples", "P(exceed), counting",
                                f"{pct} CI", f"P(exceed), tail model [{pct}]", "β of P stated",
                                "Target", "Samples sufficed", "Source"], rows,
                               [18, 11, 7, 8, 12, 18, 6, 6, 6, 16]))
    if not summary.skipped.empty:
        out.append(_heading("Not evaluated", "-"))
        for _, r in summary.skipped.iterrows():
            out.append(f"- {_escape(r['description'])}, scenario ``{r['scenario']}``: "
                       f"{_escape(r['status'].removeprefix('not evaluated: '))}.")
        out.append("")
    return out


def first_page_rst(assessment: pd.DataFrame | StudySummary, *, title: str = "Reliability summary",
                   study: str | None = None, intro: str | None = None) -> str:
    """reStructuredText summary of an :func:`~ttbpipe.stats.reliability.assess_limits` table
    (or of its :class:`StudySummary`).

    Sections: limits exceeded (probability and confidence interval per scenario); whether the
    number of samples sufficed; the full table per scenario; limits that could not be evaluated.
    """
    summary = assessment if isinstance(assessment, StudySummary) else summarize(assessment,
                                                                                study=study)
    study = summary.study if study is None else study
    out = [_heading(title + (f": {study}" if study else ""), "=")]
    out.append(intro.strip() + "\n" if intro else
               f"Probability that a sample's maximum response index exceeds its limit, "
               f"P(max index > limit), per scenario, with two-sided {summary.confidence} "
               f"confidence intervals (method: {summary.method}; weighted "
               "samples use an effective sample size). Details: docs/reliability.md.\n")
    out += _details(summary)
    return "\n".join(out).rstrip() + "\n"


def write_first_page(assessment: pd.DataFrame, path: str | os.PathLike[str], **kwargs) -> Path:
    """Write :func:`first_page_rst` atomically to ``path``."""
    return write_text(first_page_rst(assessment, **kwargs), path)


def summary_html(summary: StudySummary) -> str:
    """``report/summary.html``: the compact page (with the study's introduction), then the
    sections of the full first page under 'Details'."""
    compact = compact_page_rst(summary, intro=intro_rst(summary), details="Details below")
    details = "\n".join(["", "", *_details(summary)]).rstrip() + "\n"
    return rst_to_html(compact + "\nDetails\n=======\n\n" + details,
                       f"Reliability summary: {summary.study}")


# --- HTML pages -------------------------------------------------------------------------------------

def html_page(title: str, body: str) -> str:
    """A self-contained HTML page (the report's tables and configuration)."""
    style = ("body{font-family:sans-serif;font-size:13px;margin:1em}"
             "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:3px 6px;"
             "text-align:right}th{background:#eee}pre{font-size:12px}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{style}</style></head><body><h2>{html.escape(title)}</h2>{body}</body></html>\n")


def table_html(df: pd.DataFrame, title: str, note: str = "") -> str:
    """A table as a self-contained HTML page (for the Snakemake report)."""
    body = (f"<p>{html.escape(note)}</p>" if note else "") + df.to_html(
        index=False, float_format=lambda v: f"{v:.4g}", na_rep="", border=0)
    return html_page(title, body)


def rst_to_html(rst: str, title: str) -> str:
    """reStructuredText -> standalone HTML page (docutils)."""
    from docutils.core import publish_string

    return publish_string(rst, writer="html",
                          settings_overrides={"embed_stylesheet": True, "report_level": 3,
                                              "title": title}).decode()


def reliability_html(assessment: pd.DataFrame) -> str:
    """``report/reliability.html``: the exceedance table per scenario and limit."""
    shown = assessment[["scenario", "limit", "threshold", "n_samples", "n_exceed", "probability",
                        "ci_low", "ci_high", "reliability_index", "tail_probability",
                        "tail_ci_low", "tail_ci_high", "tail_reliability_index", "tail_method",
                        "tail_gof_statistic", "tail_gof_pvalue", "tail_status", "target_text",
                        "sufficient", "status", "source"]
                       ] if "tail_probability" in assessment else assessment
    return table_html(
        shown, "Exceedance probabilities per scenario and limit",
        "P(max index > limit) with two-sided confidence intervals: counting (probability, ci_*) "
        "and the extreme-value tail model (tail_*); reliability_index = -Phi^-1(P); "
        "target_text: the target verdict; 'sufficient': the sample-size criterion of "
        "limits.sufficiency.")


def table1_html(table1: pd.DataFrame) -> str:
    """``report/table1_std.html``: Table 1 over the per-sample maxima."""
    return table_html(
        table1, "Table 1: standard deviation of each index per randomness condition",
        "Weighted standard deviation of the per-sample maxima (SI units in the index names); "
        "columns: scenarios.")


def table1_history_html(table1_history: pd.DataFrame) -> str:
    """``report/table1_history_std.html``: Table 1 over the time histories."""
    return table_html(
        table1_history,
        "Table 1 (time histories): maximum over position of the standard deviation",
        "As the paper reads Table 1: max of the std curve of each quantity (SI units).")


def configuration_html(config: Mapping[str, Any]) -> str:
    """``report/configuration.html``: the study configuration as an HTML page."""
    import yaml

    text = yaml.safe_dump(jsonable(config), sort_keys=False, default_flow_style=None, width=100)
    return html_page("Resolved study configuration", f"<pre>{html.escape(text)}</pre>")


def study_pages(summary: StudySummary, config: Mapping[str, Any], table1: pd.DataFrame,
                table1_history: pd.DataFrame | None = None) -> dict[str, str]:
    """Every text page of a study, keyed like :data:`ttbpipe.study.outputs.STUDY_FILES`
    (``table1_history_html`` only with the time-history table)."""
    pages = {"summary_rst": main_page_rst(summary), "summary": summary_html(summary),
             "reliability_html": reliability_html(summary.assessment),
             "utilisation_html": utilisation_html(summary),
             "table1_html": table1_html(table1)}
    if table1_history is not None:
        pages["table1_history_html"] = table1_history_html(table1_history)
    pages["configuration"] = configuration_html(config)
    return pages
