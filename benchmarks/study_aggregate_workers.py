"""Wall time of a study's aggregation (tables, tail fits, figures, pages) with 1 and 2 workers.

    python benchmarks/study_aggregate_workers.py [--results results] [--rounds 2]

Reads the batch files of a finished study under ``--results`` (``study/batches``, the designs in
``study/design``; run ``snakemake --cores 2`` first) and runs
:func:`ttbpipe.study.outputs.aggregate_study` on them with ``workers`` 1 and 2, alternating
round by round, into scratch folders (the workflow's outputs are not touched; the batches'
provenance is not checked, so a study made by an earlier revision serves). Prints the wall time
of each and whether the two wrote identical tables. Timings only.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pandas as pd  # noqa: E402
import yaml  # noqa: E402

from ttbpipe import io  # noqa: E402
from ttbpipe.study.outputs import aggregate_study, read_design  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", type=Path, default=Path("results"))
    parser.add_argument("--configfile", type=Path, default=Path("config/config.yaml"))
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    batches = args.results / "study" / "batches"
    extremes = sorted(batches.rglob("extremes_*.parquet"))
    histories = sorted(batches.rglob("histories_*.parquet"))
    if not extremes:
        raise SystemExit(f"no batch files under {batches}: run the study first")
    design = read_design(sorted((args.results / "study" / "design").glob("*.parquet")))
    config = yaml.safe_load(args.configfile.read_text())
    times: dict[int, list[float]] = {1: [], 2: []}
    with tempfile.TemporaryDirectory() as scratch:
        for r in range(args.rounds):
            for workers in ((1, 2) if r % 2 == 0 else (2, 1)):
                t0 = time.perf_counter()
                aggregate_study(extremes, histories, design, config,
                                Path(scratch) / f"w{workers}", workers=workers)
                times[workers].append(time.perf_counter() - t0)
        same = all(io.read_table(Path(scratch) / "w1" / name).equals(
                       io.read_table(Path(scratch) / "w2" / name))
                   for name in ("reliability.parquet", "utilisation.parquet"))
    print(f"{len(extremes)} batch files, {len(pd.concat(map(io.read_table, extremes)))} samples")
    for workers, t in times.items():
        print(f"workers {workers}: median {statistics.median(t):6.1f} s  min {min(t):6.1f} s")
    print(f"identical reliability and utilisation tables: {same}")


if __name__ == "__main__":
    main()
