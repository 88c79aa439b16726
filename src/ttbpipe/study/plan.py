"""The study's plan, known when the workflow starts: sample counts, batches, settings digests.

Snakemake builds its job graph before any job runs. For the dry run to list the jobs the real run
will run (and for a new inspection campaign to rerun only what depends on it), every batch of the
study must be known then, without a checkpoint. Batches are consecutive sample-index ranges of
one scenario (:func:`ttbpipe.study.design.batches`), so what is needed is each scenario's number
of samples:

* configuration alone: ``fields``/``fields_mc`` (``samples`` per condition), ``irregularity_mc``
  (``samples``), ``single`` (1);
* the inspection data: ``irregularity`` has one sample per TIPM representative set, M =
  ``TIPMSelector.n_samples(N)`` for the N sections of the latest campaign's population;
  ``forecast`` has one per forecast base set (the latest campaign's own sections, or its M TIPM
  sets). A campaign's number of full sections follows from its chainage alone
  (:func:`campaign_rows`: the rows the cleaning step will output, dropouts re-inserted; then
  :func:`full_sections`, the rule of :func:`ttbpipe.irregularity.psd.section_psds`). Reading
  the chainage of each campaign file costs milliseconds and is cached per file (size, mtime).
  The design rule checks the count against the design it builds and stops with the cause if
  they ever differ.

Batch files live under a **settings digest**: ``<root>/<digest>/<scenario>/extremes_<first>-
<last>.parquet`` (:func:`ttbpipe.study.batch.batch_paths` below ``<root>/<digest>``), the digest (:func:`settings_digest`) of everything a sample's result depends
on besides its design row (:func:`batch_settings`: the simulation settings except batch size and
executor, the structure, the fields where the scenario uses them, the study seed and the code
version). Changing any of them changes the path, so Snakemake reruns every affected batch even
when an earlier run was killed and its batch jobs finished untracked; the aggregate step still
checks each file's provenance against the current digest (:func:`ttbpipe.study.batch.verify_batches`).
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
import logging
import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from .design import SINGLE, batches, resolve_scenarios

log = logging.getLogger(__name__)

#: Simulation settings that do not change a sample's result (batching and where it runs).
EXECUTION_SETTINGS = ("batch_size", "executor", "dask")
#: Scenario kinds whose samples draw the random parameter fields.
FIELD_KINDS = ("fields", "fields_mc")


@functools.lru_cache(maxsize=4096)
def _campaign_rows_cached(path: str, size: int, mtime_ns: int, mapping_json: str
                          ) -> tuple[int, float]:
    from ..inspection.format import CHAINAGE_COLUMN, InspectionError, read_campaign
    from ..inspection.grid import grid_indices

    frame = read_campaign(path, check_name=False, **json.loads(mapping_json))
    if CHAINAGE_COLUMN not in frame.columns:
        raise InspectionError(path, None, CHAINAGE_COLUMN, "missing chainage column")
    chainage = pd.to_numeric(frame[CHAINAGE_COLUMN], errors="coerce").to_numpy(float)
    chainage = chainage[np.isfinite(chainage)]
    if chainage.size < 2:
        raise InspectionError(path, None, CHAINAGE_COLUMN, "fewer than two chainage values")
    k, step = grid_indices(chainage)
    return int(k[-1]) + 1, float(step)


def campaign_rows(path: str | os.PathLike[str], mapping: Mapping[str, Any] | None = None
                  ) -> tuple[int, float]:
    """(rows of the cleaned campaign, sampling step in m) from the file's chainage alone, read
    through the file's column and unit ``mapping`` (``columns``/``units`` of
    ``inspections``; none for synthetic campaigns)."""
    stat = Path(path).stat()
    return _campaign_rows_cached(str(path), stat.st_size, stat.st_mtime_ns,
                                 json.dumps(dict(mapping or {}), sort_keys=True))


@functools.lru_cache(maxsize=16)
def synthetic_rows(spectrum: str, length_km: float, dx_m: float = 0.25) -> tuple[int, float]:
    """(rows, step) of a synthetic campaign not written yet: the generator's base grid (its
    artefacts leave the first and last samples in place, so the cleaned grid is the base grid)."""
    from ..irregularity.synthesis import synthesize_profiles

    base = synthesize_profiles(spectrum, float(length_km) * 1000.0, dx_m, seed=0)
    return len(base), float(dx_m)


def full_sections(rows: int, step_m: float, section_length_m: float) -> int:
    """Full sections of ``section_length_m`` in a campaign of ``rows`` samples at ``step_m``
    (the rule of ttbpipe.irregularity.psd.section_psds: the trailing partial one is dropped)."""
    return int(rows) // int(round(float(section_length_m) / float(step_m)))


def campaign_sections(path: str | os.PathLike[str], section_length_m: float,
                      synthetic: Mapping[str, Any] | None = None,
                      mapping: Mapping[str, Any] | None = None) -> int:
    """Full sections of one campaign: from its file (read through ``mapping``), or, for a
    synthetic campaign that has not been written yet, from the generator's grid."""
    if Path(path).is_file():
        rows, step = campaign_rows(path, mapping)
    elif synthetic is not None:
        rows, step = synthetic_rows(str(synthetic.get("spectrum", "tbt3352")),
                                    float(synthetic.get("length_km", 5.0)))
    else:
        raise FileNotFoundError(f"{path}: campaign file not found")
    return full_sections(rows, step, section_length_m)


