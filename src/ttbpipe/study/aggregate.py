"""Study-level tables, figures and report pages over all batch files (glue over ttbpipe.stats).

:func:`aggregate_study` reads the batch files one at a time (the time histories through
:func:`ttbpipe.stats.aggregate.aggregate_histories`, bounded memory; the extremes are one small
row per sample) and writes, under ``out`` (results/study by default):

* ``extremes.parquet``: every sample's extremes, sorted by scenario and sample index;
* ``history_statistics.parquet``: weighted mean, std and percentiles against position;
* ``reliability.parquet``: exceedance probability, interval and verdict per (scenario, limit);
* ``convergence.parquet``: the convergence curves of every (scenario, limit);
* ``table1_std.parquet``: the paper's Table 1, weighted std of each index per randomness
  condition (the fields scenarios; every scenario when there is none); ``table1_history_std.parquet``:
  the maximum over position of the std curve of each time-history quantity;
* ``summary.rst`` / ``summary.html``: the report's first page; ``report/*.html``: the tables and
  the resolved configuration as report pages;
* ``figures/<kind>/*.png``: convergence per scenario, PDFs of extremes (Figs. 15-16), history
  mean/std (Figs. 10-14), forecast envelopes (Fig. 17).

Columns of every table: docs/studies.md.
"""

from __future__ import annotations

import html
import logging
import os
import re
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from .. import io
from ..inspection.format import DATE_PATTERN
from ..stats import aggregate as stats_aggregate
from ..stats import plots
from ..stats.limits import limits_from_config
from ..stats.reliability import ReliabilitySettings, assess_limits, convergence_curve
from ..stats.report import first_page_rst
from ..stats.schema import RESPONSE_INDICES

log = logging.getLogger(__name__)

_DATE = re.compile(rf"^{DATE_PATTERN}$")  # a dated (campaign) scenario
#: Indices of the paper's Fig. 17 (long-term behaviour), when present.
ENVELOPE_COLUMNS = ("max_deck_vertical_acc_m_s2", "max_deck_lateral_acc_m_s2",
                    "max_carbody_lateral_acc_m_s2", "max_wheel_vertical_force_N",
                    "max_wheel_lateral_force_N")
FIGURE_KINDS = ("convergence", "pdf", "history", "envelope")


def scenario_groups(design: pd.DataFrame) -> dict[str, list[str]]:
    """Scenarios drawn together: 'irregularity' (campaign, single excitation, forecasts, Monte
    Carlo irregularity) and 'fields' (randomness conditions, KLE and plain Monte Carlo)."""
    kinds = design.drop_duplicates("scenario").set_index("scenario")["kind"]
    groups = {"irregularity": sorted(s for s, k in kinds.items()
                                     if k in ("irregularity", "forecast", "single", "irregularity_mc")),
              "fields": sorted(s for s, k in kinds.items() if k in ("fields", "fields_mc"))}
    return {g: s for g, s in groups.items() if s}


def _html_page(title: str, body: str) -> str:
    style = ("body{font-family:sans-serif;font-size:13px;margin:1em}"
             "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:3px 6px;"
             "text-align:right}th{background:#eee}pre{font-size:12px}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{style}</style></head><body><h2>{html.escape(title)}</h2>{body}</body></html>\n")


def table_html(df: pd.DataFrame, title: str, note: str = "") -> str:
    """A table as a self-contained HTML page (for the Snakemake report)."""
    body = (f"<p>{html.escape(note)}</p>" if note else "") + df.to_html(
        index=False, float_format=lambda v: f"{v:.4g}", na_rep="", border=0)
    return _html_page(title, body)


def rst_to_html(rst: str, title: str) -> str:
    """reStructuredText -> standalone HTML page (docutils)."""
    from docutils.core import publish_string

    return publish_string(rst, writer="html",
                          settings_overrides={"embed_stylesheet": True, "report_level": 3,
                                              "title": title}).decode()


