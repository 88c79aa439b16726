"""The study's one output pipeline (ttbpipe.study.outputs) and its report pages
(ttbpipe.study.report_pages).

What is checked and against what:

* the rule aggregate_study lists exactly the files of STUDY_FILES (the rule parsed by Snakemake
  itself, through ttbpipe.workflow.mock_snakemake, in a scratch copy of the repository);
* `ttbpipe stats-report --design --workers 2` writes the same files with the same content as
  the pipeline the workflow calls in one process (exact table equality, identical pages,
  byte-identical figures: the tail fits and figures of two worker processes are those of one);
* the minimal design of the command line follows the scenario labels of ttbpipe.study.design;
* the summary pages state one count of limit-scenario pairs and one text per probability: the
  count is taken from the assessment table independently of the summary object, the
  probability is 1 of 2000 samples (binomial k/N = 5e-4 exactly, below the 1e-3 switch of the
  formatter, where the pages used to differ).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from ttbpipe import io
from ttbpipe.stats import limits as L
from ttbpipe.stats.reliability import assess_limits
from ttbpipe.stats.schema import example_extremes, example_histories
from ttbpipe.study import report_pages as R
from ttbpipe.study.design import DESIGN_COLUMNS
from ttbpipe.study.outputs import (STUDY_FILES, aggregate_study, design_from_extremes,
                                   output_folder, scenario_kind_from_label)

KEEP = ["sample_index", "scenario", "weight", "seed_entropy", "train_speed_m_s",
        "static_wheel_load_N", "max_derailment_coefficient", "max_deck_vertical_acc_m_s2",
        "max_wheel_unloading_ratio"]


def test_rule_outputs_are_the_pipeline_files(tmp_path):
    from test_workflow import _copy_repository

    from ttbpipe.workflow import mock_snakemake

    _copy_repository(tmp_path)
    job = mock_snakemake("aggregate_study", root=tmp_path)
    outputs = dict(job.output.items())
    folder = Path(job.config["results_dir"]) / "study"
    assert outputs == {name: str(folder / relative) for name, relative in STUDY_FILES.items()}
    assert output_folder(outputs) == folder
    moved = {**outputs, "summary": str(folder / "summary.html")}
    expected = r"summary: .*/summary.html \(expected .*/report/summary.html\)"
    with pytest.raises(ValueError, match=expected):
        output_folder(moved)


def _synthetic_study(root: Path):
    """Two batches per scenario: a weighted campaign, a forecast and a fields condition."""
    spec = [("2024-01-15", "irregularity", True), ("2024-07-15", "forecast", True),
            ("C1", "fields", False)]
    rows, ext, hist = [], [], []
    for k, (scenario, kind, weighted) in enumerate(spec):
        n = 40
        w = np.random.default_rng(k).uniform(0.5, 1.5, n) if weighted else np.ones(n)
        rows.append(pd.DataFrame({"scenario": scenario, "kind": kind, "sample_index": np.arange(n),
                                  "weight": w, "profile_index": -1,
                                  "condition": scenario if kind == "fields" else "",
                                  "seed_entropy": ""}))
        for first in (0, 20):
            index = np.arange(first, first + 20)
            ext.append(io.write_table(
                example_extremes(index, scenario, seed=k, weights=w[index])[KEEP],
                root / scenario / f"extremes_{first:05d}.parquet"))
            hist.append(io.write_table(
                example_histories(index, scenario, seed=k, weights=w[index], n_points=30,
                                  abscissa="position_m"),
                root / scenario / f"histories_{first:05d}.parquet"))
    design = pd.concat(rows, ignore_index=True)
    io.write_table(design, root / "design.parquet")
    return ext, hist, design


def test_stats_report_command_writes_what_the_workflow_pipeline_writes(tmp_path):
    from ttbpipe.cli import main

    ext, hist, design = _synthetic_study(tmp_path / "batches")
    config_path = tmp_path / "study.yaml"
    config_path.write_text(yaml.safe_dump(
        {"study": {"name": "synthetic"},
         "limits": {"thresholds": {"derailment_coefficient": 0.3}}}, sort_keys=False))
    config = yaml.safe_load(config_path.read_text())
    pipeline, command = tmp_path / "pipeline", tmp_path / "command"
    written = aggregate_study(ext, hist, design, config, pipeline)
    assert main(["stats-report", "--extremes", *map(str, ext), "--histories", *map(str, hist),
                 "--design", str(tmp_path / "batches" / "design.parquet"),
                 "--config", str(config_path), "--out", str(command), "--workers", "2"]) == 0

    files = sorted(p.relative_to(pipeline) for p in pipeline.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(command) for p in command.rglob("*") if p.is_file())
    for name, relative in STUDY_FILES.items():
        assert (pipeline / relative).exists(), name
        if not relative.startswith("figures/"):
            assert written[name] == pipeline / relative
    for relative in files:
        if relative.suffix == ".parquet":
            pd.testing.assert_frame_equal(io.read_table(pipeline / relative),
                                          io.read_table(command / relative), check_exact=True)
        elif relative.suffix in (".rst", ".html"):
            assert (pipeline / relative).read_text() == (command / relative).read_text(), relative
        elif relative.suffix == ".png":   # drawn in two worker processes by the command
            assert (pipeline / relative).read_bytes() == (command / relative).read_bytes(), relative
    pd.testing.assert_frame_equal(io.read_table(pipeline / "design.parquet"), design)
    assert {p.parent.name for p in pipeline.rglob("*.png")} == {"convergence", "pdf", "history",
                                                                 "envelope"}


def test_minimal_design_follows_the_scenario_labels():
    labels = {"C1": "fields", "all": "fields", "C3_mc": "fields_mc", "mc": "irregularity_mc",
              "single": "single", "2024-01-15": "irregularity", "2024-07-15_p0.05": "forecast",
              "own": "irregularity"}
    assert {label: scenario_kind_from_label(label) for label in labels} == labels
    extremes = pd.concat([example_extremes(range(3), s, weights=[0.2, 0.3, 0.5])
                          for s in ("2024-01-15", "C3_mc")], ignore_index=True)
    design = design_from_extremes(extremes)
    assert list(design.columns) == list(DESIGN_COLUMNS)
    assert list(design["kind"]) == ["irregularity"] * 3 + ["fields_mc"] * 3
    assert list(design["condition"]) == [""] * 3 + ["C3"] * 3
    np.testing.assert_array_equal(design["sample_index"], extremes["sample_index"])
    np.testing.assert_array_equal(design["weight"], extremes["weight"])
    assert list(design["seed_entropy"]) == list(extremes["seed_entropy"])


def test_summary_pages_state_one_count_and_one_probability_text():
    ext = example_extremes(range(2000), "C1", seed=4, spread=0.2)
    column = "max_derailment_coefficient"
    threshold = float(np.sort(ext[column])[-2])  # exactly one sample above: P = 1/2000
    limits, context = L.limits_from_config({"thresholds": {"derailment_coefficient": threshold}})
    chosen = [lim for lim in limits if lim.category == "grade"
              or lim.name in ("deck_vertical_acc", "derailment_coefficient")]
    table = assess_limits(ext, chosen, context)
    n_limit_pairs = int(((table["category"] == "limit")
                         & ~table["status"].str.startswith("not evaluated")).sum())
    assert (table["category"] == "grade").any() and n_limit_pairs >= 2

    summary = R.summarize(table, study="demo", extremes=ext,
                          design=design_from_extremes(ext))
    main = R.main_page_rst(summary)
    compact = R.compact_page_rst(summary, intro=R.intro_rst(summary))
    full = R.first_page_rst(summary)
    for page in (main, compact, full):
        counts = {int(n) for n in re.findall(r"(\d+) (?:evaluated )?limit-scenario pairs", page)}
        assert counts == {n_limit_pairs}, page
        assert "P = 5.00e-04" in page, page
    assert "2000 coupled train-track-bridge runs in 1 scenarios" in compact
