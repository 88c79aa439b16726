"""Per-sample columns of an assessment in the study's extremes table, and their report sections.

A study assesses every sample with the profiles its configuration selects
(``assessment.standard``; :mod:`ttbpipe.assessment.study`) and writes, for each row of a
profile's table (:func:`ttbpipe.assessment.assess`), up to three float columns into the sample's
extremes row (docs/results_schema.md, "Assessed indices"):

* ``<profile>_<index>``: the processed value, in the unit its name carries
  (``en14363_sum_Y_2m_N``, ``gb5599_wheel_unloading_ratio``, ``en1990_deck_vertical_acc_m_s2``);
* ``<profile>_<stem>_utilisation``: processed / limit (rows with a limit only);
* ``<profile>_<stem>_limit<suffix>``: the limit the sample was checked against, in the index's
  unit (``en14363_sum_Y_2m_limit_N``: it depends on the sample's static axle load).

``<stem>`` is the index name without its unit suffix (``sum_Y_2m``). The raw counterpart of a
processed index stays in its own registry column (``max_lateral_wheelset_force_N``), so nothing
is lost. :func:`assessed_indices` reads the columns back for the report; :func:`extreme_columns`
writes them: the one home of the naming.

Report sections (:data:`SECTIONS`): each index belongs to one, named as a bridge or track
engineer groups the checks; :func:`section_of` is its home.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from ..stats.schema import UNIT_SUFFIXES

log = logging.getLogger(__name__)

#: Unit suffixes an index name may end with, longest first: the results schema's.
_SUFFIXES = tuple(suffix for suffix, _ in UNIT_SUFFIXES)
UTILISATION = "utilisation"
LIMIT = "limit"

#: Report sections, in report order, and the indices of each (by index name of the profiles).
SECTIONS: dict[str, tuple[str, ...]] = {
    "Running safety": ("Y_Q_2m", "sum_Y_2m_N", "derailment_coefficient_Q_P",
                       "wheel_unloading_ratio", "lateral_wheelset_force_H_N"),
    "Track loading": ("Q_max_N", "Q_qst_N", "Y_qst_N"),
    "Bridge deck": ("deck_vertical_acc_m_s2", "deck_twist_m", "vertical_deflection_m",
                    "span_to_deflection_ratio"),
    "Ride comfort": ("carbody_vertical_acc_m_s2", "carbody_lateral_acc_m_s2", "sperling_vertical",
                     "sperling_lateral", "b_v_m_s2", "N_MV"),
}
OTHER_SECTION = "Other indices"

#: How the report names an index (its notation in the standard), where the name differs.
DISPLAY_NAMES = {
    "Y_Q_2m": "(Y/Q)2m", "sum_Y_2m_N": "(ΣY)2m track shift force", "Q_max_N": "Q max",
    "Q_qst_N": "Q qst", "Y_qst_N": "Y qst",
    "derailment_coefficient_Q_P": "derailment coefficient Q/P",
    "lateral_wheelset_force_H_N": "lateral wheelset force H",
    "b_v_m_s2": "in-coach vertical acceleration b_v", "N_MV": "mean comfort N_MV",
    "span_to_deflection_ratio": "span / deflection L/δ",
    "deck_vertical_acc_m_s2": "deck vertical acceleration",
    "carbody_vertical_acc_m_s2": "car-body vertical acceleration",
    "carbody_lateral_acc_m_s2": "car-body lateral acceleration",
    "sperling_vertical": "Sperling index, vertical", "sperling_lateral": "Sperling index, lateral",
}


def display_name(index: str) -> str:
    """The report's name of an index: its notation in the standard, else the words of its name."""
    if index in DISPLAY_NAMES:
        return DISPLAY_NAMES[index]
    return split_unit(index)[0].replace("_", " ")


def section_of(index: str) -> str:
    """The report section of an assessed index (by its profile index name)."""
    for section, names in SECTIONS.items():
        if index in names:
            return section
    return OTHER_SECTION


def split_unit(index: str) -> tuple[str, str]:
    """(stem, unit suffix) of an index name: ``sum_Y_2m_N`` -> (``sum_Y_2m``, ``_N``)."""
    for suffix in _SUFFIXES:
        if index.endswith(suffix) and len(index) > len(suffix):
            return index[: -len(suffix)], suffix
    return index, ""


def value_column(profile: str, index: str) -> str:
    return f"{profile}_{index}"


def utilisation_column(profile: str, index: str) -> str:
    return f"{profile}_{split_unit(index)[0]}_{UTILISATION}"


def limit_column(profile: str, index: str) -> str:
    stem, suffix = split_unit(index)
    return f"{profile}_{stem}_{LIMIT}{suffix}"


def _records(table: pd.DataFrame | Iterable[Mapping[str, Any]]) -> Iterable[Mapping[str, Any]]:
    return table.to_dict("records") if isinstance(table, pd.DataFrame) else table