def config_html(config: Mapping[str, Any]) -> str:
    """The resolved study configuration as an HTML page."""
    import yaml

    text = yaml.safe_dump(_plain(config), sort_keys=False, default_flow_style=None, width=100)
    return _html_page("Resolved study configuration", f"<pre>{html.escape(text)}</pre>")


def _plain(obj: Any) -> Any:
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, (np.generic,)):
        return obj.item()
    return obj


def _indices_present(extremes: pd.DataFrame) -> list[str]:
    return [c for c in RESPONSE_INDICES if c in extremes.columns]


def summary_intro(extremes: pd.DataFrame, design: pd.DataFrame, study: str) -> str:
    """First paragraph of the first page: what was simulated."""
    parts = []
    for scenario, block in extremes.groupby("scenario", sort=True):
        kind = design.loc[design["scenario"] == scenario, "kind"].iloc[0]
        parts.append(f"``{scenario}`` ({kind}, {len(block)} samples)")
    return (f"Study ``{study}``: {len(extremes)} coupled train-track-bridge runs in "
            f"{extremes['scenario'].nunique()} scenarios: " + ", ".join(parts) + ". "
            "P(max index > limit) per scenario with two-sided confidence intervals "
            "(TIPM-weighted scenarios use an effective sample size); method: "
            "docs/reliability.md, study design: docs/studies.md.")


def _p_text(p: float) -> str:
    return "0" if p == 0 else (f"{p:.3g}" if p >= 1e-3 else f"{p:.1e}")


def compact_first_page_rst(assessment: pd.DataFrame, *, study: str, intro: str,
                           details: str = "0. Summary") -> str:
    """Short first page for the report's main page: limits exceeded, a limit x scenario matrix
    of P(exceed) with its interval, and whether the samples sufficed (grades, sources and the
    full verdicts are on the full page, :func:`ttbpipe.stats.report.first_page_rst`)."""
    ok = ~assessment["status"].str.startswith("not evaluated")
    evaluated = assessment[ok & (assessment["category"] == "limit")]
    level = f"{100 * float(evaluated['confidence_level'].iloc[0]):g} %" if len(evaluated) else "95 %"
    title = f"Reliability summary: {study}"
    out = [title, "=" * len(title), "", intro, ""]
    out += ["Limits exceeded", "-" * 15, ""]
    exceeded = evaluated[evaluated["n_exceed"] > 0].sort_values(["probability"], ascending=False)
    if exceeded.empty:
        out.append(f"**No sample exceeded any limit** ({evaluated['limit'].nunique()} limits, "
                   f"{evaluated['scenario'].nunique()} scenarios).")
    for _, r in exceeded.iterrows():
        out.append(f"- **{r['description']} > {r['threshold']}**, scenario ``{r['scenario']}``: "
                   f"P = {_p_text(r['probability'])}, {level} CI [{_p_text(r['ci_low'])}, "
                   f"{_p_text(r['ci_high'])}] ({int(r['n_exceed'])} of {int(r['n_samples'])} samples)")
    heading = f"P(exceed) per limit and scenario ({level} CI)"
    out += ["", heading, "-" * len(heading), ""]
    scenarios = sorted(evaluated["scenario"].unique())
    out += [".. list-table::", "   :header-rows: 1", "",
            "   * - limit"] + [f"     - {s}" for s in scenarios]
    for name, block in evaluated.groupby("limit", sort=False):
        first = block.iloc[0]
        out.append(f"   * - {name} > {first['threshold']}")
        by = block.set_index("scenario")
        for s in scenarios:
            if s not in by.index:
                out.append("     - n/a")
                continue
            r = by.loc[s]
            cell = (f"0 (< {_p_text(r['upper_one_sided'])})" if r["n_exceed"] == 0 else
                    f"{_p_text(r['probability'])} [{_p_text(r['ci_low'])}, {_p_text(r['ci_high'])}]")
            mark = "" if r["sufficient"] else " \\*"
            out.append(f"     - {cell}{mark}")
    out += ["", "0 (< u): no exceeding sample, one-sided upper bound u. "
            "\\* the number of samples did not suffice.", ""]
    out += ["Did the number of samples suffice?", "-" * 34, ""]
    short = evaluated[~evaluated["sufficient"].astype(bool)]
    if short.empty:
        out.append(f"**Yes**, for all {len(evaluated)} limit-scenario pairs.")
    else:
        need = short["status"].str.extract(r"about (\d+) effective samples")[0].dropna().astype(int)
        out.append(f"**No** for {len(short)} of {len(evaluated)} limit-scenario pairs"
                   + (f"; the criterion (limits.sufficiency) needs up to about {need.max()} "
                      "effective samples per scenario" if len(need) else "") + ".")
    skipped = assessment[~ok]
    if len(skipped):
        out += ["", f"Not evaluated: {', '.join(sorted(skipped['limit'].unique()))} (see the "
                "full summary)."]
    out += ["", f"Grades, sources and verdicts per limit: *{details}*."]
    return "\n".join(out) + "\n"


