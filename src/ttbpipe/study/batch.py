"""Run one batch of samples, here or on a Dask distributed cluster, and write it atomically.

A batch is a consecutive sample-index range of one scenario (:func:`ttbpipe.study.design.batches`).
:func:`simulate_batch` runs its samples (:func:`ttbpipe.study.samples.run_sample`), logs progress
(samples done / total, seconds per sample, ETA) and writes two tables with
:func:`ttbpipe.io.write_table`: the extremes (one row per sample) and the time histories (long
format), both in sample-index order. Nothing is written before every sample of the batch has
finished, and each file appears by an atomic rename, so an interrupted batch leaves no output.

Executors (``simulation.executor``):

* ``local``: the samples one after the other in this process (Snakemake runs batches in parallel);
* ``dask``: the samples are sent to a Dask distributed cluster -- the scheduler at
  ``$TTBPIPE_DASK_SCHEDULER`` (or ``simulation.dask.scheduler``) when set, else a LocalCluster of
  ``simulation.dask.local_workers`` single-threaded worker processes started for the batch with
  NUMBA_NUM_THREADS = OMP_NUM_THREADS = OPENBLAS_NUM_THREADS = MKL_NUM_THREADS = 1 (one sample per
  core, no oversubscription). Each sample is a pure function of its design row, so the results
  are identical to the local run.
"""

from __future__ import annotations

import json
import logging
import os
import time
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import pandas as pd

from ..io import write_table
from ..memory import reuse_freed_memory
from ..threads import WORKER_ENV
from ..assessment.columns import shared_row_metadata
from ..assessment.study import resolve_assessment, with_span_frequencies
from .samples import ASSESSMENT_ROWS_KEY, resolve_simulation, run_sample

log = logging.getLogger(__name__)

SCHEDULER_ENV = "TTBPIPE_DASK_SCHEDULER"


class Progress:
    """Progress lines of a batch: done / total, mean seconds per sample, ETA."""

    def __init__(self, label: str, total: int) -> None:
        self.label, self.total, self.done = label, int(total), 0
        self.start = time.perf_counter()

    def step(self, sample_index: int) -> str:
        self.done += 1
        elapsed = time.perf_counter() - self.start
        per = elapsed / self.done
        line = (f"batch {self.label}: sample {sample_index} done, {self.done}/{self.total} "
                f"({100.0 * self.done / self.total:.0f} %), {per:.1f} s per sample, "
                f"ETA {per * (self.total - self.done):.0f} s")
        log.info(line)
        return line


def _sample_kwargs(config: Mapping[str, Any], profiles: Mapping[str, str],
                   span_frequencies: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    if "structure" not in config:
        raise ValueError("configuration has no structure: section (the study's bridge); copy the "
                         "one in config/config.yaml")
    assessment = resolve_assessment(config.get("assessment"))
    if span_frequencies is not None:
        record = json.loads(Path(span_frequencies).read_text())
        assessment = with_span_frequencies(assessment, record, config["structure"],
                                           str(span_frequencies))
    return {"study_seed": int(config["study"]["seed"]),
            "sim": resolve_simulation(config.get("simulation")),
            "structure": dict(config["structure"]), "fields": config.get("fields"),
            "profiles": dict(profiles), "assessment": assessment}


def _run_local(rows: pd.DataFrame, kwargs: Mapping[str, Any], progress: Progress,
               runner: Callable = run_sample) -> list[tuple[dict, pd.DataFrame]]:
    results = []
    for row in rows.to_dict("records"):
        results.append(runner(row, **kwargs))
        progress.step(int(row["sample_index"]))
    return results


def _pin_threads() -> dict[str, str]:
    """Run on each worker: report the thread settings (they must be set before numba loads)."""
    return {k: os.environ.get(k, "") for k in WORKER_ENV}


def dask_client(dask_cfg: Mapping[str, Any] | None = None):
    """(client, cluster or None): the configured scheduler, else a LocalCluster of pinned workers."""
    from distributed import Client, LocalCluster

    dask_cfg = dict(dask_cfg or {})
    address = os.environ.get(SCHEDULER_ENV) or dask_cfg.get("scheduler")
    if address:
        client = Client(address)
        log.info("dask: connected to scheduler %s (%d workers)", address,
                 len(client.scheduler_info().get("workers", {})))
        client.run(reuse_freed_memory)
        for worker, env in client.run(_pin_threads).items():
            unpinned = [k for k, v in env.items() if v != "1"]
            if unpinned:
                log.warning("dask worker %s: %s not set to 1; start the workers with these "
                            "variables to avoid oversubscribing the cores", worker, unpinned)
        return client, None
    n = int(dask_cfg.get("local_workers", 2))
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=None, env=dict(WORKER_ENV))
    client = Client(cluster)
    client.run(reuse_freed_memory)
    log.info("dask: LocalCluster of %d single-threaded workers (%s)", n, WORKER_ENV)
    return client, cluster


