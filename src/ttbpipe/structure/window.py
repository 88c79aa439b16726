"""A moving window over the approach track: only the track near the train moves.

The approaches (plain track before and after the bridge) are there to bring the train on and
off the bridge; at any time only the track near the wheels deflects and vibrates (the rail's
deflection basin decays over a few metres, the vibration the train leaves behind decays with
the track's damping). The window freezes the approach track that is farther than
``margin_m`` ahead of the leading and behind the last wheelset: its DOFs keep their
displacement with zero velocity and acceleration (a zero inverse mass, as for fixed DOFs), and
its elements are skipped where none of their DOFs moves. The bridge (girders, piers, bearings,
the track on the deck and the track within ``margin_m`` of each abutment) and every monitored DOF
always move.

Bookkeeping is by segments of ``segment_m`` along x: a DOF belongs to the segment of its x, an
element to the lowest segment of its DOFs (an element spans at most two neighbouring segments;
checked), and is evaluated when either of them is active. Segments switch when the window
crosses a segment boundary (every ``segment_m / V``: 60 ms at 300 km/h), not per step. Ahead
of the train the frozen track holds the static state the run started from, so it enters the
window at rest in equilibrium; behind it the track is frozen as the train left it.

Validated against the whole track in ``tests/test_track_window.py`` and docs/performance.md
("Moving window over the approach track").
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import kernel
from ..index_ranges import range_span
from .kernels import _EVERY_ELEMENT

#: Segment length of the window's bookkeeping (m): a few fastener bays, longer than any element.
SEGMENT_M = 5.0
#: ``simulation.track_window_m`` when a case does not give it (None: the whole track moves).
DEFAULT_TRACK_WINDOW_M = None

#: The window of a run: its segments (which always move, which move now, the active range
#: of the last update), each diagonal DOF's segment (-1: always moves), the structure's
#: inverse mass and the working copy with the frozen DOFs at 0, each element's lowest segment
#: (-1: always evaluated), and the evaluated elements as ranges (``*_ranges`` rows [start,
#: end), ``n_ranges`` rows of beams, links, pads, ballast, link triples, then of
#: ``dof_ranges``), which the kernels loop over
#: (:func:`ttbpipe.structure.kernels.windowed_accelerations_in_place`). ``dof_ranges``: the
#: DOFs that move (the others keep zero velocity and accelerations, so the loop's Zhai update
#: and its clearing of the loads skip them: :func:`clear_moving`,
#: :func:`ttbpipe.timestepping.zhai.zhai_predict_ranges`).
TrackWindow = namedtuple("TrackWindow", [
    "n_segments", "segment_m", "margin_m", "segment_always", "segment_on", "active",
    "dof_segment", "base_inv_mass", "inv_mass",
    "beam_segment", "link_segment", "pad_segment", "ballast_segment", "triple_segment",
    "beam_ranges", "link_ranges", "pad_ranges", "ballast_ranges", "triple_ranges", "n_ranges",
    "dof_ranges",
])
#: Kinds of ranges of a window, the rows of ``n_ranges``: elements (beams, links, pads,
#: ballast, link triples), then the moving DOFs.
N_RANGE_KINDS = 6
DOF_RANGES = 5


def _every(n_rows: int = 1) -> np.ndarray:
    """Ranges of ``n_rows`` rows whose first is the kernels' "every element" row."""
    ranges = np.zeros((n_rows, 2), dtype=np.int64)
    ranges[0] = _EVERY_ELEMENT[0]
    return ranges


def no_window(packed) -> TrackWindow:
    """The whole track moves: no segments, every element, the structure's own inverse mass."""
    i0, u0 = np.zeros(0, np.int64), np.zeros(0, np.uint8)
    return TrackWindow(0, SEGMENT_M, np.inf, u0, u0.copy(), np.zeros(2, np.int64), i0,
                       packed.inv_mass, packed.inv_mass, i0, i0, i0, i0, i0,
                       _every(), _every(), _every(), _every(), _every(),
                       np.ones(N_RANGE_KINDS, dtype=np.int64), _every())


