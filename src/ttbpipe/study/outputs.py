"""Every output of a study, from its batch files, design and configuration: one pipeline.

:func:`aggregate_study` is the only path to the study's tables, figures and report pages: the
workflow's rule ``aggregate_study`` (workflow/scripts/aggregate_study.py) and the command
``ttbpipe stats-report`` (:mod:`ttbpipe.study.cli_report`) both call it. It reads the batch files
one at a time (the time histories through :func:`ttbpipe.stats.streaming.aggregate_histories`,
bounded memory; the extremes are one small row per sample) and writes, under ``out``
(results/study by default), the files of :data:`STUDY_FILES`:

* ``design.parquet``: the design the outputs were made from;
* ``extremes.parquet``: every sample's extremes, sorted by scenario and sample index;
* ``history_statistics.parquet``: weighted mean, std and percentiles against position;
* ``utilisation.parquet``: per scenario and assessed index (the standards of ``assessment:``,
  docs/assessment.md) the median, 95th percentile and maximum utilisation = index / limit, the
  sample that reached the maximum, the limit and P(utilisation > 1) with its interval
  (:mod:`ttbpipe.study.utilisation`);
* ``reliability.parquet``: exceedance probability, interval and verdict per (scenario, limit):
  the assessed limits (utilisation > 1, categories ``limit`` and ``grade``) and, as category
  ``raw``, the raw-peak thresholds of ``limits:`` (:mod:`ttbpipe.stats.limits`; not code
  checks: the standards evaluate processed indices; without assessed columns they are the
  limits);
* ``convergence.parquet``: the convergence curves of every (scenario, limit);
* ``table1_std.parquet``: the paper's Table 1, weighted std of each index per randomness
  condition (the fields scenarios; every scenario when there is none); ``table1_history_std.parquet``:
  the maximum over position of the std curve of each time-history quantity;
* ``summary.rst`` / ``report/summary.html``: the report's first page; ``report/*.html``: the
  tables and the configuration as report pages (their text: :mod:`ttbpipe.study.report_pages`);
* ``figures/<kind>/*.png``: utilisation per report section (the margins to the limits),
  convergence per scenario, PDFs of extremes (Figs. 15-16), history
  mean/std (Figs. 10-14), forecast envelopes (Fig. 17).

Without a design (``design=None``, the command line without ``--design``) the outputs are made
from :func:`design_from_extremes`, the minimal design read off the extremes. Without time-history
files the history table, its Table 1 page and the history figures are not written.
Columns of every table: docs/studies.md.
"""

from __future__ import annotations

import functools
import logging
import os
import re
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from .. import io
from ..parallel import process_map
from ..dates import DATE_PATTERN
from ..stats import plots, streaming, tables
from ..assessment.columns import assessed_indices, shared_row_metadata
from ..stats.limits import limits_from_config
from ..stats.reliability import ReliabilitySettings, assess_limits, convergence_curve
from ..stats.schema import RESPONSE_INDICES
from . import report_pages, utilisation
from .design import DESIGN_COLUMNS, FIELD_CONDITIONS, MC_IRREGULARITY, SINGLE

log = logging.getLogger(__name__)

_DATE = re.compile(rf"^{DATE_PATTERN}$")  # a dated (campaign) scenario
_FORECAST_LEVEL = re.compile(rf"^{DATE_PATTERN}_p[0-9.]+$")  # <target date>_p<level>
#: Indices of the paper's Fig. 17 (long-term behaviour), when present.
ENVELOPE_COLUMNS = ("max_deck_vertical_acc_m_s2", "max_deck_lateral_acc_m_s2",
                    "max_carbody_lateral_acc_m_s2", "max_wheel_vertical_force_N",
                    "max_wheel_lateral_force_N")
FIGURE_KINDS = ("utilisation", "convergence", "pdf", "history", "envelope")