def sample_counts(config: Mapping[str, Any], labels: Mapping[str, Sequence[str]], *,
                  latest_sections: int | None, population_sections: int | None
                  ) -> dict[str, int]:
    """Number of samples of every scenario label (``labels``: kind -> labels, as
    :func:`ttbpipe.study.design.scenario_labels` gives them)."""
    from ..tipm.settings import representative_count, resolve_config

    sc = resolve_scenarios(config["study"])
    counts: dict[str, int] = {}
    tipm = resolve_config(config.get("tipm"))
    if labels.get("irregularity") or labels.get("forecast"):
        if population_sections is None or latest_sections is None:
            raise ValueError("the irregularity and forecast scenarios need the number of "
                             "sections of the inspection campaigns")
        selection = tipm["selection"]
        m = representative_count(int(population_sections), selection["fraction"],
                                 selection["min_samples"], selection.get("max_samples"))
    for label in labels.get("irregularity", ()):
        counts[label] = m
    for label in labels.get(SINGLE, ()):
        counts[label] = 1
    for label in labels.get("forecast", ()):
        counts[label] = m if tipm["forecast"]["base"] == "selection" else int(latest_sections)
    for kind in ("fields", "fields_mc", "irregularity_mc"):
        for label in labels.get(kind, ()):
            counts[label] = int(sc[kind]["samples"])
    return counts


def batch_ranges(counts: Mapping[str, int], batch_size: int) -> list[tuple[str, int, int]]:
    """(scenario, first, last) of every batch: samples 0..n-1 of each scenario in batches of
    ``batch_size`` (the partition of :func:`ttbpipe.study.design.batches`)."""
    frame = pd.DataFrame({"scenario": [s for s, n in counts.items() for _ in range(int(n))],
                          "sample_index": [i for n in counts.values() for i in range(int(n))]})
    return batches(frame, batch_size) if len(frame) else []


def batch_settings(config: Mapping[str, Any], kind: str, code_version: str) -> dict[str, Any]:
    """Everything a batch's results depend on besides its design rows (and, for the
    irregularity and forecast scenarios, the TIPM profile files, which are inputs)."""
    from ..assessment.study import resolve_assessment
    from .samples import resolve_simulation

    simulation = resolve_simulation(config.get("simulation"))
    settings: dict[str, Any] = {
        "simulation": {k: v for k, v in simulation.items() if k not in EXECUTION_SETTINGS},
        "structure": copy.deepcopy(config.get("structure") or {}),
        "seed": int(config["study"]["seed"]),
        "code_version": str(code_version),
        "assessment": resolve_assessment(config.get("assessment")),
    }
    if kind in FIELD_KINDS:
        settings["fields"] = copy.deepcopy(config.get("fields"))
    if kind == "irregularity_mc":
        settings["mc_profiles"] = mc_profile_settings(config)
    return settings


def mc_profile_settings(config: Mapping[str, Any]) -> dict[str, Any]:
    """Profile settings of the Monte Carlo irregularity scenario (its population's PSD band and
    the TIPM profile length, step and synthesis ``amplitudes``: ``tipm.profiles``), the keys
    :func:`ttbpipe.study.samples.mc_profile` reads."""
    from ..tipm.settings import resolve_config

    return {"wavelength_band_m": (config.get("psd") or {}).get("wavelength_band_m"),
            **resolve_config(config.get("tipm"))["profiles"]}


def settings_digest(settings: Mapping[str, Any]) -> str:
    """12 hex digits of SHA-256 over the canonical JSON of ``settings``."""
    text = json.dumps(settings, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]
