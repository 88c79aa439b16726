"""End-to-end checks of the Snakemake workflow on a small study in a scratch copy of the repo.

What it shows: the DAG runs from synthetic inspection data to the first figure; every table
carries provenance; and adding one inspection campaign reruns only its year's preparation job and
what genuinely depends on it.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from ttbpipe.io import read_provenance

REPO = Path(__file__).resolve().parents[1]

SMALL_STUDY = """\
inspections:
  directory: resources/inspections
  synthetic:
    enabled: true
    directory: resources/inspections/synthetic
    spectrum: tbt3352
    length_km: 2.0
    campaigns: 3
    start_date: "2023-12-15"   # two calendar years: two preparation jobs
    interval_months: 1
    seed: 7
study:
  seed: 1
  scenarios:
    fields: {conditions: [C1], samples: 2}   # random rail: exercises the per-sample step check
simulation:
  end_x_m: 100.0
  batch_size: 10
assessment:
  standard: []   # 0.2 m of run: too short for the standards' windows (tests/test_study_batch.py)
"""


def _copy_repository(dest: Path) -> None:
    listed = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"], cwd=REPO, check=True,
        capture_output=True, text=True).stdout.split("\n")
    for name in filter(None, listed):
        if name.startswith(("results/", "resources/inspections/")) or name.startswith("."):
            continue
        src = REPO / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    (dest / "resources" / "inspections").mkdir(parents=True, exist_ok=True)
    profiles = dest / "profiles"
    if not profiles.exists():
        profiles.symlink_to("workflow/profiles")


def _jobs(log: str) -> list[tuple[str, str]]:
    """(rule, wildcards) of every job a Snakemake log (dry or real run) lists, sorted."""
    jobs = []
    for block in re.split(r"(?m)^(?=(?:local)?(?:rule|checkpoint) \w+:$)", log):
        head = re.match(r"(?:local)?(?:rule|checkpoint) (\w+):$", block, flags=re.M)
        if head:
            wildcards = re.search(r"(?m)^\s+wildcards: (.*)$", block)
            jobs.append((head.group(1), wildcards.group(1) if wildcards else ""))
    return sorted(jobs)


def _snakemake(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "snakemake", "--cores", "2", "--configfile", "small.yaml", *args]
    result = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if result.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed:\n{result.stdout[-3000:]}\n{result.stderr[-5000:]}")
    return result


@pytest.mark.parametrize("profile", ["workflow/profiles/default/config.yaml",
                                     "profiles/slurm/config.yaml"])
def test_profiles_do_not_keep_snakemake_alive_after_its_last_job(profile):
    """Snakemake 9.27 starts a non-daemon ``threading.Timer`` of the ``max-jobs-per-timespan``
    timespan after every job selection (``JobScheduler._schedule_reevalutation``), and the
    interpreter waits for it before exiting: with ``1000/1m`` each call outlived its last job by
    up to a minute (measured 65.8 s for a 6.5 s run; the test suite took 23 min instead of 16).
    A profile may set the option only with Snakemake's default timespan or less."""
    import yaml
    from snakemake.settings.types import MaxJobsPerTimespan

    settings = yaml.safe_load((REPO / profile).read_text())
    value = settings.get("max-jobs-per-timespan")
    if value is not None:
        assert MaxJobsPerTimespan.parse_choice(str(value)).timespan <= 1, (
            f"{profile}: max-jobs-per-timespan {value}: every snakemake call would stay alive "
            "that long after its last job")


#: Modules the Snakefile's own process must not load: it validates the configuration and plans
#: the study (every ``snakemake`` call, dry runs included, pays for what it imports), while the
#: jobs load what they compute with. scipy.stats and numba cost about 1 s and 0.5 s, the
#: structure package (SciPy's sparse solvers) and Matplotlib more.
PLANNING_MUST_NOT_IMPORT = ("numba", "scipy.stats", "scipy.sparse.linalg", "scipy.integrate",
                            "scipy.signal", "matplotlib", "ttbpipe.structure", "ttbpipe.tipm.stages",
                            "ttbpipe.reliability.subset")


