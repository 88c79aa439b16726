"""Time the reliability table of a finished study (its tail fits with their goodness of fit).

    python benchmarks/study_reliability_time.py [--results results]
        [--configfile config/config.yaml] [--rounds 3]

Reads the batch files of a finished study under ``--results`` (``snakemake --cores 2`` first) and
builds its reliability table as :func:`ttbpipe.study.outputs.aggregate_study` does (the limits of
``limits:`` and the assessed indices, :func:`ttbpipe.stats.reliability.assess_limits` in one
process), ``--rounds`` times. Prints the wall time (median, minimum) and the number of tail
fits, with ``FIGURE`` lines for benchmarks/compare_revisions.py (not a ``bench_*`` script:
benchmarks/run_all.py has no finished study to read). Timings only.
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace
from pathlib import Path

import yaml

from ttbpipe.assessment.columns import assessed_indices
from ttbpipe.stats import streaming
from ttbpipe.stats.limits import limits_from_config
from ttbpipe.stats.reliability import ReliabilitySettings, assess_limits
from ttbpipe.study import outputs, utilisation


def study_limits(results: Path, configfile: Path):
    """(extremes, limits, context, settings) of the finished study under ``results`` as
    :func:`ttbpipe.study.outputs.aggregate_study` assesses them (also used by
    benchmarks/tail_profile_reference.py)."""
    paths = sorted((results / "study" / "batches").rglob("extremes_*.parquet"))
    if not paths:
        raise SystemExit(f"no batch files under {results}/study/batches: run the study first")
    extremes = streaming.read_extremes(paths).sort_values(
        ["scenario", "sample_index"], kind="stable").reset_index(drop=True)
    section = yaml.safe_load(configfile.read_text()).get("limits")
    raw_limits, context = limits_from_config(section)
    limits = utilisation.assessed_limits(assessed_indices(
        extremes.columns, outputs._assessment_metadata(paths)))
    limits += [replace(lim, category="raw") for lim in raw_limits] if limits else raw_limits
    return extremes, limits, context, ReliabilitySettings.from_config(section)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", type=Path, default=Path("results"))
    parser.add_argument("--configfile", type=Path, default=Path("config/config.yaml"))
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    extremes, limits, context, settings = study_limits(args.results, args.configfile)
    times = []
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        table = assess_limits(extremes, limits, context, settings, workers=1)
        times.append(time.perf_counter() - t0)
    fits = int(table["tail_model"].notna().sum()) if "tail_model" in table else -1
    print(f"{len(extremes)} samples, {len(table)} rows, {fits} tail fits: median "
          f"{statistics.median(times):.1f} s, min {min(times):.1f} s")
    print(f"FIGURE study_reliability_table_s = {statistics.median(times):.4g} s")


if __name__ == "__main__":
    main()