#: Every output of :func:`aggregate_study`, relative to its output folder, keyed by the output
#: names of the rule aggregate_study (workflow/rules/report.smk lists the same paths; the
#: workflow script checks them with :func:`output_folder`). The figure entries are folders.
STUDY_FILES: dict[str, str] = {
    "design": "design.parquet",
    "extremes": "extremes.parquet",
    "history": "history_statistics.parquet",
    "reliability": "reliability.parquet",
    "utilisation": "utilisation.parquet",
    "convergence": "convergence.parquet",
    "table1": "table1_std.parquet",
    "table1_history": "table1_history_std.parquet",
    "summary_rst": "summary.rst",
    "summary": "report/summary.html",
    "reliability_html": "report/reliability.html",
    "utilisation_html": "report/utilisation.html",
    "table1_html": "report/table1_std.html",
    "table1_history_html": "report/table1_history_std.html",
    "configuration": "report/configuration.html",
    **{f"{kind}_figures": f"figures/{kind}" for kind in FIGURE_KINDS},
}


def output_folder(outputs: Mapping[str, str | os.PathLike[str]]) -> Path:
    """The folder of a set of named outputs laid out as :data:`STUDY_FILES` (the rule's
    ``output:``); an output at another place, or a missing one, is an error naming it."""
    folder = Path(outputs["extremes"]).parent
    wrong = [f"{name}: {outputs.get(name)} (expected {folder / relative})"
             for name, relative in STUDY_FILES.items()
             if name not in outputs or Path(outputs[name]) != folder / relative]
    if wrong:
        raise ValueError("the study outputs are not laid out as ttbpipe.study.outputs.STUDY_FILES: "
                         + "; ".join(wrong))
    return folder


def read_design(paths: Sequence[str | os.PathLike[str]]) -> pd.DataFrame:
    """The study design from its per-scenario design tables (rule study_design), concatenated."""
    return pd.concat([io.read_table(p) for p in paths], ignore_index=True)


def scenario_kind_from_label(label: str) -> str:
    """The kind of a scenario from its label alone (for :func:`design_from_extremes`).

    The labels of ttbpipe.study.design: ``C1`` .. ``C4``, ``all`` -> fields; ``<condition>_mc``
    -> fields_mc; ``mc`` -> irregularity_mc; ``single`` -> single; ``<date>_p<level>`` ->
    forecast; any other label (a campaign date, a forecast target date, a label of one's own)
    -> irregularity. A forecast at one level has a plain date as its label and so reads as
    irregularity; both are drawn in the same figures.
    """
    label = str(label)
    if label in FIELD_CONDITIONS:
        return "fields"
    if label.endswith("_mc") and label[:-len("_mc")] in FIELD_CONDITIONS:
        return "fields_mc"
    if label == MC_IRREGULARITY:
        return "irregularity_mc"
    if label == SINGLE:
        return SINGLE
    if _FORECAST_LEVEL.match(label):
        return "forecast"
    return "irregularity"


def design_from_extremes(extremes: pd.DataFrame) -> pd.DataFrame:
    """The minimal design of a set of results: the columns of
    :data:`ttbpipe.study.design.DESIGN_COLUMNS`, with ``scenario``, ``sample_index``, ``weight``
    (and ``seed_entropy`` when present) from the extremes, ``kind`` from the label
    (:func:`scenario_kind_from_label`), ``condition`` the fields condition (else empty) and
    ``profile_index`` -1 (unknown)."""
    kinds = extremes["scenario"].astype(str).map(scenario_kind_from_label)
    design = pd.DataFrame({
        "scenario": extremes["scenario"].astype(str).to_numpy(),
        "kind": kinds.to_numpy(),
        "sample_index": extremes["sample_index"].to_numpy(dtype=np.int64),
        "weight": extremes["weight"].to_numpy(dtype=float),
        "profile_index": np.full(len(extremes), -1, dtype=np.int64),
        "condition": [s.removesuffix("_mc") if k in ("fields", "fields_mc") else ""
                      for s, k in zip(extremes["scenario"].astype(str), kinds)],
        "seed_entropy": (extremes["seed_entropy"].astype(str).to_numpy()
                         if "seed_entropy" in extremes else ""),
    })
    return design[list(DESIGN_COLUMNS)]


