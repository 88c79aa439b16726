"""Geometry of the line: approach, spans, approach; rail nodes, slab units, girder meshes.

x = 0 at the start of the first approach. Rails: one node per fastener, spacing adjusted to fit
the line exactly. The layout does not depend on the random properties (docs/structure.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np


@dataclass
class Layout:
    """Geometry of the line (independent of the random properties)."""

    total_m: float
    bridge_start_m: float
    bridge_end_m: float
    span_starts_m: np.ndarray
    span_lengths_m: np.ndarray
    rail_x: np.ndarray                     # rail node (= fastener) positions
    rail_zone: np.ndarray                  # "bridge" | "approach" per node
    slab_units: list = field(default_factory=list)   # list of (zone, node_x array)
    girder_n_el: list = field(default_factory=list)  # elements per span
    #: lateral offset of each track's centre line from the girders' shear centre (m, + left);
    #: track k has rails 2k (left) and 2k+1 (right), its own slab units (``slab_units``, the
    #: same for every track) and approaches
    track_offsets_m: tuple = (0.0,)

    @property
    def n_spans(self) -> int:
        return self.span_lengths_m.size

    @property
    def n_tracks(self) -> int:
        return len(self.track_offsets_m)


#: Track offsets of a double-track deck when none are given: the tracks 5.0 m apart (line
#: spacing of 350 km/h lines, TB 10621-2014 [M]), each 2.5 m off the girder's axis.
DOUBLE_TRACK_OFFSETS_M = (2.5, -2.5)


def track_offsets(cfg: Mapping[str, Any]) -> tuple[float, ...]:
    """Lateral offsets (m, + left) of every track's centre line from the girders' shear centre.

    ``layout.tracks`` (1 or 2) tracks; ``girder.track_offsets_m`` gives one offset per track
    (track k's rails are 2k, 2k+1); without it one track sits at ``girder.track_offset_m`` and
    two at :data:`DOUBLE_TRACK_OFFSETS_M`. The paper's eq. 24 term B_r - b_s/2 per track.
    """
    lay, g = cfg["layout"], cfg["girder"]
    n = lay.get("tracks", 1)
    if n not in (1, 2):
        raise ValueError(f"structure.layout.tracks: {n!r}; expected 1 or 2")
    given = g.get("track_offsets_m")
    if given is None:
        if n == 1:
            return (float(g["track_offset_m"]),)
        if float(g["track_offset_m"]) != 0.0:
            raise ValueError("structure.girder.track_offset_m is the offset of a single track; "
                             "a double-track deck (layout.tracks: 2) takes one offset per track "
                             "in girder.track_offsets_m")
        return DOUBLE_TRACK_OFFSETS_M
    offsets = tuple(float(e) for e in given)
    if len(offsets) != n:
        raise ValueError(f"structure.girder.track_offsets_m: {len(offsets)} offsets for "
                         f"layout.tracks: {n}; give one per track")
    if n == 1 and float(g["track_offset_m"]) not in (0.0, offsets[0]):
        raise ValueError("structure.girder: track_offset_m and track_offsets_m disagree; give one")
    if n == 2 and abs(offsets[0] - offsets[1]) < float(cfg["slab"]["width_m"]):
        raise ValueError(f"structure.girder.track_offsets_m: {list(offsets)} puts the tracks "
                         "on top of each other; their centre lines must be at least a slab "
                         "width apart")
    return offsets


def _slab_units(a: float, b: float, cfg: Mapping[str, Any], zone: str,
                span_edges: list[float] | None = None) -> list:
    """Slab units covering [a, b]: one continuous unit, or discrete units (per span on bridges)."""
    el = float(cfg["element_length_m"])
    units = []
    if cfg["type"] == "continuous":
        n = max(1, int(round((b - a) / el)))
        return [(zone, np.linspace(a, b, n + 1))]
    if cfg["type"] != "discrete":
        raise ValueError(f"structure.slab.type: {cfg['type']!r}; expected continuous | discrete")
    edges = span_edges if span_edges is not None else [a, b]
    joint = float(cfg["joint_m"])
    for lo, hi in zip(edges[:-1], edges[1:]):
        n_u = max(1, int(round((hi - lo) / (float(cfg["unit_length_m"]) + joint))))
        pitch = (hi - lo) / n_u
        for u in range(n_u):
            ua, ub = lo + u * pitch + joint / 2, lo + (u + 1) * pitch - joint / 2
            n = max(1, int(round((ub - ua) / el)))
            units.append((zone, np.linspace(ua, ub, n + 1)))
    return units


def make_layout(cfg: Mapping[str, Any]) -> Layout:
    """Line geometry from a resolved structure config."""
    lay = cfg["layout"]
    spans = np.asarray(lay["spans_m"], dtype=float)
    if spans.size and np.any(spans <= 0):
        raise ValueError(f"structure.layout.spans_m must be positive, got {spans.tolist()}")
    approach = float(lay["approach_length_m"])
    if approach < 0:
        raise ValueError("structure.layout.approach_length_m must be >= 0")
    total = 2 * approach + float(spans.sum())
    if total <= 0:
        raise ValueError("structure.layout: empty line (no spans and no approaches)")
    starts = approach + np.concatenate([[0.0], np.cumsum(spans)[:-1]]) if spans.size else np.zeros(0)
    bs, be = approach, approach + float(spans.sum())
    spacing = float(cfg["fastener"]["spacing_m"])
    n_el = max(2, int(round(total / spacing)))
    rail_x = np.linspace(0.0, total, n_el + 1)
    zone = np.where((rail_x >= bs - 1e-9) & (rail_x <= be + 1e-9) & (spans.size > 0),
                    "bridge", "approach")
    layout = Layout(total, bs, be, starts, spans, rail_x, zone,
                    track_offsets_m=track_offsets(cfg))
    if lay["bridge_track"] == "slab" and spans.size:
        edges = list(np.concatenate([starts, [be]]))
        layout.slab_units += _slab_units(bs, be, cfg["slab"], "bridge", edges)
    if lay["approach_track"] == "slab" and approach > 0:
        layout.slab_units += _slab_units(0.0, bs, cfg["slab"], "approach")
        layout.slab_units += _slab_units(be, total, cfg["slab"], "approach")
    layout.slab_units.sort(key=lambda u: u[1][0])
    el = float(cfg["girder"]["element_length_m"])
    layout.girder_n_el = [max(4, int(round(L / el))) for L in spans]
    return layout
