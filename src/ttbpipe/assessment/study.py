"""The study's assessment of each sample: the profiles of ``assessment.standard``, in memory.

A study (``config/config.yaml``) selects profiles with ``assessment.standard`` (a name or a list;
default every profile, :data:`DEFAULT_STANDARDS`) and updates their defaults with
``assessment.options.<profile>``. :func:`run_case` adds to a sample's case what the selected
profiles need recorded (the EN 1990 A2 twist monitors, :func:`.monitors.deck_check_monitors`,
when ``en1990`` is selected with ``twist`` on); :func:`assess_sample` assesses the run's table
and summary with the same code as ``ttbpipe assess`` (:func:`.api.assess_records`: the rows of
:func:`ttbpipe.assessment.assess` without building its table) and
returns the extremes-row columns of :func:`.columns.extreme_columns` and the rows' metadata.

EN 1990 A2's f0 and f3 come from the modal analysis of the study's nominal structure, cached per
process (:func:`.modal.span_frequencies`): a fields sample's random girder properties do not
change the band it is filtered in (the band is a property of the design, and its cut-off only
moves with f3 by a few per cent under the fields' coefficients of variation).
"""

from __future__ import annotations

import copy
import functools
import json
from typing import Any, Mapping

import pandas as pd

from ..configuration import validate_section
from .api import assess_records
from .columns import extreme_columns, row_metadata
from .registry import get_profile
from .run import RunData

#: Profiles a study assesses when ``assessment.standard`` is not given.
DEFAULT_STANDARDS = ("en14363", "gb5599", "en1990", "en12299")


def resolve_assessment(section: Mapping[str, Any] | None) -> dict[str, Any]:
    """``assessment:`` validated (study schema), ``standard`` as a list of known profile names
    and ``options`` resolved against each profile's defaults (unknown options are an error)."""
    cfg = validate_section(section, "assessment")
    standard = cfg.get("standard")
    names = list(DEFAULT_STANDARDS if standard is None else
                 [standard] if isinstance(standard, str) else standard)
    if len(set(names)) != len(names):
        raise ValueError(f"assessment.standard lists a profile twice: {names}")
    options = dict(cfg.get("options") or {})
    unused = sorted(set(options) - set(names))
    if unused:
        raise ValueError(f"assessment.options has options for {unused}, which "
                         f"assessment.standard {names} does not select")
    resolved = {name: get_profile(name).resolve_options(options.get(name)) for name in names}
    return {"standard": names, "options": resolved}


def needs_span_frequencies(assessment: Mapping[str, Any]) -> bool:
    """Whether the EN 1990 profile is selected and takes f0, f3 and the span lengths from the
    modal analysis (none of them given as options)."""
    if "en1990" not in assessment["standard"]:
        return False
    options = assessment["options"]["en1990"]
    return any(options[k] is None for k in ("f0_hz", "f3_hz", "span_lengths_m"))


def with_span_frequencies(assessment: Mapping[str, Any], record: Mapping[str, Any],
                          structure: Mapping[str, Any], source: str) -> dict[str, Any]:
    """``assessment`` (resolved) with the EN 1990 spans of the study's span-frequency record
    (:func:`.modal.span_frequency_record`) as options: the numbers the modal analysis would
    give, without each batch process repeating it (1.1 s). Unchanged when not needed."""
    if not needs_span_frequencies(assessment):
        return dict(assessment)
    from .modal import span_options

    options = {**assessment["options"], "en1990": {**assessment["options"]["en1990"],
                                                   **span_options(record, structure, source)}}
    return {**assessment, "options": options}


def needs_twist_monitors(assessment: Mapping[str, Any]) -> bool:
    return "en1990" in assessment["standard"] and bool(assessment["options"]["en1990"]["twist"])


@functools.lru_cache(maxsize=4)
def _twist_monitors(case_json: str) -> tuple[str, ...]:
    from ..simulation.setup import nominal_structure
    from ..structure.monitors import default_monitors
    from .monitors import deck_check_monitors

    model = nominal_structure(json.loads(case_json))
    return tuple(json.dumps(m) for m in [*default_monitors(model), *deck_check_monitors(model)])


def run_case(case: Mapping[str, Any], assessment: Mapping[str, Any]) -> dict[str, Any]:
    """``case`` with the monitors the selected profiles need (a copy; unchanged otherwise)."""
    if not needs_twist_monitors(assessment) or case.get("monitors"):
        return dict(case)
    out = copy.deepcopy(dict(case))
    # the structure on the case's layout (a curve moves the deck monitors with the track)
    where = {"structure": out.get("structure") or {},
             "simulation": {"layout": (out.get("simulation") or {}).get("layout")}}
    out["monitors"] = [json.loads(m) for m in
                       _twist_monitors(json.dumps(where, sort_keys=True, default=str))]
    return out


def assess_sample(table: pd.DataFrame, summary: Mapping[str, Any], case: Mapping[str, Any],
                  assessment: Mapping[str, Any]) -> tuple[dict[str, float], list[dict[str, str]]]:
    """(extremes-row columns, row metadata) of every selected profile on one run. The EN 1990
    modal analysis uses the case's nominal structure (no per-sample factors)."""
    nominal = {k: v for k, v in case.items() if k != "properties"}
    columns: dict[str, float] = {}
    metadata: list[dict[str, str]] = []
    run = RunData(table, summary, nominal)       # read once, shared by the profiles
    for name in assessment["standard"]:
        result = assess_records(run, name, options=assessment["options"][name])
        columns.update(extreme_columns(result))
        metadata += row_metadata(result)
    return columns, metadata
