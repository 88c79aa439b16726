"""The study stage under Snakemake: killing a run and rerunning it.

A tiny fields-only study (one 32 m span, one car, 10 m of run, 4 samples in batches of 1) in a
scratch copy of the repository. Snakemake is interrupted (SIGINT to its process group, as Ctrl-C
does) as soon as the first batch file exists; the rerun must finish without redoing the finished
batches (their files keep their modification times), and no temporary or partial file may remain.
The final extremes must equal those of an uninterrupted run of the same design in the package
(exact equality: the runs are deterministic).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from test_workflow import _copy_repository

TINY_STUDY = """\
study:
  name: tiny
  seed: 3
  scenarios:
    irregularity: {enabled: false}
    forecast: {enabled: false}
    fields: {conditions: [C3], samples: 4}
inspections:
  synthetic: {enabled: true, length_km: 2.0, campaigns: 2}
structure:
  layout: {approach_length_m: 30.0, spans_m: [32.0], approach_track: ballasted, bridge_track: slab}
simulation:
  train: {composition: [trailer]}
  end_x_m: 35.0
  batch_size: 1
fields:
  variance_fraction: 0.9
assessment:
  standard: []   # a 0.15 s run is too short for the standards' filters
"""


def _recorded(workdir: Path, kind: str) -> set[str]:
    """Outputs Snakemake recorded under .snakemake/<kind>: ``incomplete`` (jobs it had not seen
    finish when it was stopped) or ``metadata`` (jobs it registered as finished). Each is a
    file named by the urlsafe base64 of the output's path, long names split into '@' chunks."""
    import base64

    root = workdir / ".snakemake" / kind
    out = set()
    for path in root.rglob("*") if root.is_dir() else []:
        if path.is_file() and path.name != "migration_underway":
            parts = path.relative_to(root).parts
            out.add(base64.urlsafe_b64decode("".join(p.lstrip("@") for p in parts)).decode())
    return out


def _incomplete(workdir: Path) -> set[str]:
    return _recorded(workdir, "incomplete")


def _default_sigint() -> None:
    """In the child before exec: SIGINT unblocked and at its default action. A test process can
    inherit SIGINT ignored or blocked (by the test runner or an earlier test's library), and a
    child inherits both, so that Ctrl-C, and this file's SIGINT, would not reach Snakemake."""
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(cmd: list[str], cwd: Path, env: dict) -> tuple[subprocess.Popen, list[str]]:
    """Start Snakemake in its own process group; a thread collects its output lines."""
    import threading

    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True,
                            preexec_fn=_default_sigint)
    output: list[str] = []
    threading.Thread(target=lambda: output.extend(iter(proc.stdout.readline, "")),
                     daemon=True).start()
    return proc, output


def _cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "snakemake", *args, "--cores", "2", "--configfile", "tiny.yaml"]


def _interrupted_run(workdir: Path, env: dict) -> tuple[Path, dict[str, int]]:
    """Run the tiny study in ``workdir`` and interrupt it (SIGINT to its process group, as
    Ctrl-C) once Snakemake has registered a finished batch; (batch folder, {file: mtime} of the
    batches it had registered) or None when the run ended before the interruption took."""
    workdir.mkdir(parents=True)
    _copy_repository(workdir)
    (workdir / "tiny.yaml").write_text(TINY_STUDY)
    root = workdir / "results" / "study" / "batches"   # <digest>/<scenario>/...
    proc, output = _start(_cmd("results/study/extremes.parquet"), workdir, env)
    deadline = time.monotonic() + 180
    # interrupt once Snakemake has registered a finished batch (a batch whose files exist but
    # whose job Snakemake has not seen end is, rightly, marked incomplete and redone). Snakemake
    # records a finished job's outputs in .snakemake/metadata at once; its log lines reach the
    # pipe later on a loaded machine.
    while time.monotonic() < deadline and not any(
            "/batches/" in name for name in _recorded(workdir, "metadata")):
        if proc.poll() is not None:
            pytest.fail("snakemake ended before the first batch:\n" + "".join(output)[-3000:])
        time.sleep(0.02)
    seen = time.strftime("%H:%M:%S")
    # Snakemake turns SIGINT into its orderly stop only while it waits in its scheduling loop;
    # right after a job's end it is busy starting the next ones, so let it settle first and
    # repeat the signal until it stops (a batch takes several seconds: the run is still going)
    time.sleep(1.0)
    for _ in range(10):
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=3)
            break
        except subprocess.TimeoutExpired:
            continue
    proc.wait(timeout=60)
    if (workdir / "results" / "study" / "extremes.parquet").exists():
        print(f"{workdir.name}: batch registered at {seen}; the run finished despite SIGINT "
              f"(test process: SIGINT handler {signal.getsignal(signal.SIGINT)}, blocked "
              f"{signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])}):\n"
              + "".join(output)[-2500:])
        return None
    batches = next(root.glob("*/C3"))
    # a batch whose job Snakemake had not seen finish is marked incomplete and redone, rightly
    pending = _incomplete(workdir)
    finished = {p.name: p.stat().st_mtime_ns for p in batches.glob("*.parquet")
                if str(p.relative_to(workdir)) not in pending}
    return batches, finished


