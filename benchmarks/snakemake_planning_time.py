"""Wall time of Snakemake's planning of a study: ``snakemake -n`` in a scratch copy of the tree.

    python benchmarks/snakemake_planning_time.py [--configfile config/config.yaml] [--rounds 3]
    python benchmarks/compare_revisions.py --rev <old> --rounds 5 \\
        --script benchmarks/snakemake_planning_time.py --figure snakemake_dry_run_s

Every ``snakemake`` call reads the Snakefile first, which validates the configuration and plans
the study (``ttbpipe.study.plan``) before any job starts: a dry run is that part alone. The
script copies the tree it runs in (its working directory: the Snakefile, ``workflow/``,
``config/``, ``profiles/`` and the inspection files shipped in ``resources/``, no results) into a
scratch folder, so that both trees of benchmarks/compare_revisions.py plan the same fresh study
with their own Snakefile and package (``PYTHONPATH``), and runs ``python -m snakemake -n --cores
2`` there ``--rounds`` times. Prints the wall time of each and a ``FIGURE`` line with the median.
Not a ``bench_*`` script (benchmarks/run_all.py does not run it). Timings only.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: What a fresh checkout plans a study from (generated inspection campaigns are not copied).
_COPIED = ("Snakefile", "workflow", "config", "profiles")


def _copy_tree(src: Path, dest: Path) -> None:
    for name in _COPIED:
        path = src / name
        if path.is_dir():
            shutil.copytree(path, dest / name, symlinks=True,
                            ignore=shutil.ignore_patterns("__pycache__", ".snakemake"))
        elif path.exists():
            shutil.copy2(path, dest / name)
    shipped = src / "resources"
    if shipped.is_dir():
        shutil.copytree(shipped, dest / "resources",
                        ignore=shutil.ignore_patterns("generated", "synthetic", "synthetic_case*"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", default="config/config.yaml")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    times = []
    with tempfile.TemporaryDirectory(prefix="ttbpipe_plan_") as scratch:
        _copy_tree(Path.cwd(), Path(scratch))
        for _ in range(args.rounds):
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--cores", "2",
                                   "--configfile", args.configfile], cwd=scratch,
                                  capture_output=True, text=True)
            times.append(time.perf_counter() - start)
            if proc.returncode != 0:
                raise SystemExit(f"snakemake -n failed in a copy of {Path.cwd()}:\n"
                                 f"{proc.stderr[-3000:]}")
    print("snakemake -n wall times: " + ", ".join(f"{t:.2f} s" for t in times))
    print(f"FIGURE snakemake_dry_run_s = {statistics.median(times):.4g} s")


if __name__ == "__main__":
    main()