def _run_dask(rows: pd.DataFrame, kwargs: Mapping[str, Any], progress: Progress,
              dask_cfg: Mapping[str, Any] | None,
              runner: Callable = run_sample) -> list[tuple[dict, pd.DataFrame]]:
    from distributed import as_completed

    client, cluster = dask_client(dask_cfg)
    try:
        records = rows.to_dict("records")
        futures = [client.submit(runner, row, **kwargs, pure=False,
                                 key=f"ttbpipe-sample-{row['scenario']}-{row['sample_index']}-{os.getpid()}")
                   for row in records]
        position = {f.key: i for i, f in enumerate(futures)}
        results: list = [None] * len(futures)
        for future in as_completed(futures):
            i = position[future.key]
            results[i] = future.result()  # re-raises the sample's exception here
            progress.step(int(records[i]["sample_index"]))
        return results
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_batch(rows: pd.DataFrame, config: Mapping[str, Any], profiles: Mapping[str, str], *,
              label: str = "", executor: str | None = None,
              runner: Callable = run_sample, metadata: list | None = None,
              span_frequencies: str | os.PathLike[str] | None = None
              ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Simulate the design rows of one batch; (extremes, histories) in sample-index order.
    ``metadata``: a list that receives the assessed rows' metadata of the batch (clause,
    category, limit source per profile index; the same for every sample).
    ``span_frequencies``: the study's EN 1990 span-frequency record (JSON of
    :func:`ttbpipe.assessment.modal.span_frequency_record`), so that the batch does not repeat
    the modal analysis; None: the batch's process analyses the structure itself (same numbers)."""
    sim = resolve_simulation(config.get("simulation"))
    executor = executor or sim["executor"]
    kwargs = _sample_kwargs(config, profiles, span_frequencies)
    rows = rows.sort_values(["scenario", "sample_index"]).reset_index(drop=True)
    progress = Progress(label or f"{rows['scenario'].iloc[0]} "
                        f"{rows['sample_index'].iloc[0]}-{rows['sample_index'].iloc[-1]}", len(rows))
    log.info("batch %s: %d samples, executor %s", progress.label, len(rows), executor)
    if executor == "local":
        results = _run_local(rows, kwargs, progress, runner)
    elif executor == "dask":
        results = _run_dask(rows, kwargs, progress, sim.get("dask"), runner)
    else:
        raise ValueError(f"simulation.executor: {executor!r}; expected local | dask")
    rows_meta = [r[0].pop(ASSESSMENT_ROWS_KEY, None) for r in results]
    if metadata is not None:
        metadata.extend(shared_row_metadata(
            (f"sample {r[0]['scenario']}/{r[0]['sample_index']}", m)
            for r, m in zip(results, rows_meta)))
    extremes = pd.DataFrame([r[0] for r in results])
    extremes["scenario"] = extremes["scenario"].astype("string")
    extremes["seed_entropy"] = extremes["seed_entropy"].astype("string")
    histories = pd.concat([r[1] for r in results], ignore_index=True)
    histories["scenario"] = histories["scenario"].astype("string")
    return extremes, histories


def simulate_batch(rows: pd.DataFrame, config: Mapping[str, Any], profiles: Mapping[str, str],
                   extremes_path: str | os.PathLike[str], histories_path: str | os.PathLike[str],
                   *, executor: str | None = None, runner: Callable = run_sample,
                   span_frequencies: str | os.PathLike[str] | None = None,
                   **provenance: Any) -> tuple[Path, Path]:
    """Run a batch and write its two tables atomically (nothing is written if a sample fails)."""
    from ..stats.schema import validate_extremes, validate_histories

    reuse_freed_memory()   # the samples' arrays reused, not mapped afresh (ttbpipe.memory)
    assessed: list = []
    extremes, histories = run_batch(rows, config, profiles, executor=executor, runner=runner,
                                    metadata=assessed, span_frequencies=span_frequencies)
    validate_extremes(extremes, extremes_path)
    validate_histories(histories, histories_path)
    meta = dict(config=config, samples=[int(i) for i in rows["sample_index"]],
                assessment=assessed, **provenance)
    # histories first: the extremes file is the batch's "done" marker for a reader outside Snakemake
    write_table(histories, histories_path, kind="study_histories", **meta)
    write_table(extremes, extremes_path, kind="study_extremes", **meta)
    log.info("batch written: %s (%d samples), %s (%d rows)", extremes_path, len(extremes),
             histories_path, len(histories))
    return Path(extremes_path), Path(histories_path)


def batch_paths(root: str, scenario: str, first: int, last: int) -> tuple[str, str]:
    """File names of one batch: <root>/<scenario>/extremes_<first>-<last>.parquet and histories_."""
    return (f"{root}/{scenario}/extremes_{first:05d}-{last:05d}.parquet",
            f"{root}/{scenario}/histories_{first:05d}-{last:05d}.parquet")


def expected_outputs(design: pd.DataFrame, batch_size: int, root: str) -> list[str]:
    """Every batch file of a design (extremes then histories per batch)."""
    from .design import batches

    out: list[str] = []
    for scenario, first, last in batches(design, batch_size):
        out += batch_paths(root, scenario, first, last)
    return out