def test_planning_the_default_study_loads_no_compute_modules(tmp_path):
    """``snakemake -n`` on the shipped default study in a fresh copy (no campaign written yet,
    so the plan also counts the synthetic campaigns' rows): its process imports none of
    :data:`PLANNING_MUST_NOT_IMPORT` (``python -X importtime`` lists every module it loads).
    Measured: the dry run of a finished default study took 5.5-5.9 s with them, the Snakemake
    call's start-up on every run (docs/performance.md, "The Snakefile's imports")."""
    _copy_repository(tmp_path)
    result = subprocess.run([sys.executable, "-X", "importtime", "-m", "snakemake", "-n",
                             "--cores", "1"], cwd=tmp_path, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "simulate_batch" in result.stdout, result.stdout[-3000:]
    loaded = {line.rsplit("|", 1)[1].strip() for line in result.stderr.splitlines()
              if line.startswith("import time:") and line.count("|") == 2}
    assert "ttbpipe.study.plan" in loaded     # the listing is the planning process's
    unwanted = [name for name in PLANNING_MUST_NOT_IMPORT
                if any(m == name or m.startswith(name + ".") for m in loaded)]
    assert not unwanted, f"the Snakefile's process imported {unwanted}"


@pytest.mark.slow
def test_small_study_runs_and_a_new_campaign_reruns_only_its_jobs(tmp_path):
    _copy_repository(tmp_path)
    (tmp_path / "small.yaml").write_text(SMALL_STUDY)

    # the copy as a git checkout: the first run must leave it clean (generated data is ignored,
    # no tracked file is rewritten)
    shutil.copy2(REPO / ".gitignore", tmp_path / ".gitignore")
    git = ["git", "-c", "user.name=ttbpipe", "-c", "user.email=ttbpipe@localhost"]
    subprocess.run([*git, "init", "-q"], cwd=tmp_path, check=True)
    subprocess.run([*git, "add", "-A"], cwd=tmp_path, check=True)
    subprocess.run([*git, "commit", "-qm", "checkout"], cwd=tmp_path, check=True)

    _snakemake(tmp_path, "--quiet", "all")
    status = subprocess.run(["git", "status", "--porcelain"], cwd=tmp_path, check=True,
                            capture_output=True, text=True).stdout
    assert status == "", f"the first run changed the checkout:\n{status}"
    psd_tables = sorted((tmp_path / "results" / "psd").glob("*.parquet"))
    assert [p.stem for p in psd_tables] == ["2023-12-15", "2024-01-15", "2024-02-15"]
    provenance = read_provenance(psd_tables[0])
    assert provenance["config"]["inspections"]["synthetic"]["length_km"] == 2.0
    assert (tmp_path / "results" / "figures" / "psd_vs_standard.png").stat().st_size > 10_000

    # Nothing left to do after a complete run.
    dry = _snakemake(tmp_path, "--dry-run")
    assert "Nothing to be done" in dry.stdout + dry.stderr

    # A user drops in one new campaign (CSV); only its year's preparation job and their
    # dependents must run, not the earlier year's.
    newest = pd.read_parquet(tmp_path / "resources/inspections/synthetic/2024-02-15.parquet")
    newest.to_csv(tmp_path / "resources/inspections/2024-03-15.csv", index=False)
    dry = _snakemake(tmp_path, "--dry-run")
    text = dry.stdout + dry.stderr
    dates = set(re.findall(r"date=(\d{4}-\d{2}-\d{2})", text))
    assert dates <= {"2024-03-15"}, text[-3000:]
    stats = dict(re.findall(r"^(\w+)\s+(\d+)$", text, flags=re.M))
    assert stats.get("prepare_campaigns_2024") == "1", stats
    assert "prepare_campaigns_2023" not in stats, stats
    assert "results/psd/2024-03-15.parquet" in text
    assert "synth_inspections" not in stats

    # The real run runs exactly the jobs the dry run listed (no checkpoint hides any), and none
    # of them is a batch or design of the scenarios that do not read inspection data.
    planned = _jobs(text)
    real = _snakemake(tmp_path)
    assert _jobs(real.stdout + real.stderr) == planned
    batches = [w for rule, w in planned if rule in ("simulate_batch", "study_design")]
    assert batches and all("scenario=2024-" in w or "scenario=2025-" in w for w in batches), batches
    assert not any("scenario=single" in w or "scenario=C1" in w for w in batches)
    assert any("scenario=2024-03-15" in w for w in batches)   # the new latest campaign's sets

    # Re-copying an unchanged file (new mtime, same content) does not trigger reruns.
    src = tmp_path / "resources/inspections/2024-03-15.csv"
    data = src.read_bytes()
    src.unlink()
    src.write_bytes(data)
    dry = _snakemake(tmp_path, "--dry-run")
    assert "Nothing to be done" in dry.stdout + dry.stderr, (dry.stdout + dry.stderr)[-3000:]


def test_unusable_campaign_files_stop_the_workflow_at_parse_time(tmp_path):
    """Files meant as campaigns but named or placed otherwise are reported when Snakemake reads
    the Snakefile (before any job), each with the name it should have; files that are not data
    and the synthetic directory are not."""
    _copy_repository(tmp_path)
    (tmp_path / "small.yaml").write_text(SMALL_STUDY)
    folder = tmp_path / "resources" / "inspections"
    for name in ("20240414.csv", "2024/2024-05-15.csv", "README.md", "synthetic/2024-01-15.csv"):
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text("chainage_m\n0\n")
    cmd = [sys.executable, "-m", "snakemake", "--cores", "1", "--configfile", "small.yaml",
           "--dry-run"]
    result = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    text = result.stdout + result.stderr
    assert result.returncode != 0, text[-3000:]
    assert "2 inspection file(s) the workflow cannot use" in text, text[-3000:]
    assert "resources/inspections/20240414.csv: compact date (YYYYMMDD); rename it to " \
           "2024-04-14.csv" in text
    assert "resources/inspections/2024/2024-05-15.csv: in a subfolder (2024/)" in text
    assert "README.md" not in text and "synthetic/2024-01-15.csv" not in text
    # renamed and moved as told, the same folder parses and plans the jobs for both campaigns
    # (with campaign data in them: the plan reads each campaign's chainage when it starts)
    from ttbpipe.inspection.synthetic import write_synthetic_campaigns

    data = write_synthetic_campaigns(tmp_path / "generated", dates=["2024-04-14", "2024-05-15"],
                                     length_km=2.0, fmt="csv")
    (folder / "20240414.csv").rename(folder / "2024-04-14.csv")
    (folder / "2024" / "2024-05-15.csv").rename(folder / "2024-05-15.csv")
    for path in data:
        shutil.copy(path, folder / path.name)
    dry = _snakemake(tmp_path, "--dry-run")
    dates = set(re.findall(r"psd/(\d{4}-\d{2}-\d{2})\.parquet", dry.stdout + dry.stderr))
    assert {"2024-04-14", "2024-05-15"} <= dates
