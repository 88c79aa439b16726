"""Assess a run against a standard: :func:`assess` (a table and its summary) and
:func:`assess_result` (a ``ttbpipe simulate`` Parquet file)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Mapping

import pandas as pd

from .base import records_to_frame, rows_to_records
from .registry import get_profile
from .run import RunData

log = logging.getLogger(__name__)


def assess(table: pd.DataFrame, summary: Mapping[str, Any], standard: str, *,
           options: Mapping[str, Any] | None = None,
           config: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """One row per index of ``standard`` (a profile name: en14363, gb5599, en1990, en12299)
    evaluated on a run's time-history ``table`` and ``summary``: the clause, the processed value,
    its raw counterpart, the limit, utilisation = processed / limit, the unit, where it governs
    and the processing parameters (columns :data:`~.base.COLUMNS`). ``options`` update the
    profile's defaults (unknown keys are an error); ``config`` is the run's case (the EN 1990
    deck checks build its structure for the modal analysis)."""
    return records_to_frame(assess_records(RunData(table, summary, config), standard,
                                           options=options))


def assess_records(run: RunData, standard: str, *,
                   options: Mapping[str, Any] | None = None) -> list[dict[str, Any]]:
    """:func:`assess` as records (one dict per row, keys :data:`~.base.COLUMNS`) of a run's
    :class:`~.run.RunData`, without building the DataFrame: a study assesses every sample
    against several profiles, which then share the run's histories (:class:`~.run.RunData`
    reads each set of columns once)."""
    profile = get_profile(standard)
    resolved = profile.resolve_options(options)
    records = rows_to_records(profile, profile.evaluate(run, resolved))
    for row in records:
        log.info("%s %s (%s): %.4g %s (raw %.4g), limit %.4g, utilisation %.3f", profile.name,
                 row["index"], row["location"], row["processed_value"], row["unit"],
                 row["raw_value"], row["limit"], row["utilisation"])
    return records


def assess_result(path: str | Path, standard: str, *,
                  options: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """:func:`assess` of a ``ttbpipe simulate`` result: its table, and the summary and case of
    its provenance (:func:`ttbpipe.io.read_provenance`)."""
    from ..io import read_provenance, read_table

    prov = read_provenance(path)
    if prov.get("kind") != "simulation" or not isinstance(prov.get("summary"), Mapping):
        raise ValueError(f"{path}: not a ttbpipe simulate result (provenance kind "
                         f"{prov.get('kind')!r}, summary {'present' if prov.get('summary') else 'absent'})")
    return assess(read_table(path), prov["summary"], standard, options=options,
                  config=prov.get("config"))