def missing_batches(design: pd.DataFrame, batch_size: int, root: str) -> list[tuple[str, int, int]]:
    """Batches whose two files are not both present (what a rerun has to do)."""
    from .design import batches

    return [b for b in batches(design, batch_size)
            if not all(Path(p).is_file() for p in batch_paths(root, *b))]


def simulate_design(design: pd.DataFrame, config: Mapping[str, Any], profiles: Mapping[str, str],
                    root: str, *, batch_size: int | None = None, executor: str | None = None,
                    runner: Callable = run_sample) -> list[tuple[str, int, int]]:
    """Run every missing batch of a design (outside Snakemake: tests, the Dask "all" mode).

    Finished batches are skipped, so a rerun after an interruption redoes only what is missing.
    Returns the batches it ran.
    """
    sim = resolve_simulation(config.get("simulation"))
    size = int(batch_size or sim["batch_size"])
    todo = missing_batches(design, size, root)
    from .design import batch_rows

    for k, (scenario, first, last) in enumerate(todo):
        log.info("study: batch %d/%d (%s %d-%d)", k + 1, len(todo), scenario, first, last)
        simulate_batch(batch_rows(design, scenario, first, last), config, profiles,
                       *batch_paths(root, scenario, first, last), executor=executor,
                       runner=runner)
    return todo


class StaleBatchError(ValueError):
    """Batch files that were not made by the current settings and code, or cannot be read."""


def _differences(old: Any, new: Any, path: str = "") -> list[str]:
    """Key paths where two settings documents differ (for the error message)."""
    if isinstance(old, Mapping) and isinstance(new, Mapping):
        out: list[str] = []
        for key in sorted(set(old) | set(new), key=str):
            out += _differences(old.get(key), new.get(key), f"{path}.{key}" if path else str(key))
        return out
    return [] if old == new else [f"{path}: {old!r} -> {new!r}"]


def verify_batches(paths: Sequence[str | os.PathLike[str]], design: pd.DataFrame,
                   settings: Mapping[str, Mapping[str, Any]], *,
                   rerun_hint: str = "snakemake --cores 2 --forcerun") -> dict[str, dict]:
    """Check, before aggregating, that every batch file was made for the current study; returns
    each file's provenance document by path (read once, for the aggregation's other uses).

    For each file: it can be read (a truncated or corrupt Parquet file fails here, not deep in
    pyarrow); its provenance names a scenario whose current settings (``settings[scenario]``,
    :func:`ttbpipe.study.plan.batch_settings`) have the digest the file was made with; and it
    holds exactly the design's samples of its index range. Raises :class:`StaleBatchError`
    naming every bad file, what is wrong with it and the command that remakes them.
    """
    import json

    import pyarrow.parquet as pq

    from ..io import PROVENANCE_KEY
    from .plan import settings_digest

    problems: list[tuple[str, str]] = []
    documents: dict[str, dict] = {}
    design_index = {s: set(int(i) for i in g["sample_index"])
                    for s, g in design.groupby(design["scenario"].astype(str))}
    for path in map(str, paths):
        try:
            meta = pq.ParquetFile(path).metadata
            doc = json.loads((meta.metadata or {})[PROVENANCE_KEY])
        except KeyError:
            problems.append((path, "no ttbpipe provenance in its metadata: not written by a batch job"))
            continue
        except Exception as exc:   # truncated or corrupt file (pyarrow raises ArrowInvalid, OSError)
            problems.append((path, f"unreadable ({type(exc).__name__}: {exc}): truncated or "
                                   "corrupt, e.g. by a job killed while copying or a full disk"))
            continue
        documents[path] = doc
        scenario = str(doc.get("scenario"))
        current = settings.get(scenario)
        if current is None:
            problems.append((path, f"scenario {scenario!r} is not part of the current study"))
            continue
        made_with = doc.get("settings_digest")
        if made_with != settings_digest(current):
            changed = _differences(doc.get("settings") or {}, dict(current))
            problems.append((path, f"made with settings digest {made_with}, the current one is "
                                   f"{settings_digest(current)}"
                                   + (f" ({'; '.join(changed[:5])})" if changed else "")))
            continue
        first, last = int(doc.get("first", -1)), int(doc.get("last", -1))
        expected = sorted(i for i in design_index.get(scenario, set()) if first <= i <= last)
        if sorted(int(i) for i in doc.get("samples", [])) != expected:
            problems.append((path, f"holds samples {doc.get('samples')} but the design of "
                                   f"{scenario} has {expected} in {first}-{last}"))
    if problems:
        lines = "\n".join(f"  {p}: {why}" for p, why in problems)
        files = " ".join(sorted({p for p, _ in problems}))
        raise StaleBatchError(
            f"{len(problems)} batch file(s) were not made by the current settings and code or "
            f"cannot be read, so they must not be aggregated:\n{lines}\n"
            f"Remake them: {rerun_hint} {files}")
    return documents