def scenario_groups(design: pd.DataFrame) -> dict[str, list[str]]:
    """Scenarios drawn together: 'irregularity' (campaign, single excitation, forecasts, Monte
    Carlo irregularity) and 'fields' (randomness conditions, KLE and plain Monte Carlo)."""
    kinds = design.drop_duplicates("scenario").set_index("scenario")["kind"]
    groups = {"irregularity": sorted(s for s, k in kinds.items()
                                     if k in ("irregularity", "forecast", "single", "irregularity_mc")),
              "fields": sorted(s for s, k in kinds.items() if k in ("fields", "fields_mc"))}
    return {g: s for g, s in groups.items() if s}


def _indices_present(extremes: pd.DataFrame) -> list[str]:
    return [c for c in RESPONSE_INDICES if c in extremes.columns]


def aggregate_study(extremes_paths: Sequence[str | os.PathLike[str]],
                    history_paths: Sequence[str | os.PathLike[str]],
                    design: pd.DataFrame | None, config: Mapping[str, Any],
                    out: str | os.PathLike[str] = "results/study", *,
                    settings: Mapping[str, Mapping[str, Any]] | None = None,
                    n_bins: int = 256, workers: int = 1) -> dict[str, Path]:
    """Write every study table, figure and report page (see the module docstring).

    ``settings`` (the workflow's per-scenario batch settings, ttbpipe.study.plan.batch_settings):
    first check every batch file's provenance against them
    (:func:`ttbpipe.study.batch.verify_batches`: a stale or unreadable batch stops here, named).
    ``design=None``: the minimal design of the extremes (:func:`design_from_extremes`).
    Returns the path of every file written, keyed as :data:`STUDY_FILES` (figures one by one).
    ``workers``: processes for the tail fits and the figures (:mod:`ttbpipe.parallel`; the
    results do not depend on it).
    """
    out = Path(out)
    paths = {name: out / relative for name, relative in STUDY_FILES.items()}
    written: dict[str, Path] = {}
    study = str((config.get("study") or {}).get("name", "study"))
    provenance: dict[str, dict] = {}
    if settings is not None:
        if design is None:
            raise ValueError("checking the batches' provenance (settings=) needs their design")
        from .batch import verify_batches  # here: ttbpipe.study.batch imports the simulation

        provenance = verify_batches([*extremes_paths, *history_paths], design, settings)
    extremes = streaming.read_extremes(extremes_paths)
    extremes = extremes.sort_values(["scenario", "sample_index"], kind="stable").reset_index(drop=True)
    if design is None:
        design = design_from_extremes(extremes)
    written["design"] = io.write_table(design, paths["design"], config=config, kind="study_design")
    expected = design[["scenario", "sample_index"]].astype({"scenario": str})
    got = extremes[["scenario", "sample_index"]].astype({"scenario": str})
    missing = expected.merge(got, how="left", indicator=True).query("_merge == 'left_only'")
    if len(missing):
        raise ValueError(f"{len(missing)} sample(s) of the design have no result, e.g. "
                         f"{missing.iloc[0]['scenario']}/{missing.iloc[0]['sample_index']}; rerun "
                         "the missing batches")
    written["extremes"] = io.write_table(extremes, paths["extremes"], config=config,
                                         kind="study_extremes_all", n_files=len(extremes_paths))

    section = config.get("limits")
    raw_limits, context = limits_from_config(section)
    indices = assessed_indices(extremes.columns, _assessment_metadata(extremes_paths, provenance))
    limits = utilisation.assessed_limits(indices)
    if limits:   # the raw-peak thresholds stay in the table, marked as such
        raw_limits = [replace(lim, category="raw") for lim in raw_limits]
    limits = limits + raw_limits
    reliability = ReliabilitySettings.from_config(section)
    table = assess_limits(extremes, limits, context, reliability, workers=workers)
    written["reliability"] = io.write_table(table, paths["reliability"], config=config,
                                            kind="study_reliability")
    util = utilisation.utilisation_table(extremes, indices, table)
    written["utilisation"] = io.write_table(util, paths["utilisation"], config=config,
                                            kind="study_utilisation")
    evaluable = table[~table["status"].str.startswith("not evaluated")
                      & (table["category"] != "raw")]
    by_name = {lim.name: lim for lim in limits}
    curves: dict[str, list[pd.DataFrame]] = {}
    for scenario, block in evaluable.groupby("scenario", sort=True):
        curves[scenario] = [convergence_curve(extremes, by_name[name], context, reliability,
                                              scenario)
                            for name in block["limit"]]
    long = []
    for scenario, cs in curves.items():
        for c in cs:
            long.append(c.assign(scenario=scenario, limit=c.attrs["limit"]))
    conv = pd.concat(long, ignore_index=True) if long else pd.DataFrame()
    written["convergence"] = io.write_table(conv, paths["convergence"], config=config,
                                            kind="study_convergence")

    groups = scenario_groups(design)
    t1_scenarios = groups.get("fields") or sorted(extremes["scenario"].unique())
    table1 = tables.standard_deviation_table(
        extremes[extremes["scenario"].isin(t1_scenarios)], scenarios=t1_scenarios).reset_index()
    written["table1"] = io.write_table(table1, paths["table1"], config=config,
                                       kind="study_table1_std", scenarios=t1_scenarios)

    stats: dict = {}
    t1h = None
    if history_paths:
        stats = streaming.aggregate_histories(history_paths, n_bins=n_bins)
        written["history"] = io.write_table(streaming.statistics_frame(stats), paths["history"],
                                            config=config, kind="study_history_statistics",
                                            n_bins=n_bins)
        t1h = tables.max_std_table({k: v for k, v in stats.items()
                                    if k[0] in t1_scenarios}).reset_index()
        written["table1_history"] = io.write_table(t1h, paths["table1_history"], config=config,
                                                   kind="study_table1_history_std")
    else:
        log.info("no time-history files: %s, %s and the history figures are not written",
                 STUDY_FILES["history"], STUDY_FILES["table1_history"])

    summary = report_pages.summarize(table, study=study, extremes=extremes, design=design,
                                     utilisation=util)
    for name, text in report_pages.study_pages(summary, config, table1, t1h).items():
        written[name] = io.write_text(text, paths[name])

    tasks = _figure_tasks(extremes, stats, curves, groups, raw_limits, context, out / "figures")
    tasks += _utilisation_figure_tasks(extremes, indices, out / "figures" / "utilisation")
    written.update(_draw_figures(tasks, workers))
    log.info("study aggregated: %d samples, %d scenarios, %d limit rows -> %s", len(extremes),
             extremes["scenario"].nunique(), len(table), out)
    return written