def extreme_columns(table: pd.DataFrame | Iterable[Mapping[str, Any]]) -> dict[str, float]:
    """The extremes-row columns of one profile's assessment (its table, or the table's records:
    :func:`ttbpipe.assessment.api.assess_records`; see the module docstring)."""
    out: dict[str, float] = {}
    for row in _records(table):
        out[value_column(row["profile"], row["index"])] = float(row["processed_value"])
        if np.isfinite(row["limit"]):
            out[utilisation_column(row["profile"], row["index"])] = float(row["utilisation"])
            out[limit_column(row["profile"], row["index"])] = float(row["limit"])
    return out


@dataclass(frozen=True)
class AssessedIndex:
    """One assessed index of an extremes table: its columns, unit, kind and report section.

    ``category`` is the profile row's: ``limit`` (a safety or serviceability limit), ``grade``
    (a quality or comfort grade boundary) or ``info`` (no limit).
    """

    profile: str
    index: str
    value: str
    utilisation: str | None
    limit: str | None
    unit: str
    category: str
    section: str
    clause: str
    limit_source: str
    standard: str

    @property
    def label(self) -> str:
        return f"{self.profile} {self.index}"


def _unit(suffix: str) -> str:
    return dict(UNIT_SUFFIXES).get(suffix, "1")


def row_metadata(table: pd.DataFrame | Iterable[Mapping[str, Any]]) -> list[dict[str, str]]:
    """Clause, category, unit and limit source of each row of a profile's assessment (its table
    or the table's records; JSON-able): what the report needs besides the values; the study
    keeps them in its batches' provenance."""
    keys = ("profile", "index", "clause", "category", "unit", "limit_source", "standard")
    return [{k: r[k] for k in keys} for r in _records(table)]


def shared_row_metadata(candidates: Iterable[tuple[str, Iterable[Mapping[str, str]] | None]]
                        ) -> list[dict[str, str]]:
    """The :func:`row_metadata` that a study's samples share: the first non-empty of
    ``candidates`` ``(origin, metadata)`` (a sample, a batch file). The profiles word each limit
    source as the rule, with the sample's own values (its static load, speed, span) in the row's
    notes and in the limit column, so every sample gives the same records. Where later
    candidates differ, one warning per index names the first origin, the first that differs and
    how many do (the first is kept), so nothing is replaced silently."""
    first_origin, first, known = None, None, {}
    differing: dict[tuple[str, str], list] = {}     # index -> [origin, field, value, count]
    for origin, meta in candidates:
        if not meta:
            continue
        meta = [dict(m) for m in meta]
        if first is None:
            first_origin, first = origin, meta
            known = {(m["profile"], m["index"]): m for m in first}
            continue
        for m in meta:
            key = (m["profile"], m["index"])
            ref = known.get(key)
            if ref is not None and ref != m:
                if key not in differing:
                    field = next(k for k in {**ref, **m} if m.get(k) != ref.get(k))
                    differing[key] = [origin, field, m.get(field), 0]
                differing[key][3] += 1
    for (profile, index), (origin, field, value, count) in differing.items():
        log.warning("assessment metadata of %s %s differs between %s and %s%s (%s: %r, %r); the "
                    "report keeps the first", profile, index, first_origin, origin,
                    f" and {count - 1} more" if count > 1 else "", field,
                    known[(profile, index)].get(field), value)
    return first or []


def assessed_indices(columns: Iterable[str], metadata: Iterable[Mapping[str, str]] = ()
                     ) -> list[AssessedIndex]:
    """The assessed indices whose value column is among ``columns``, in report order (section,
    then the section's index order, then profile); ``metadata``: :func:`row_metadata` records
    (clause, category, limit source) of the profiles' rows, where known."""
    from .registry import profiles as registry

    names = list(registry())
    meta = {(m["profile"], m["index"]): m for m in metadata}
    cols = set(columns)
    found: list[AssessedIndex] = []
    for name in names:
        prefix = f"{name}_"
        for col in sorted(c for c in cols if c.startswith(prefix)):
            index = col[len(prefix):]
            if index.endswith(f"_{UTILISATION}") or _LIMIT_TAIL.search(index):
                continue
            util, lim = utilisation_column(name, index), limit_column(name, index)
            info = meta.get((name, index), {})
            found.append(AssessedIndex(
                name, index, col, util if util in cols else None, lim if lim in cols else None,
                _unit(split_unit(index)[1]),
                info.get("category", "limit" if util in cols else "info"),
                section_of(index), info.get("clause", ""), info.get("limit_source", ""),
                info.get("standard", name)))
    order = {s: k for k, s in enumerate([*SECTIONS, OTHER_SECTION])}
    return sorted(found, key=lambda a: (order[a.section], _position(a.index),
                                        names.index(a.profile)))


_LIMIT_TAIL = re.compile(rf"_{LIMIT}({'|'.join(_SUFFIXES)})?$")


def _position(index: str) -> int:
    for names in SECTIONS.values():
        if index in names:
            return names.index(index)
    return len(SECTIONS)
