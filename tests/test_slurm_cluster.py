"""The SLURM profile and Dask on SLURM against a local run, on a real one-node Slurm.

Runs ``tools/slurm_check.sh`` (docs/cluster.md section 7): it starts a one-node Slurm on this
machine (slurmctld, slurmd, slurmdbd with a private MariaDB, munge; stopped again afterwards),
runs the small study ``tests/cluster/small_study.yaml`` locally, through ``--profile
profiles/slurm`` with the SLURM executor plugin, and with its batches on a ``dask_jobqueue``
SLURMCluster, and exits 0 only if every SLURM job Snakemake submitted is in ``sacct`` and
COMPLETED (as many as its sbatch submissions), every Dask batch job ran on the cluster's workers,
and ``tools/compare_results.py`` finds every file under ``results/`` of the SLURM and Dask runs
identical to the local run's (determinism: a sample's results do not depend on the scheduler).
This test checks that exit status and reads the job counts Slurm saw from the check's summary.

It needs root, Debian's ``slurm-wlm``, ``munge``, ``slurmdbd`` and ``mariadb-server`` and the
``cluster`` extra, and takes about 4 minutes; without them it is skipped with the reason.
``TTBPIPE_SKIP_SLURM_CHECK=1`` skips it; ``-m "not cluster and not validation"`` deselects it (a
command-line ``-m`` replaces the default ``-m "not validation"``).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DAEMONS = ("slurmctld", "slurmd", "slurmdbd", "munged", "mariadbd", "sinfo", "sacct", "sbatch")
MODULES = ("snakemake_executor_plugin_slurm", "dask_jobqueue")


def _missing() -> list[str]:
    missing = []
    if os.environ.get("TTBPIPE_SKIP_SLURM_CHECK"):
        missing.append("TTBPIPE_SKIP_SLURM_CHECK is set")
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        missing.append("root (the check starts the Slurm daemons)")
    missing += [exe for exe in DAEMONS
                if shutil.which(exe) is None and not os.access(f"/usr/sbin/{exe}", os.X_OK)]
    missing += [f"python module {m}" for m in MODULES if importlib.util.find_spec(m) is None]
    if not (REPO / ".git").exists():
        missing.append("a git checkout (the check copies its tracked files)")
    return missing


MISSING = _missing()


@pytest.mark.cluster
@pytest.mark.skipif(bool(MISSING), reason="one-node Slurm check needs: " + ", ".join(MISSING))
def test_slurm_profile_and_dask_on_slurm_match_the_local_run(tmp_path):
    check_dir = tmp_path / "slurm-check"
    proc = subprocess.run(
        ["bash", str(REPO / "tools" / "slurm_check.sh")], cwd=REPO,
        env={**os.environ, "PYTHON": sys.executable, "CHECK_DIR": str(check_dir)},
        capture_output=True, text=True, timeout=1800)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"tools/slurm_check.sh exit {proc.returncode}:\n{output[-6000:]}"
    summary = (check_dir / "summary.txt").read_text()
    print(summary)    # the check's wall times and job counts, shown with -rA or -s
    slurm = re.search(r"sacct: (\d+) jobs, (\d+) COMPLETED; sbatch submissions in the Snakemake "
                      r"log: (\d+)", summary)
    assert slurm, summary
    in_sacct, completed, submitted = map(int, slurm.groups())
    assert in_sacct == completed == submitted > 0
    assert "simulate_batch" in summary           # the batches ran as SLURM jobs
    dask = re.search(r"(\d+) of (\d+) batch jobs on the cluster", summary)
    assert dask and int(dask.group(1)) == int(dask.group(2)) > 0, summary
    assert "slurm_check: OK" in summary