def _assessment_metadata(paths: Sequence[str | os.PathLike[str]],
                         provenance: Mapping[str, dict] | None = None) -> list[dict]:
    """The assessed rows' metadata (clause, category, limit source) of the batches' provenance
    (:func:`ttbpipe.study.batch.simulate_batch` keeps it there), the same in every batch
    (:func:`~ttbpipe.assessment.columns.shared_row_metadata` logs any that differs).
    ``provenance``: the documents already read, by path (the rest are read here)."""
    known = provenance or {}
    return shared_row_metadata(
        (str(path), (known.get(str(path)) or io.read_provenance(path)).get("assessment"))
        for path in paths)


def _utilisation_figure_tasks(extremes, indices, folder: Path) -> list[tuple]:
    return [(f"utilisation_{utilisation.figure_name(section)}",
             folder / f"{utilisation.figure_name(section)}.png",
             functools.partial(utilisation.plot_section, extremes, indices, section))
            for section in utilisation.sections_present(indices)]


#: The figure tasks ``(name, path, build)`` of the running aggregation: module level, so that
#: the forked workers of :func:`ttbpipe.parallel.process_map` see them.
_FIGURE_TASKS: list[tuple] = []


def _draw_figure(i: int) -> tuple[str, Path]:
    import matplotlib.pyplot as plt

    name, path, build = _FIGURE_TASKS[i]
    fig = build()
    try:
        return name, io.save_figure(fig, path)
    finally:
        plt.close(fig)