def main_page_rst(assessment: pd.DataFrame, *, details: str = "0. Summary") -> str:
    """A few lines for the report's main page (which must stay short to display whole):
    the limits exceeded with P and interval, and whether the number of samples sufficed."""
    ok = ~assessment["status"].str.startswith("not evaluated")
    evaluated = assessment[ok & (assessment["category"] == "limit")]
    level = f"{100 * float(evaluated['confidence_level'].iloc[0]):g} %" if len(evaluated) else "95 %"
    out = []
    exceeded = evaluated[evaluated["n_exceed"] > 0].sort_values("probability", ascending=False)
    if exceeded.empty:
        bound = evaluated.groupby("scenario")["upper_one_sided"].max()
        out.append(f"**Limits exceeded: none.** No sample of any scenario exceeded any of the "
                   f"{evaluated['limit'].nunique()} safety and comfort limits (one-sided {level} "
                   "upper bounds of P(exceed): " + ", ".join(
                       f"{s} < {_p_text(b)}" for s, b in bound.items()) + ").")
    else:
        out.append(f"**Limits exceeded** (P(max index > limit), {level} CI):")
        out.append("")
        for _, r in exceeded.iterrows():
            out.append(f"- **{r['description']} > {r['threshold']}**, scenario ``{r['scenario']}``: "
                       f"P = {_p_text(r['probability'])} [{_p_text(r['ci_low'])}, "
                       f"{_p_text(r['ci_high'])}] ({int(r['n_exceed'])} of {int(r['n_samples'])})")
    out.append("")
    short = evaluated[~evaluated["sufficient"].astype(bool)]
    if short.empty:
        out.append(f"**Did the samples suffice? Yes**, for all {len(evaluated)} limit-scenario pairs.")
    else:
        need = short["status"].str.extract(r"about (\d+) effective samples")[0].dropna().astype(int)
        out.append(f"**Did the samples suffice? No**, for {len(short)} of {len(evaluated)} "
                   "limit-scenario pairs" + (f": the criterion (limits.sufficiency) needs up to "
                                             f"about {need.max()} effective samples per scenario"
                                             if len(need) else "") + ".")
    out += ["", f"Table per limit and scenario, grades, sources: category *{details}*."]
    return "\n".join(out) + "\n"