def _dof_x(model) -> np.ndarray:
    """x (m) of every diagonal-mass DOF of the track (rails, slab nodes, sleepers, ballast
    blocks); NaN for the DOFs that belong to the bridge's supports (lumped piers)."""
    packed, layout, info = model.packed, model.layout, model.dof_info
    x = np.full(int(packed.n_diag), np.nan)
    n_rn = int(info["n_rail_nodes"])
    for r in range(int(packed.n_rails)):
        d = 5 * (r * n_rn + np.arange(n_rn))
        for k in range(5):
            x[d + k] = layout.rail_x
    for (_, xs), d0 in zip(layout.slab_units * layout.n_tracks, info["slab_node_dof0"]):
        for k in range(5):
            x[d0 + k] = xs
    n_slab, n_bal = int(packed.pad_group[0]), int(packed.pad_group[1])
    for p in range(n_slab, n_slab + n_bal):
        node = (int(packed.pad_rail[p]) // 5) % n_rn
        x[packed.pad_seat_a[p]:packed.pad_seat_a[p] + 3] = layout.rail_x[node]
    for j in range(packed.bal_sleeper.size):
        x[packed.bal_block[j]:packed.bal_block[j] + 2] = x[packed.bal_sleeper[j]]
    unplaced = np.flatnonzero(np.isnan(x[:info["pier"]]))
    if unplaced.size:
        raise RuntimeError(f"internal: {unplaced.size} track DOFs without a position "
                           f"(first {unplaced[0]})")
    return x


def _element_segments(ptr, dofs, dof_segment, what: str) -> np.ndarray:
    """Lowest segment of each element's DOFs (CSR ``ptr``/``dofs``, entries < 0 unused); -1
    where one of them always moves (a bridge or support DOF)."""
    n_el = ptr.size - 1
    if n_el == 0:
        return np.zeros(0, dtype=np.int64)
    n_diag = dof_segment.size
    used = dofs >= 0
    seg = np.where(dofs >= n_diag, -1, dof_segment[np.clip(dofs, 0, n_diag - 1)])
    start = ptr[:-1]
    moving = np.maximum.reduceat((used & (seg < 0)).astype(np.int64), start)
    lo = np.minimum.reduceat(np.where(used, seg, np.iinfo(np.int64).max), start)
    hi = np.maximum.reduceat(np.where(used, seg, -1), start)
    wide = np.flatnonzero((moving == 0) & (hi > lo + 1))
    if wide.size:
        e = wide[0]
        raise ValueError(f"track window: {what} {e} spans segments {lo[e]}..{hi[e]}; its DOFs "
                         f"lie more than {SEGMENT_M} m apart")
    return np.where(moving > 0, -1, lo).astype(np.int64)


def track_window(model, margin_m: float, keep_dofs=()) -> TrackWindow:
    """The moving window of a structure model: approach track farther than ``margin_m`` from
    the train frozen (module docstring). ``keep_dofs``: DOFs that always move (monitors)."""
    margin_m = float(margin_m)
    if not margin_m > 0:
        raise ValueError(f"simulation.track_window_m: {margin_m}; give a positive margin in "
                         "metres (or null for the whole track)")
    packed, layout = model.packed, model.layout
    x = _dof_x(model)
    n_seg = int(np.floor(layout.total_m / SEGMENT_M)) + 1
    dof_segment = np.where(np.isnan(x), -1,
                           np.floor(np.nan_to_num(x) / SEGMENT_M)).astype(np.int64)
    always = np.zeros(n_seg, dtype=np.uint8)
    if layout.n_spans:
        first = int(np.floor((layout.bridge_start_m - margin_m) / SEGMENT_M))
        last = int(np.floor((layout.bridge_end_m + margin_m) / SEGMENT_M))
        always[max(first, 0):min(last, n_seg - 1) + 1] = 1
    keep = np.asarray(keep_dofs, dtype=np.int64)
    keep = keep[keep < dof_segment.size]
    always[dof_segment[keep][dof_segment[keep] >= 0]] = 1
    dof_segment = np.where((dof_segment >= 0) & (always[np.maximum(dof_segment, 0)] == 1), -1,
                           dof_segment)
    nb = packed.beam_L.size
    beam_seg = _element_segments(np.arange(0, 2 * nb + 1, 2),
                                 np.column_stack([packed.beam_dof_a, packed.beam_dof_b]).ravel(),
                                 dof_segment, "beam element")
    link_seg = _element_segments(packed.link_ptr, packed.link_dof, dof_segment, "link")
    tri_seg = _element_segments(packed.tri_ptr, packed.tri_dof, dof_segment, "link triple")
    n_pad = packed.pad_rail.size
    pad_dofs = np.column_stack([packed.pad_rail, packed.pad_seat_a, packed.pad_seat_b]).ravel()
    pad_seg = _element_segments(np.arange(0, 3 * n_pad + 1, 3), pad_dofs, dof_segment,
                                "rail pad")
    ns = packed.bal_sleeper.size
    nxt = np.where(packed.bal_next != 0, packed.bal_block + 2, -1)
    bal_dofs = np.column_stack([packed.bal_sleeper, packed.bal_block, nxt]).ravel()
    bal_seg = _element_segments(np.arange(0, 3 * ns + 1, 3), bal_dofs, dof_segment, "sleeper")
    segments = (beam_seg, link_seg, pad_seg, bal_seg, tri_seg)
    # until the first update every element is evaluated and every DOF moves (row 0: [0, -1))
    return TrackWindow(n_seg, SEGMENT_M, margin_m, always, always.copy(),
                       np.array([-1, -1], np.int64), dof_segment, packed.inv_mass,
                       packed.inv_mass.copy(), *segments,
                       *(_every(e.size // 2 + 2) for e in segments),
                       np.ones(N_RANGE_KINDS, dtype=np.int64),
                       _every(dof_segment.size // 2 + 2))


@kernel(inline="always")
def _extend_runs(ranges, rows, inside, i, selected):
    """One index of the runs of selected indices written as rows [start, end) of ``ranges``:
    index ``i`` opens a run, closes the open one or neither; returns (rows, inside a run)."""
    if selected and not inside:
        ranges[rows, 0] = i
        return rows, True
    if inside and not selected:
        ranges[rows, 1] = i
        return rows + 1, False
    return rows, inside


@kernel(inline="always")
def _close_runs(ranges, rows, inside, end):
    """Close the open run at ``end``; returns the number of rows."""
    if inside:
        ranges[rows, 1] = end
        return rows + 1
    return rows


@kernel(creates_arrays=False)
def _element_ranges(segment, segment_on, ranges):
    """The runs of elements to evaluate as rows [start, end) of ``ranges`` (an element with a
    DOF in an active segment: its lowest segment or the next one active; or one that always
    moves); returns the number of rows."""
    n = segment_on.shape[0]
    rows = 0
    inside = False
    for e in range(segment.shape[0]):
        s = segment[e]
        evaluated = s < 0 or segment_on[s] != 0 or (s + 1 < n and segment_on[s + 1] != 0)
        rows, inside = _extend_runs(ranges, rows, inside, e, evaluated)
    return _close_runs(ranges, rows, inside, segment.shape[0])


@kernel(creates_arrays=False)
def clear_moving(window, values):
    """Set the entries of the DOFs that move (``window.dof_ranges``) to 0: the coupled loop's
    loads before each evaluation. The frozen DOFs' accelerations are 0 already: each
    evaluation scales them by their zero inverse mass. Without a window, one plain loop over
    all entries (the ranges' one row measured slower)."""
    n = values.shape[0]
    if window.n_segments == 0:
        for i in range(n):
            values[i] = 0.0
        return
    for k in range(window.n_ranges[DOF_RANGES]):
        start, end = range_span(window.dof_ranges, k, n)
        for i in range(start, end):
            values[i] = 0.0


@kernel(creates_arrays=False)
def _moving_dof_ranges(dof_segment, segment_on, n_dof, ranges):
    """The runs of DOFs that move as rows [start, end) of ``ranges``: a diagonal DOF whose
    segment is active or that always moves, and every DOF after the diagonal ones (the span
    blocks); returns the number of rows."""
    n_diag = dof_segment.shape[0]
    rows = 0
    inside = False
    for d in range(n_diag):
        s = dof_segment[d]
        rows, inside = _extend_runs(ranges, rows, inside, d, s < 0 or segment_on[s] != 0)
    if n_dof > n_diag:
        rows, inside = _extend_runs(ranges, rows, inside, n_diag, True)
    return _close_runs(ranges, rows, inside, n_dof)


@kernel(creates_arrays=False)
def update_window(window, x_low, x_high, vel, acc, acc_prev):
    """Move the window to cover [x_low - margin, x_high + margin] (the train's wheelsets between
    x_low and x_high). DOFs that leave it stop where they are (velocity and accelerations set
    to 0); DOFs that enter it move again. Nothing to do while no segment boundary is crossed."""
    n = window.n_segments
    if n == 0:
        return
    seg = window.segment_m
    first = int(np.floor((x_low - window.margin_m) / seg))
    last = int(np.floor((x_high + window.margin_m) / seg))
    if first == window.active[0] and last == window.active[1]:
        return
    window.active[0] = first
    window.active[1] = last
    on = window.segment_on
    for s in range(n):
        on[s] = 1 if (window.segment_always[s] != 0 or first <= s <= last) else 0
    dof_segment = window.dof_segment
    for d in range(dof_segment.shape[0]):
        s = dof_segment[d]
        if s < 0:
            continue
        if on[s] != 0:
            window.inv_mass[d] = window.base_inv_mass[d]
        else:
            window.inv_mass[d] = 0.0
            vel[d] = 0.0
            acc[d] = 0.0
            acc_prev[d] = 0.0
    n = window.n_ranges
    n[0] = _element_ranges(window.beam_segment, on, window.beam_ranges)
    n[1] = _element_ranges(window.link_segment, on, window.link_ranges)
    n[2] = _element_ranges(window.pad_segment, on, window.pad_ranges)
    n[3] = _element_ranges(window.ballast_segment, on, window.ballast_ranges)
    n[4] = _element_ranges(window.triple_segment, on, window.triple_ranges)
    n[DOF_RANGES] = _moving_dof_ranges(dof_segment, on, vel.shape[0], window.dof_ranges)