def _draw_figures(tasks: list[tuple], workers: int) -> dict[str, Path]:
    """Draw and save every figure task (in ``workers`` processes): {name: path}."""
    _FIGURE_TASKS[:] = tasks
    try:
        return dict(process_map(_draw_figure, range(len(tasks)), workers))
    finally:
        _FIGURE_TASKS.clear()


def _distinct_curves(curves: list[pd.DataFrame]) -> list[pd.DataFrame]:
    """The convergence curves worth a panel: every limit with an exceeding sample, and one panel
    for all limits without any (their estimate is 0 and their upper bound depends only on the
    number and weights of the samples, so their panels would be identical). None for a scenario
    of one sample (nothing converges)."""
    if not curves or len(curves[0]) < 2:
        return []
    hit = [c for c in curves if (c["n_exceed"] > 0).any()]
    zero = [c for c in curves if not (c["n_exceed"] > 0).any()]
    if zero:
        shared = zero[0].copy()
        shared.attrs = {**zero[0].attrs, "limit": "no_exceedance",
                        "description": (f"any of the {len(zero)} limits without an exceeding "
                                        "sample" if len(zero) > 1 else zero[0].attrs["description"]),
                        "threshold": "its limit" if len(zero) > 1 else zero[0].attrs["threshold"]}
        hit.append(shared)
    return hit


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


def _pdf_figure(extremes, column, scenarios, group, threshold, shown):
    fig = plots.plot_extreme_pdfs(extremes, column, scenarios=scenarios, threshold=shown)
    fig.axes[0].set_title(f"{group} scenarios", fontsize=9)
    _off_scale_note(fig.axes[0], column, threshold, shown)
    return fig


def _envelope_figure(env, column, threshold, shown):
    fig = plots.plot_forecast_envelope(env, threshold=shown)
    _off_scale_note(fig.axes[0], column, threshold, shown)
    return fig


def _figure_tasks(extremes, stats, curves, groups, limits, context, root: Path) -> list[tuple]:
    """The study's figures as tasks ``(name, path, build)``; their folders emptied first."""
    tasks: list[tuple] = []
    for kind in FIGURE_KINDS:
        _clear(root / kind)
    thresholds = {lim.column: lim.threshold for lim in limits
                  if getattr(lim, "threshold", None) is not None and lim.category == "limit"}
    for scenario, cs in curves.items():
        cs = _distinct_curves(cs)
        if not cs:
            continue
        tasks.append((f"convergence_{scenario}", root / "convergence" / f"{scenario}.png",
                      functools.partial(plots.plot_exceedance_convergence, cs,
                                        ncols=min(3, len(cs)))))
    for group, scenarios in groups.items():
        for column in _indices_present(extremes):
            largest = float(extremes.loc[extremes["scenario"].isin(scenarios), column].max())
            shown = _near(thresholds.get(column), largest)
            tasks.append((f"pdf_{group}_{column}", root / "pdf" / f"{group}_{column}.png",
                          functools.partial(_pdf_figure, extremes, column, scenarios, group,
                                            thresholds.get(column), shown)))
        for quantity in sorted({q for s, q in stats if s in scenarios}):
            tasks.append((f"history_{group}_{quantity}", root / "history" / f"{group}_{quantity}.png",
                          functools.partial(plots.plot_history_statistics, stats, quantity,
                                            scenarios=scenarios,
                                            band=(0.05, 0.95) if len(scenarios) == 1 else None)))
    dated = sorted(s for s in extremes["scenario"].unique() if _DATE.match(str(s)))
    if len(dated) >= 2:
        for column in ENVELOPE_COLUMNS:
            if column in extremes.columns:
                env = tables.forecast_envelope(extremes[extremes["scenario"].isin(dated)],
                                               column, scenarios=dated)
                shown = _near(thresholds.get(column), float(env["upper"].max()))
                tasks.append((f"envelope_{column}", root / "envelope" / f"{column}.png",
                              functools.partial(_envelope_figure, env, column,
                                                thresholds.get(column), shown)))
    return tasks