@pytest.mark.slow
def test_killed_run_resumes_without_redoing_finished_batches(tmp_path):
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    # Snakemake acts on SIGINT in its scheduling loop; on a loaded machine the signal can land
    # elsewhere and the run goes on to the end. That is a miss of the set-up, not a result: try
    # again in a fresh copy (three times at most, then the test fails)
    for attempt in range(3):
        got = _interrupted_run(tmp_path / f"attempt{attempt}", env)
        if got is not None:
            break
    else:
        pytest.fail("three runs finished before they could be interrupted; the test shows nothing")
    tmp_path = tmp_path / f"attempt{attempt}"
    batches, finished = got
    assert finished, "no batch finished before the interruption"
    assert not [p for p in batches.iterdir() if p.name.startswith(".")], "temporary files left"

    rerun = subprocess.run(_cmd("results/study/extremes.parquet"), cwd=tmp_path, env=env,
                           capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stdout[-3000:] + rerun.stderr[-3000:]
    for name, stamp in finished.items():
        assert (batches / name).stat().st_mtime_ns == stamp, f"{name} was redone"
    log = rerun.stdout + rerun.stderr
    ran = len(re.findall(r"(?m)^(?:local)?rule simulate_batch:", log))
    n_done = sum(1 for n in finished if n.startswith("extremes_"))
    assert ran == 4 - n_done, log[-3000:]
    assert sorted(p.name for p in batches.iterdir()) == sorted(
        [f"{k}_{i:05d}-{i:05d}.parquet" for i in range(4) for k in ("extremes", "histories")])

    # the same samples simulated in one go by the package
    import yaml

    from ttbpipe.study.batch import simulate_design
    from ttbpipe.study.design import build_design

    config = yaml.safe_load((tmp_path / "config" / "config.yaml").read_text())
    tiny = yaml.safe_load(TINY_STUDY)
    for key in ("study", "structure", "simulation", "assessment"):
        config[key] = tiny[key]
    config["fields"]["variance_fraction"] = 0.9
    design = build_design(config["study"], latest_campaign="2024-01-15", horizons_months=[])
    simulate_design(design, config, {}, str(tmp_path / "direct"), batch_size=4)
    direct = pd.read_parquet(tmp_path / "direct" / "C3" / "extremes_00000-00003.parquet")
    workflow = pd.read_parquet(tmp_path / "results" / "study" / "extremes.parquet")
    pd.testing.assert_frame_equal(direct.reset_index(drop=True), workflow.reset_index(drop=True),
                                  check_exact=True, check_dtype=False)


@pytest.mark.slow
def test_batches_finished_after_a_killed_run_are_not_mixed_with_new_settings(tmp_path):
    """Snakemake's own process killed (SIGKILL, as the OOM killer does) while batch jobs run:
    the jobs finish untracked. After a simulation setting changes, the rerun must recompute
    every batch (the batch paths carry the digest of the settings they depend on), and the
    aggregate's provenance check must find only current batches. Then a truncated batch file
    makes the aggregation stop with a message naming it, not a pyarrow traceback."""
    import yaml

    from ttbpipe.io import read_provenance

    _copy_repository(tmp_path)
    (tmp_path / "tiny.yaml").write_text(TINY_STUDY)
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    batches = tmp_path / "results" / "study" / "batches"
    proc = subprocess.Popen(_cmd("results/study/extremes.parquet"), cwd=tmp_path, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline and not list(batches.glob("*/C3/extremes_*.parquet")):
        assert proc.poll() is None, "snakemake ended before the first batch"
        time.sleep(0.2)
    os.kill(proc.pid, signal.SIGKILL)          # Snakemake only: its batch jobs go on
    proc.wait(timeout=30)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:         # until the orphaned jobs have finished
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    old = sorted(batches.glob("*/C3/extremes_*.parquet"))
    assert old, "no batch finished"
    assert not (tmp_path / "results" / "study" / "extremes.parquet").exists()
    old_digest = old[0].parent.parent.name

    config = yaml.safe_load(TINY_STUDY)
    config["simulation"]["deck_filter_hz"] = 25.0
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(config))
    subprocess.run(_cmd("--unlock"), cwd=tmp_path, env=env, check=True, capture_output=True)
    rerun = subprocess.run(_cmd("results/study/extremes.parquet"), cwd=tmp_path, env=env,
                           capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stdout[-3000:] + rerun.stderr[-3000:]
    log = rerun.stdout + rerun.stderr
    assert len(re.findall(r"(?m)^(?:local)?rule simulate_batch:", log)) == 4, log[-3000:]
    new = sorted(p for p in batches.glob("*/C3/extremes_*.parquet")
                 if p.parent.parent.name != old_digest)
    assert len(new) == 4
    for path in new:
        assert read_provenance(path)["settings"]["simulation"]["deck_filter_hz"] == 25.0
    for path in old:                           # the stale ones are left alone, never read
        assert read_provenance(path)["settings"]["simulation"]["deck_filter_hz"] == 30.0
    aggregated = read_provenance(tmp_path / "results" / "study" / "extremes.parquet")
    assert aggregated["config"]["simulation"]["deck_filter_hz"] == 25.0

    with open(new[1], "r+b") as f:             # a batch file damaged on disk
        f.truncate(new[1].stat().st_size // 2)
    broken = subprocess.run(_cmd("results/study/extremes.parquet", "--forcerun",
                                 "aggregate_study"), cwd=tmp_path, env=env,
                            capture_output=True, text=True)
    text = broken.stdout + broken.stderr
    assert broken.returncode != 0
    assert f"{new[1].relative_to(tmp_path)}: unreadable (ArrowInvalid" in text, text[-3000:]
    assert "Remake them: snakemake --cores 2 --forcerun" in text