def aggregate_study(extremes_paths: Sequence[str | os.PathLike[str]],
                    history_paths: Sequence[str | os.PathLike[str]], design: pd.DataFrame,
                    config: Mapping[str, Any], out: str | os.PathLike[str] = "results/study", *,
                    n_bins: int = 256) -> dict[str, Path]:
    """Write every study table, figure and report page (see the module docstring)."""
    out = Path(out)
    written: dict[str, Path] = {}
    study = str((config.get("study") or {}).get("name", "study"))
    extremes = stats_aggregate.read_extremes(extremes_paths)
    extremes = extremes.sort_values(["scenario", "sample_index"], kind="stable").reset_index(drop=True)
    expected = design[["scenario", "sample_index"]].astype({"scenario": str})
    got = extremes[["scenario", "sample_index"]].astype({"scenario": str})
    missing = expected.merge(got, how="left", indicator=True).query("_merge == 'left_only'")
    if len(missing):
        raise ValueError(f"{len(missing)} sample(s) of the design have no result, e.g. "
                         f"{missing.iloc[0]['scenario']}/{missing.iloc[0]['sample_index']}; rerun "
                         "the missing batches")
    written["extremes"] = io.write_table(extremes, out / "extremes.parquet", config=config,
                                         kind="study_extremes_all", n_files=len(extremes_paths))

    section = config.get("limits")
    limits, context = limits_from_config(section)
    settings = ReliabilitySettings.from_config(section)
    table = assess_limits(extremes, limits, context, settings)
    written["reliability"] = io.write_table(table, out / "reliability.parquet", config=config,
                                            kind="study_reliability")
    evaluable = table[~table["status"].str.startswith("not evaluated")]
    by_name = {lim.name: lim for lim in limits}
    curves: dict[str, list[pd.DataFrame]] = {}
    for scenario, block in evaluable.groupby("scenario", sort=True):
        curves[scenario] = [convergence_curve(extremes, by_name[name], context, settings, scenario)
                            for name in block["limit"]]
    long = []
    for scenario, cs in curves.items():
        for c in cs:
            long.append(c.assign(scenario=scenario, limit=c.attrs["limit"]))
    conv = pd.concat(long, ignore_index=True) if long else pd.DataFrame()
    written["convergence"] = io.write_table(conv, out / "convergence.parquet", config=config,
                                            kind="study_convergence")

    groups = scenario_groups(design)
    t1_scenarios = groups.get("fields") or sorted(extremes["scenario"].unique())
    table1 = stats_aggregate.standard_deviation_table(
        extremes[extremes["scenario"].isin(t1_scenarios)], scenarios=t1_scenarios).reset_index()
    written["table1"] = io.write_table(table1, out / "table1_std.parquet", config=config,
                                       kind="study_table1_std", scenarios=t1_scenarios)

    stats = stats_aggregate.aggregate_histories(history_paths, n_bins=n_bins)
    written["history"] = io.write_table(stats_aggregate.statistics_frame(stats),
                                        out / "history_statistics.parquet", config=config,
                                        kind="study_history_statistics", n_bins=n_bins)
    t1h = stats_aggregate.max_std_table({k: v for k, v in stats.items() if k[0] in t1_scenarios})
    written["table1_history"] = io.write_table(t1h.reset_index(), out / "table1_history_std.parquet",
                                               config=config, kind="study_table1_history_std")

    # report pages
    intro = summary_intro(extremes, design, study)
    rst = first_page_rst(table, title="Reliability summary", study=study, intro=" ")
    written["summary_rst"] = io.write_text(main_page_rst(table), out / "summary.rst")
    # summary.rst: a few lines for the report's main page; summary.html: the limit x scenario
    # matrix, then the full first page of ttbpipe.stats.report
    compact = compact_first_page_rst(table, study=study, intro=intro, details="Details below")
    full = rst.split("\n", 3)[3]   # without its title: the compact page has one
    written["summary_html"] = io.write_text(
        rst_to_html(compact + "\nDetails\n=======\n\n" + full, f"Reliability summary: {study}"),
        out / "report" / "summary.html")
    shown = table[["scenario", "limit", "threshold", "n_samples", "n_exceed", "probability",
                   "ci_low", "ci_high", "sufficient", "status", "source"]
                  ] if "probability" in table else table
    written["reliability_html"] = io.write_text(table_html(
        shown, "Exceedance probabilities per scenario and limit",
        "P(max index > limit) with two-sided confidence intervals; 'sufficient': the sample-size "
        "criterion of limits.sufficiency."), out / "report" / "reliability.html")
    written["table1_html"] = io.write_text(table_html(
        table1, "Table 1: standard deviation of each index per randomness condition",
        "Weighted standard deviation of the per-sample maxima (SI units in the index names); "
        "columns: scenarios."), out / "report" / "table1_std.html")
    written["table1_history_html"] = io.write_text(table_html(
        t1h.reset_index(), "Table 1 (time histories): maximum over position of the standard deviation",
        "As the paper reads Table 1: max of the std curve of each quantity (SI units)."),
        out / "report" / "table1_history_std.html")
    written["config_html"] = io.write_text(config_html(config), out / "report" / "configuration.html")

    written.update(_figures(extremes, stats, curves, groups, limits, context, out / "figures"))
    log.info("study aggregated: %d samples, %d scenarios, %d limit rows -> %s", len(extremes),
             extremes["scenario"].nunique(), len(table), out)
    return written


