"""``ttbpipe stats-report --extremes FILES... [--histories FILES...] [--design FILES...]
--config CONFIG --out DIR``: the study's outputs from per-batch result files.

Runs :func:`ttbpipe.study.outputs.aggregate_study`, the pipeline of the workflow's rule
aggregate_study, and writes into ``DIR`` the same files the workflow writes into results/study
(:data:`ttbpipe.study.outputs.STUDY_FILES`: the tables, ``summary.rst``, ``report/*.html`` and
``figures/<kind>/``). ``--design``: the design tables of the samples (the workflow's
``design.parquet`` or its per-scenario ``designs/*.parquet``); without it, the minimal design read
off the extremes (:func:`ttbpipe.study.outputs.design_from_extremes`: scenario, sample index and
weight of every sample, the scenario kind from its label). Without ``--histories`` the history
table, its Table 1 and the history figures are left out. ``--config``: the study configuration
as given (its ``limits:`` and ``study.name`` are used; no section is required). The batch files'
provenance is not checked (files from anywhere are accepted); the workflow checks it.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--extremes", nargs="+", required=True, type=Path,
                        help="extremes Parquet files (one per batch)")
    parser.add_argument("--histories", nargs="*", default=[], type=Path,
                        help="long-format time-history Parquet files (one per batch)")
    parser.add_argument("--design", nargs="+", default=None, type=Path,
                        help="design Parquet file(s) of the samples (default: the minimal design "
                             "from the extremes' scenario, sample_index and weight)")
    parser.add_argument("--config", type=Path, default=None,
                        help="study configuration (YAML); its limits: section is used")
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--bins", type=int, default=256, help="histogram bins per grid point")
    parser.add_argument("--workers", type=int, default=1,
                        help="processes for the tail fits and the figures (results do not "
                             "depend on it)")


def run(args: argparse.Namespace) -> int:
    import matplotlib
    import yaml

    matplotlib.use("Agg")
    from .outputs import aggregate_study, read_design

    config = {}
    if args.config is not None:
        with open(args.config) as handle:
            config = yaml.safe_load(handle) or {}
    try:
        design = read_design(args.design) if args.design else None
        written = aggregate_study(args.extremes, args.histories, design, config, args.out,
                                  n_bins=args.bins, workers=args.workers)
    except ValueError as exc:  # ResultsSchemaError included: bad or missing result files
        log.error("%s", exc)
        return 1
    log.info("study outputs written to %s (%d files)", args.out, len(written))
    return 0
