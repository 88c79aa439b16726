"""A study of a few hundred cheap samples through Snakemake: what the workflow costs per sample.

    python benchmarks/bench_study_workflow.py [--samples 200] [--batch-size 20] [--cores 2]
        [--keep DIR]

Copies the workflow of the source tree it runs in (the current directory: the repository root,
or an older revision exported by ``compare_revisions.py`` / ``run_all.py``, whose package comes
first on ``PYTHONPATH``) into a scratch folder without results, writes a study overlay and runs
``snakemake --cores N --configfile bench.yaml --until aggregate_study`` there. The study: one
fields condition (C2) of ``--samples`` samples, one trailer car at 300 km/h over one 32 m span
between 30 m approaches (0.8 s of run per sample), no TIPM scenarios; nothing assessed to the
standards where the tree knows ``assessment:`` (older trees have no such section, and 0.8 s
is too short for the standards' windows), so that old and new do the same work.

Figures: the wall time, the CPU time of every process (user + sys of the waited-for
children), the Snakemake jobs, the coupled runs' own wall time as the batches logged it
("coupled run done: X s wall"), and the rest of the CPU time (the workflow's overhead) as a
share. Timings only; compare side by side (``run_all.py`` does, against its baseline revision).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from study_job_times import coupled_run_seconds, jobs_of  # noqa: E402

# Generated or bulky: not part of the workflow a study needs.
SKIP = shutil.ignore_patterns("results", "logs", ".snakemake", ".git", "__pycache__",
                              "synthetic", "*.egg-info", "benchmarks", "tests", "docs")


def overlay(samples: int, batch_size: int, with_assessment: bool) -> str:
    text = f"""\
study:
  name: bench
  seed: 11
  scenarios:
    irregularity: {{enabled: false}}
    forecast: {{enabled: false}}
    fields: {{conditions: [C2], samples: {samples}}}
structure:
  layout: {{approach_length_m: 30.0, spans_m: [32.0], approach_track: ballasted,
            bridge_track: slab}}
simulation:
  train: {{composition: [trailer]}}
  end_x_m: 90.0
  batch_size: {batch_size}
"""
    if with_assessment:
        text += "assessment: {standard: []}\n"
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--batch-size", type=int, default=20)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--keep", type=Path, default=None,
                        help="run the study in this (new) folder and keep it, logs included")
    args = parser.parse_args()
    tree = Path.cwd()
    if not (tree / "Snakefile").is_file():
        raise SystemExit(f"{tree}: no Snakefile; run from a source tree's root")
    with tempfile.TemporaryDirectory(prefix="ttbpipe_study_bench_") as tmp:
        work = args.keep.resolve() if args.keep else Path(tmp) / "tree"
        shutil.copytree(tree, work, ignore=SKIP, symlinks=True)
        knows_assessment = re.search(r"(?m)^assessment:", (tree / "config/config.yaml").read_text())
        (work / "bench.yaml").write_text(overlay(args.samples, args.batch_size,
                                                 bool(knows_assessment)))
        cmd = [sys.executable, "-m", "snakemake", "--cores", str(args.cores), "--configfile",
               "bench.yaml", "--until", "aggregate_study"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=work, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        log = proc.stdout + proc.stderr
        if proc.returncode != 0:
            raise SystemExit(f"snakemake failed in {work}:\n{log[-4000:]}")
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        jobs = jobs_of(log)
        runs = 0.0
        for job in jobs:
            path = work / job["log"] if job["log"] else None
            if job["rule"] == "simulate_batch" and path and path.is_file():
                runs += coupled_run_seconds(path.read_text())
    print(f"study of {args.samples} samples ({args.batch_size} per batch) on {args.cores} cores in "
          f"{tree}: wall {wall:.1f} s, CPU {cpu:.1f} s, {len(jobs)} Snakemake jobs, coupled runs "
          f"{runs:.1f} s")
    print(f"FIGURE study_workflow_wall_s = {wall:.4g} s")
    print(f"FIGURE study_workflow_cpu_s = {cpu:.4g} s")
    print(f"FIGURE study_workflow_cpu_s_per_sample = {cpu / args.samples:.4g} s")
    print(f"FIGURE study_workflow_jobs = {len(jobs)} jobs")
    print(f"FIGURE study_workflow_coupled_runs_s = {runs:.4g} s")
    print(f"FIGURE study_workflow_overhead_share = {max(cpu - runs, 0.0) / cpu:.4g} 1")


if __name__ == "__main__":
    main()
