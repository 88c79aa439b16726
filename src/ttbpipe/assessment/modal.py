"""Natural frequencies of each span of a run's structure for the EN 1990 A2 band rule.

EN 1990 A2 A2.4.4.2.1 checks deck accelerations for frequencies up to the greater of 30 Hz,
1.5 times the frequency of the fundamental mode of the member and the frequency of its third
mode (standards.md [M: the band rule]). The member is a span; its f0 (first) and f3 (third)
vertical bending frequencies come from ttbpipe's modal analysis
(:func:`ttbpipe.structure.modal.modal_analysis`) of the run's structure
(:func:`ttbpipe.structure.build_structure` of the case's ``structure:`` section, with the
``properties:`` factors when the case has them), done once per structure (cached).

Identification. With several equal spans coupled through the rails, each bending mode of a span
is a cluster of nearly equal global modes that mix the spans. A mode counts for span s and order
j when its kinetic energy is mostly in the girders' vertical coordinates (share >= 0.5), at
least 1 % of it is in span s, and the vertical deflection of span s along its length has j
half-waves (sign changes + 1 over 41 points, ignoring points below 5 % of the largest). The
span's f_j is the mean of the cluster's frequencies weighted by their energy in span s.

The ballasted approaches have hundreds of sleeper-ballast modes between 40 and 60 Hz, where the
third bending mode of a 32 m span lies; the global eigenproblem is therefore solved with the
sleeper-ballast coordinates held fixed (they only touch the bridge through the rails; measured
on the reference case: the first five frequencies change by 1e-5 with or without them). f3 is
then sought near the bare girder's third frequency scaled by the coupled/bare ratio of the
second, and the search window grows until the cluster lies inside it.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Mapping

import numpy as np

from ..io import jsonable

log = logging.getLogger(__name__)

MIN_VERTICAL_SHARE = 0.5     # girder-vertical share of a bending mode's kinetic energy
MIN_SPAN_SHARE = 0.01        # share of the mode's energy in the span for it to count there
SHAPE_POINTS = 41
SHAPE_FLOOR = 0.05


@dataclass(frozen=True)
class SpanFrequencies:
    """Span s (1-based), its start and length (m), first and third vertical frequencies (Hz)."""

    span: int
    start_m: float
    length_m: float
    f0_hz: float
    f3_hz: float


def span_frequencies(structure_config: Mapping[str, Any] | None,
                     properties: Mapping[str, Any] | None = None) -> tuple[SpanFrequencies, ...]:
    """f0 and f3 of every span of the structure of a case (cached per structure)."""
    return _span_frequencies(_structure_key(structure_config, properties))


def _structure_key(structure_config: Mapping[str, Any] | None,
                   properties: Mapping[str, Any] | None = None) -> str:
    return json.dumps(jsonable({"structure": structure_config or {}, "properties": properties}),
                      sort_keys=True)


def span_frequency_record(structure_config: Mapping[str, Any] | None) -> dict[str, Any]:
    """f0 and f3 of every span of a nominal structure as a JSON-able record, with the structure
    it belongs to. A study computes it once (rule study_span_frequencies) and its batches take
    the spans from it (:func:`span_options`) instead of each process repeating the analysis."""
    return {"structure_key": _structure_key(structure_config),
            "spans": [dataclasses.asdict(s) for s in span_frequencies(structure_config)]}


def span_options(record: Mapping[str, Any], structure_config: Mapping[str, Any] | None,
                 source: str = "the span-frequency record") -> dict[str, list[float]]:
    """The EN 1990 profile's options ``f0_hz``, ``f3_hz``, ``span_lengths_m`` from a record of
    :func:`span_frequency_record`; the same numbers as the analysis of ``structure_config``
    (JSON keeps every float exactly). A record made for another structure is an error."""
    if record.get("structure_key") != _structure_key(structure_config):
        raise ValueError(f"{source} was computed for another structure than the study's "
                         "(structure: section changed since): rerun the workflow, which "
                         "recomputes it (rule study_span_frequencies)")
    spans = [SpanFrequencies(**s) for s in record["spans"]]
    return {"f0_hz": [s.f0_hz for s in spans], "f3_hz": [s.f3_hz for s in spans],
            "span_lengths_m": [s.length_m for s in spans]}


@lru_cache(maxsize=8)
def _span_frequencies(key: str) -> tuple[SpanFrequencies, ...]:
    from ..structure import apply_factors, build_structure
    from ..structure.random_properties import property_factors

    doc = json.loads(key)
    model = build_structure(doc["structure"])
    if doc["properties"]:
        factors = property_factors(doc["properties"], model)
        if factors:
            model = apply_factors(model, factors)
    if not model.spans:
        raise ValueError("the structure has no spans: nothing to check against EN 1990 A2")
    return analyse(model)


def analyse(model) -> tuple[SpanFrequencies, ...]:
    """f0 and f3 of every span of a :class:`ttbpipe.structure.StructureModel` (uncached)."""
    from ..structure.modal import component_index_sets

    ballast = component_index_sets(model)["sleeper_ballast"]
    fixed = model.fixed.copy()
    fixed[ballast] = True
    member = dataclasses.replace(model, fixed=fixed)
    matrices = member.matrices()          # assembled once for every eigen-solve below
    n_spans = len(member.spans)

    low = _clusters(member, matrices, sigma_hz=0.0, n_modes=8 * n_spans + 10, orders=(1, 2))
    estimates = {}
    for s, red in enumerate(member.spans):
        bare = np.asarray(red.mode_frequencies_hz[0], dtype=float)
        if bare.size < 3:
            raise ValueError(f"span {s + 1}: the girder keeps {bare.size} vertical mode(s) (below "
                             "structure.girder.max_mode_frequency_hz); its third mode is above "
                             "them: raise that frequency or give the option f3_hz")
        if low[(s, 1)] is None:
            raise ValueError(f"span {s + 1}: no first vertical bending mode among the lowest "
                             f"{8 * n_spans + 10} modes")
        f2 = low[(s, 2)]
        estimates[s] = bare[2] * (f2 / bare[1] if f2 is not None else low[(s, 1)] / bare[0])
    third: dict = {}
    for n_modes in (6 * n_spans + 20, 12 * n_spans + 40, 24 * n_spans + 80):
        todo = [s for s in range(n_spans) if third.get(s) is None]
        if not todo:
            break
        # spans of equal length share a search: one window around the median estimate
        sigma = float(np.median([estimates[s] for s in todo]))
        found = _clusters(member, matrices, sigma_hz=sigma, n_modes=n_modes, orders=(3,),
                          spans=todo)
        for s in todo:
            third[s] = found[(s, 3)]
    out = []
    for s, red in enumerate(member.spans):
        if third[s] is None:
            raise ValueError(f"span {s + 1}: no complete cluster of third vertical bending modes "
                             f"near {estimates[s]:.1f} Hz; give the option f3_hz")
        out.append(SpanFrequencies(s + 1, float(red.start_m), float(red.length_m),
                                   low[(s, 1)], third[s]))
        log.info("span %d (%.1f m): f0 = %.3f Hz, f3 = %.3f Hz", s + 1, red.length_m,
                 low[(s, 1)], third[s])
    return tuple(out)


def _half_waves(w: np.ndarray) -> int:
    big = np.abs(w) > SHAPE_FLOOR * np.max(np.abs(w))
    signs = np.sign(w[big])
    return 1 + int(np.count_nonzero(np.diff(signs) != 0))


def _clusters(member, matrices, sigma_hz: float, n_modes: int, orders, spans=None) -> dict:
    """{(span index, order): energy-weighted frequency of the complete cluster, or None}."""
    from ..structure.modal import modal_analysis

    res = modal_analysis(member, n_modes=n_modes, sigma_hz=sigma_hz, matrices=matrices)
    mass = matrices[0].tocsr()
    freqs = res.frequencies_hz
    vertical = res.shares["girder_vertical"] >= MIN_VERTICAL_SHARE
    total = np.einsum("ij,ij->j", res.shapes, mass @ res.shapes)
    spans = range(len(member.spans)) if spans is None else spans
    out = {}
    for s in spans:
        red = member.spans[s]
        o = member.dof_info["span_dof0"][s]
        idx = np.arange(o, o + red.n)
        block = mass[idx][:, idx]
        sub = res.shapes[idx]
        share = np.einsum("ij,ij->j", sub, block @ sub) / total
        xs = np.linspace(red.start_m, red.start_m + red.length_m, SHAPE_POINTS)
        rows = np.array([red.rows_at(x)[0] for x in xs])
        deflection = rows @ sub                                   # (points, modes)
        waves = np.array([_half_waves(deflection[:, j]) if share[j] >= MIN_SPAN_SHARE else 0
                          for j in range(freqs.size)])
        for order in orders:
            hit = vertical & (share >= MIN_SPAN_SHARE) & (waves == order)
            if not hit.any():
                out[(s, order)] = None
                continue
            lo, hi = freqs[hit].min(), freqs[hit].max()
            # complete: the window of computed modes extends beyond the cluster on both sides
            # (eigsh returns the modes nearest sigma, so none inside [lo, hi] is missing)
            complete = freqs.min() < lo and freqs.max() > hi
            if sigma_hz <= 0.0:
                complete = freqs.max() > hi
            out[(s, order)] = (float(np.sum(share[hit] * freqs[hit]) / np.sum(share[hit]))
                               if complete else None)
    return out