def _clear(folder: Path) -> None:
    """Figures of a previous run that this run would not rewrite must not linger."""
    if folder.is_dir():
        for f in folder.glob("*.png"):
            f.unlink()
    folder.mkdir(parents=True, exist_ok=True)


def _near(threshold: float | None, largest: float, ratio: float = 2.0) -> float | None:
    """The limit, when drawing it keeps the data readable (within ``ratio`` of the largest
    value); else None and the caller names it in the title."""
    if threshold is None or not np.isfinite(largest) or threshold <= ratio * largest:
        return threshold
    return None


def _off_scale_note(ax, column: str, threshold: float | None, shown: float | None) -> None:
    if threshold is not None and shown is None:
        factor, unit = plots.display_scale(column)
        unit = "" if unit in ("1", "-", "–") else f" {unit}"
        title = ax.get_title()
        ax.set_title((title + "; " if title else "") +
                     f"limit {threshold * factor:.3g}{unit} far above the data, not drawn",
                     fontsize=9)


def _figures(extremes, stats, curves, groups, limits, context, root: Path) -> dict[str, Path]:
    import matplotlib.pyplot as plt

    written: dict[str, Path] = {}
    for kind in FIGURE_KINDS:
        _clear(root / kind)
    thresholds = {lim.column: lim.threshold for lim in limits
                  if getattr(lim, "threshold", None) is not None and lim.category == "limit"}
    for scenario, cs in curves.items():
        fig = plots.plot_exceedance_convergence(cs, ncols=3)
        written[f"convergence_{scenario}"] = io.save_figure(fig, root / "convergence" / f"{scenario}.png")
        plt.close(fig)
    for group, scenarios in groups.items():
        for column in _indices_present(extremes):
            largest = float(extremes.loc[extremes["scenario"].isin(scenarios), column].max())
            shown = _near(thresholds.get(column), largest)
            fig = plots.plot_extreme_pdfs(extremes, column, scenarios=scenarios, threshold=shown)
            fig.axes[0].set_title(f"{group} scenarios", fontsize=9)
            _off_scale_note(fig.axes[0], column, thresholds.get(column), shown)
            written[f"pdf_{group}_{column}"] = io.save_figure(fig, root / "pdf" / f"{group}_{column}.png")
            plt.close(fig)
        for quantity in sorted({q for s, q in stats if s in scenarios}):
            fig = plots.plot_history_statistics(stats, quantity, scenarios=scenarios,
                                                band=(0.05, 0.95) if len(scenarios) == 1 else None)
            written[f"history_{group}_{quantity}"] = io.save_figure(
                fig, root / "history" / f"{group}_{quantity}.png")
            plt.close(fig)
    dated = sorted(s for s in extremes["scenario"].unique() if _DATE.match(str(s)))
    if len(dated) >= 2:
        for column in ENVELOPE_COLUMNS:
            if column in extremes.columns:
                env = stats_aggregate.forecast_envelope(extremes[extremes["scenario"].isin(dated)],
                                                        column, scenarios=dated)
                shown = _near(thresholds.get(column), float(env["upper"].max()))
                fig = plots.plot_forecast_envelope(env, threshold=shown)
                _off_scale_note(fig.axes[0], column, thresholds.get(column), shown)
                written[f"envelope_{column}"] = io.save_figure(fig, root / "envelope" / f"{column}.png")
                plt.close(fig)
    return written
