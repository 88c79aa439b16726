"""Build the track-bridge structure: DOF numbering, masses, elements and links, packed arrays.

Entry points: :func:`build_structure`, :func:`apply_factors`, :func:`carrier_positions`.
Sparse global matrices for modal analysis, the time-step check and the tests:
:meth:`StructureModel.matrices`. Decisions and sources: docs/structure.md.

The parts: the line geometry in :mod:`.layout`, the carriers of the random properties in
:mod:`.carriers`, the link accumulator in :mod:`.links`, the global matrices in :mod:`.matrices`;
their public names stay importable from here. Rail 0 is the left rail (+y), rail 1 the right;
on a double-track deck (``layout.tracks: 2``) track k has rails 2k (left) and 2k + 1 (right),
its own slab, pads, CA mortar (at its own offset on the same girders) and approaches.
"""

from __future__ import annotations

import copy
import logging
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from . import properties as P
from .carriers import (CARRIER_PARAMETERS, PARAMETER_CARRIER, carrier_positions, factored,
                       nominal_properties)
from .damping import girder_damping_ratio
from .girder import SpanReduction, reduce_span
from .kernels import StructurePacked, group_triple_entries
from .layout import Layout, make_layout
from .pier import PierReduction, pier_from_config
from .shape_functions import hermite, hermite_shape
from .plan import PLACEMENTS, plan_eccentricity_m, span_is_curved
from .links import LinkAccumulator
from .matrices import assemble_matrices, ballast_link_rows, pad_link_rows

__all__ = ["CARRIER_PARAMETERS", "PARAMETER_CARRIER", "GAUSS3", "Layout", "StructureModel",
           "apply_factors", "assemble_matrices", "ballast_link_rows", "build_structure",
           "carrier_positions", "make_layout", "nominal_properties", "pad_link_rows"]

log = logging.getLogger(__name__)

#: 3-point Gauss-Legendre rule on [0, 1]: (xi, weight)
GAUSS3 = ((0.5 - np.sqrt(0.15), 5 / 18), (0.5, 8 / 18), (0.5 + np.sqrt(0.15), 5 / 18))


@dataclass
class StructureModel:
    """The assembled structure: configuration, geometry, per-carrier properties, packed arrays."""

    config: dict
    layout: Layout
    properties: dict
    packed: StructurePacked
    spans: list                      # SpanReduction per span
    dof_info: dict                   # offsets of each DOF block
    slab_elements: np.ndarray        # (n, 2) x of slab element ends
    slab_element_node0: np.ndarray   # first DOF of node a of each slab element
    fixed: np.ndarray                # bool mask of fixed DOFs
    link_kinds: list                 # kind of each CSR link (bearing, pier)
    triple_kinds: list = field(default_factory=list)   # "ca" per triple (pads: pad_*, ballast: bal_*)
    piers: list = field(default_factory=list)   # PierReduction per pier of a given height
    cant: tuple | None = None        # (x knots m, cant angle knots rad) of the track on the deck
    plan: tuple | None = None        # (x knots m, curvature knots 1/m) of the track in plan
    slab_element_track: np.ndarray | None = None   # track of each slab element (None: all 0)
    # what is derived from the model alone (global matrices, stability analysis, static
    # factorisation), computed on first use: a model is not changed after assembly
    # (apply_factors and dataclasses.replace give new models, with an empty cache)
    _derived: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_tracks(self) -> int:
        return self.layout.n_tracks

    @property
    def n_dof(self) -> int:
        return int(self.packed.n_dof)

    @property
    def rail_x_range(self) -> tuple[float, float]:
        return float(self.layout.rail_x[0]), float(self.layout.rail_x[-1])

    @property
    def rail_head_height_m(self) -> float:
        return float(self.config["rail"]["head_height_m"])

    def derived(self, key: Any, compute):
        """``compute()`` once per model and ``key``; later calls return the same object (the
        callers treat it as read-only). Samples of a study that share the structure share
        one model (:func:`ttbpipe.simulation.setup.prepare`), so its matrices, stability
        analysis and static factorisation are made once per process."""
        if key not in self._derived:
            self._derived[key] = compute()
        return self._derived[key]

    def matrices(self):
        """Global sparse (M, K, C) assembled from the same arrays the kernels use (once per
        model; read-only)."""
        return self.derived("matrices", lambda: assemble_matrices(self.packed))

    def stable_time_step(self, safety: float = 0.9) -> float:
        from ..timestepping.limits import stable_time_step
        return stable_time_step(self, safety)["dt_s"]

    def check_time_step(self, dt: float) -> None:
        from ..timestepping.limits import check_time_step
        check_time_step(self, dt)


def build_structure(config: Mapping[str, Any] | None = None,
                    factors: Mapping[str, np.ndarray] | None = None,
                    cant: tuple[np.ndarray, np.ndarray] | None = None,
                    plan: tuple[np.ndarray, np.ndarray] | None = None) -> StructureModel:
    """Build the structure from a ``structure:`` config section (defaults fill missing keys).

    ``cant``: the track's cant angle along x as knots (x m, angle rad; + = left rail up),
    piecewise linear (:func:`ttbpipe.vehicle.curving.cant_knots` of ``simulation.layout``). The
    track (rails, pads, slab) is then modelled in the canted track plane and the CA mortar joins
    it to the level girder through the rotation of the deck's motion into that plane (docstring
    of :func:`_ca_deck_rows`); None or all zero: level track.
    ``plan``: the track's curvature along x as knots (x m, curvature 1/m; + = to the left),
    piecewise linear (:func:`ttbpipe.vehicle.curving.plan_knots`): on the spans it reaches the
    track's centre line runs off the straight girders' axes by the curve's offset from each
    span's chord (:mod:`ttbpipe.structure.plan`, ``girder.placement_on_curves``); None or all
    zero: tangent track.
    """
    cfg = P.resolve(config)
    layout = make_layout(cfg)
    props = nominal_properties(cfg, layout)
    if factors:
        props = factored(props, factors)
    if cant is not None:
        xk, tk = (np.asarray(a, dtype=float) for a in cant)
        cant = None if not np.any(tk != 0.0) else (xk, tk)
    if plan is not None:
        xk, kk = (np.asarray(a, dtype=float) for a in plan)
        plan = None if not np.any(kk != 0.0) else (xk, kk)
    return _assemble(cfg, layout, props, cant, plan)


def apply_factors(model_or_properties, factors: Mapping[str, np.ndarray]):
    """Multiply per-carrier properties by random-field factors.

    ``factors``: {parameter name: array over the carriers of its kind}, names from
    :data:`CARRIER_PARAMETERS`. A rail/fastener array of length n applies to both rails, of length
    2n to rail 0 then rail 1. Given a :class:`StructureModel`, returns a NEW re-assembled model;
    given a properties dict, returns a new dict.
    """
    if isinstance(model_or_properties, StructureModel):
        m = model_or_properties
        return _assemble(m.config, m.layout, factored(m.properties, factors), m.cant, m.plan)
    return factored(model_or_properties, factors)


def _ca_deck_rows(rz: np.ndarray, ry: np.ndarray, rr: np.ndarray, e_track: float,
                  h_deck: float, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows (over a span's DOFs) of the deck's vertical and lateral motion under the track's
    centre line, in the track plane's axes.

    The deck point at lateral offset e (``e_track``) and height h (``h_deck``) above the shear
    centre moves by z = (rz + e rr) q vertically and y = (ry - h rr) q laterally (paper eq. 24;
    rz, ry, rr: the girder's vertical, lateral and roll rows at that x). A track canted by theta
    (+ = left rail up) has its normal z_t and in-plane lateral y_t axes rotated about x:
    z_t = z cos theta - y sin theta, y_t = y cos theta + z sin theta, so the CA mortar (normal
    and in-plane springs between the slab and the deck) carries the track-plane loads of the
    train into the girder's vertical and lateral directions: on a curve at balanced cant the
    wheel forces are normal to the track plane and the girder receives the weight downwards
    and the centrifugal force outwards. Roll is unchanged. theta = 0 returns the level rows as
    they were (bit for bit). ``e_track``, ``theta``: numbers, or columns (k, 1) against rows
    (k, n) of k points."""
    z = rz + e_track * rr
    y = ry - h_deck * rr
    canted = np.asarray(theta) != 0.0
    if not np.any(canted):
        return z, y
    c, s = np.cos(theta), np.sin(theta)
    return np.where(canted, c * z - s * y, z), np.where(canted, c * y + s * z, y)


def _plan_offsets_at_ca_points(slab_elems: list, spans: list, curved_span: list,
                               plan: tuple | None, placement: str) -> np.ndarray:
    """(n_elements, 3) offset of the track's centre line from the straight girder's axis at the
    CA quadrature points of the bridge's slab elements (:mod:`ttbpipe.structure.plan`), one
    vectorised evaluation per curved span; a point on the common end of two spans belongs to
    the first, as in the assembly's ``span_rows``. Zero elsewhere."""
    out = np.zeros((len(slab_elems), len(GAUSS3)))
    if not any(curved_span):
        return out
    xa = np.array([e[0] for e in slab_elems])
    xb = np.array([e[1] for e in slab_elems])
    bridge = np.array([e[4] == "bridge" for e in slab_elems])[:, None]
    x = xa[:, None] + np.array([g[0] for g in GAUSS3])[None, :] * (xb - xa)[:, None]
    taken = ~np.broadcast_to(bridge, x.shape).copy()
    for s, red in enumerate(spans):
        here = ~taken & (red.start_m - 1e-9 <= x) & (x <= red.start_m + red.length_m + 1e-9)
        taken |= here
        if curved_span[s] and here.any():
            out[here] = plan_eccentricity_m(plan, red.start_m, red.length_m, x[here], placement)
    return out


def _check_rails_on_deck(girder: Mapping[str, Any], layout: Layout, spans: list,
                         plan: tuple | None, placement: str, half_gauge: float) -> None:
    """With ``girder.deck_width_m``, every rail must lie on the deck: the track offsets plus,
    on a span under a curve, the track's offset from the straight girder's axis
    (:mod:`ttbpipe.structure.plan`, at 33 points of the span). Raises ValueError naming the
    track and the span, with the remedies."""
    width = girder.get("deck_width_m")
    if width is None:
        return
    for s, red in enumerate(spans):
        x = red.start_m + np.linspace(0.0, red.length_m, 33)
        plan_m = plan_eccentricity_m(plan, red.start_m, red.length_m, x, placement)
        for t, e_track in enumerate(layout.track_offsets_m):
            reach = float(np.max(np.abs(e_track + plan_m))) + half_gauge
            if reach > 0.5 * float(width):
                curve = (f", of which up to {float(np.max(np.abs(plan_m))):.3f} m from the curve "
                         "in plan (girder.placement_on_curves, simulation.layout)"
                         if np.any(plan_m != 0.0) else "")
                raise ValueError(
                    f"track {t + 1} on span {s + 1}: a rail lies {reach:.3f} m from the girder's "
                    f"axis{curve}, beyond the deck's half width {0.5 * float(width):.3f} m "
                    "(structure.girder.deck_width_m); check girder.track_offset(s)_m and the "
                    "deck width, or on a curve a larger radius or placement_on_curves: "
                    "split_versine")


#: The rail pads' groups in the packed structure's order (kernels._pad_forces): on a slab
#: element, on a sleeper, on rigid ground.
PAD_KINDS = ("slab", "ballasted", "rigid")


def _pad_arrays(pads: Mapping[str, list]) -> dict[str, np.ndarray]:
    """The packed structure's pad fields from {kind: [(rail DOF, seat a, seat b, (xi, L, e),
    k3, c3), ...]} lists, the groups in :data:`PAD_KINDS` order."""
    pad_all = [q for kind in PAD_KINDS for q in pads[kind]]
    ints = lambda col: np.array([q[col] for q in pad_all], dtype=np.int64)  # noqa: E731
    floats = lambda col: (np.array([q[col] for q in pad_all], dtype=float).ravel()  # noqa: E731
                          if pad_all else np.zeros(0))
    return dict(pad_rail=ints(0), pad_seat_a=ints(1), pad_seat_b=ints(2), pad_geom=floats(3),
                pad_k=floats(4), pad_c=floats(5),
                pad_group=np.array([len(pads[kind]) for kind in PAD_KINDS], dtype=np.int64))


def _pad_seat_elements(x: np.ndarray, zone: str, track: int, slab_elems: list,
                       elem_zone: np.ndarray, elem_track: np.ndarray) -> np.ndarray:
    """The slab element under each rail node at ``x`` of ``zone`` on ``track``: the first of
    that zone and track whose ends hold x (1e-9 m tolerance), else the one with the nearest
    end."""
    cand = np.flatnonzero((elem_zone == zone) & (elem_track == track))
    xa = np.array([slab_elems[j][0] for j in cand], dtype=float)[None, :]
    xb = np.array([slab_elems[j][1] for j in cand], dtype=float)[None, :]
    x = x[:, None]
    inside = (xa <= x + 1e-9) & (x <= xb + 1e-9)
    nearest = np.argmin(np.minimum(np.abs(xa - x), np.abs(xb - x)), axis=1)
    return cand[np.where(inside.any(axis=1), np.argmax(inside, axis=1), nearest)]


def _rail_pads(layout: Layout, bridge_kind: str, approach_kind: str, slab_elems: list,
               props: Mapping[str, np.ndarray], n_tracks: int, half_gauge: float, bf2: float,
               sleeper_dof0: int, ns_track: int, sleeper_of_node: np.ndarray
               ) -> dict[str, np.ndarray]:
    """The packed structure's rail pad fields (kernels._pad_forces), every pad at once, in the
    order of :func:`_rail_pads_by_node` and bit for bit its arrays
    (tests/test_structure_matrices.py): grouped by :data:`PAD_KINDS`, within a group rail node
    by node, track by track, rail 2t (offset +e) before rail 2t + 1 (-e). A pad has its rail DOF, its
    seat (a slab element's end nodes with (xi, L) of the node on it, a sleeper, or none), the
    rail's lateral offset e and (k, c) vertical, lateral and roll (the foot's width:
    k b_f^2 / 12)."""
    n_rn = layout.rail_x.size
    zones = np.asarray(layout.rail_zone)
    kinds = np.where(zones == "bridge", bridge_kind, approach_kind)
    elem_zone = np.array([e[4] for e in slab_elems])
    elem_track = np.array([e[5] for e in slab_elems], dtype=np.int64)
    side = np.arange(2)[None, None, :]
    e_r = np.where(side == 0, half_gauge, -half_gauge)
    parts: dict[str, list] = {name: [] for name in ("pad_rail", "pad_seat_a", "pad_seat_b",
                                                     "pad_geom", "pad_k", "pad_c")}
    for kind in PAD_KINDS:
        nodes = np.flatnonzero(kinds == kind)
        node = nodes[:, None, None]                     # (node, track, side)
        track = np.arange(n_tracks)[None, :, None]
        rail = 2 * track + side
        shape = (nodes.size, n_tracks, 2)
        kz, cz, ky, cy = (props[f"pad_{name}"][rail, node] for name in ("kz", "cz", "ky", "cy"))
        xi, length = np.zeros(shape), np.zeros(shape)     # a seat's position: slab pads only
        if kind == "slab":
            seat = np.zeros((nodes.size, n_tracks, 1), dtype=np.int64)
            for t in range(n_tracks):
                for zone in np.unique(zones[nodes]):
                    here = np.flatnonzero(zones[nodes] == zone)
                    seat[here, t, 0] = _pad_seat_elements(layout.rail_x[nodes[here]], str(zone),
                                                          t, slab_elems, elem_zone, elem_track)
            xa = np.array([e[0] for e in slab_elems], dtype=float)[seat]
            length = np.array([e[1] for e in slab_elems], dtype=float)[seat] - xa
            xi = np.clip((layout.rail_x[node] - xa) / length, 0.0, 1.0)
            seat_a = np.array([e[2] for e in slab_elems], dtype=np.int64)[seat]
            seat_b = np.array([e[3] for e in slab_elems], dtype=np.int64)[seat]
        elif kind == "ballasted":
            seat_a = sleeper_dof0 + 3 * (track * ns_track + sleeper_of_node[node])
            seat_b = np.int64(-1)
        else:   # rigid ground
            seat_a = seat_b = np.int64(-1)
        full = lambda a: np.broadcast_to(a, shape)  # noqa: E731
        parts["pad_rail"].append(full(5 * (rail * n_rn + node)))
        parts["pad_seat_a"].append(full(seat_a))
        parts["pad_seat_b"].append(full(seat_b))
        parts["pad_geom"].append(np.stack([full(xi), full(length), full(e_r)], axis=-1))
        parts["pad_k"].append(np.stack([kz, ky, kz * bf2], axis=-1))
        parts["pad_c"].append(np.stack([cz, cy, cz * bf2], axis=-1))
    arrays = {name: np.concatenate([np.ravel(a) for a in values]).astype(
        np.int64 if name in ("pad_rail", "pad_seat_a", "pad_seat_b") else float)
        for name, values in parts.items()}
    arrays["pad_group"] = np.array([a.size for a in parts["pad_rail"]], dtype=np.int64)
    return arrays


def _rail_pads_by_node(layout: Layout, bridge_kind: str, approach_kind: str, slab_elems: list,
                       props: Mapping[str, np.ndarray], n_tracks: int, half_gauge: float,
                       bf2: float, sleeper_dof0: int, ns_track: int, sleeper_of_node: np.ndarray
                       ) -> dict[str, np.ndarray]:
    """:func:`_rail_pads` one rail node at a time: the obviously correct reference of
    tests/test_structure_matrices.py."""
    n_rn = layout.rail_x.size
    pads: dict[str, list] = {kind: [] for kind in PAD_KINDS}
    slab_x = np.array([[e[0], e[1]] for e in slab_elems]).reshape(-1, 2)
    elem_zone = np.array([e[4] for e in slab_elems])
    elem_track = np.array([e[5] for e in slab_elems], dtype=np.int64)
    for i, x in enumerate(layout.rail_x):
        zone = layout.rail_zone[i]
        kind = bridge_kind if zone == "bridge" else approach_kind
        for t in range(n_tracks):
            seat = None
            if kind == "slab":
                cand = np.flatnonzero((elem_zone == zone) & (elem_track == t))
                xa = slab_x[cand, 0]; xb = slab_x[cand, 1]
                inside = np.flatnonzero((xa <= x + 1e-9) & (x <= xb + 1e-9))
                j = cand[inside[0]] if inside.size else cand[int(np.argmin(
                    np.minimum(np.abs(xa - x), np.abs(xb - x))))]
                xa_j, xb_j, da, db, _, _ = slab_elems[j]
                Ls = xb_j - xa_j
                xi = float(np.clip((x - xa_j) / Ls, 0.0, 1.0))
                seat = (da, db, xi, Ls)
            for r in (2 * t, 2 * t + 1):
                e_r = half_gauge if r % 2 == 0 else -half_gauge
                rd = 5 * (r * n_rn + i)
                kz, cz = props["pad_kz"][r, i], props["pad_cz"][r, i]
                ky, cy = props["pad_ky"][r, i], props["pad_cy"][r, i]
                k3, c3 = (kz, ky, kz * bf2), (cz, cy, cz * bf2)
                if kind == "slab":
                    da, db, xi, Ls = seat
                    pads["slab"].append((rd, da, db, (xi, Ls, e_r), k3, c3))
                elif kind == "ballasted":
                    sd = sleeper_dof0 + 3 * (t * ns_track + sleeper_of_node[i])
                    pads["ballasted"].append((rd, sd, -1, (0.0, 0.0, e_r), k3, c3))
                else:  # rigid ground
                    pads["rigid"].append((rd, -1, -1, (0.0, 0.0, e_r), k3, c3))
    return _pad_arrays(pads)


def _ca_foundation_coefficients(slab_elems: list, props: Mapping[str, np.ndarray], cfg: dict
                                ) -> tuple[np.ndarray, ...]:
    """(kz, cz, ky, cy) per slab element, per metre: the CA mortar's on the bridge, the
    foundation's (``slab_on_subgrade``, scaled by the element's CA factors) elsewhere."""
    bridge = np.array([e[4] == "bridge" for e in slab_elems], dtype=bool)
    sub, ca = cfg["slab_on_subgrade"], cfg["ca"]
    out = []
    for name, key in (("kz", "N_m2"), ("cz", "Ns_m2"), ("ky", "N_m2"), ("cy", "Ns_m2")):
        values = np.array(props[f"ca_{name}"], dtype=float)[:bridge.size]
        ground = ~bridge
        values[ground] = float(sub[f"foundation_{name}_{key}"]) * (
            values[ground] / float(ca[f"{name}_{key}"]))
        out.append(values)
    return tuple(out)


def _ca_triples(links: LinkAccumulator, slab_elems: list, spans: list, span_dof0: list,
                props: Mapping[str, np.ndarray], cfg: dict, track_offsets: np.ndarray,
                cant, plan_offset: np.ndarray, curved_span: list, t_half: float, b2: float,
                h_deck: float) -> None:
    """The CA mortar (bridge) or foundation (slab on subgrade) link triples of every slab
    element, added to ``links`` in the order of :func:`_ca_triples_by_point` (element by
    element, its three quadrature points in turn) with the same DOFs and coefficients, bit for
    bit (tests/test_structure_matrices.py), computed for all points at once.

    A consistent distributed foundation: 3-point Gauss quadrature of k N^T N over the element,
    the slab's Hermite (vertical, lateral) and linear (roll) shape functions against the girder's
    rows at each point. A point's DOFs are, in this order: the slab's vertical ends and slopes,
    its roll ends, the girder span's DOFs (on the bridge), the slab's lateral ends and slopes;
    those whose three coefficients are all zero are left out."""
    n_el = len(slab_elems)
    if n_el == 0:
        return
    xa = np.array([e[0] for e in slab_elems], dtype=float)
    xb = np.array([e[1] for e in slab_elems], dtype=float)
    da = np.array([e[2] for e in slab_elems], dtype=np.int64)
    db = np.array([e[3] for e in slab_elems], dtype=np.int64)
    bridge = np.array([e[4] == "bridge" for e in slab_elems], dtype=bool)
    e_track = track_offsets[np.array([e[5] for e in slab_elems], dtype=np.int64)]
    kz, cz, ky, cy = _ca_foundation_coefficients(slab_elems, props, cfg)
    n_gauss = len(GAUSS3)
    xi = np.array([g[0] for g in GAUSS3])[None, :]
    Ls = (xb - xa)[:, None]
    x = xa[:, None] + xi * Ls                             # (n_el, n_gauss) quadrature points
    w = np.array([g[1] for g in GAUSS3])[None, :] * Ls
    N = hermite.py_func(np.broadcast_to(xi, x.shape), np.broadcast_to(Ls, x.shape))
    # the span under each bridge point: the first that holds it (a common end: the first span)
    span_of = np.full(x.shape, -1, dtype=np.int64)
    for s, red in enumerate(spans):
        here = (bridge[:, None] & (span_of < 0) & (red.start_m - 1e-9 <= x)
                & (x <= red.start_m + red.length_m + 1e-9))
        span_of[here] = s
    n_points = x.size
    n_girder = np.array([red.n for red in spans] + [0], dtype=np.int64)[span_of.ravel()]
    width = 10 + int(n_girder.max())
    dofs = np.zeros((n_points, width), dtype=np.int64)
    coef = np.zeros((n_points, width, 3))
    valid = np.zeros((n_points, width), dtype=bool)
    a = np.repeat(da, n_gauss)
    b = np.repeat(db, n_gauss)
    xi_p = np.broadcast_to(xi, x.shape).ravel()
    dofs[:, :6] = np.stack([a, a + 1, b, b + 1, a + 4, b + 4], axis=1)
    valid[:, :6] = True
    for col in range(4):
        coef[:, col, 0] += N[col].ravel()
    coef[:, 4, 1] += t_half * (1 - xi_p)
    coef[:, 5, 1] += t_half * xi_p
    coef[:, 4, 2] += 1 - xi_p
    coef[:, 5, 2] += xi_p
    lateral = (a + 2, a + 3, b + 2, b + 3)
    x_p, span_p = x.ravel(), span_of.ravel()
    for s in [-1, *range(len(spans))]:
        points = np.flatnonzero(span_p == s)
        if not points.size:
            continue
        n = 0 if s < 0 else spans[s].n
        if n:
            rz, ry, rr = spans[s].rows_at_many(x_p[points])
            # the deck under the track's centre line (paper eq. 24), in the track plane; on a
            # curve the centre line runs off the straight girder's axis
            e_here = e_track[points // n_gauss]
            if curved_span[s]:
                e_here = e_here + plan_offset.ravel()[points]
            theta = (np.zeros(points.size) if cant is None
                     else np.interp(x_p[points], cant[0], cant[1]))
            deck_z, deck_y = _ca_deck_rows(rz, ry, rr, e_here[:, None], h_deck, theta[:, None])
            dofs[points, 6:6 + n] = span_dof0[s] + np.arange(n)
            valid[points, 6:6 + n] = True
            coef[points, 6:6 + n, 0] += -deck_z
            coef[points, 6:6 + n, 1] += -deck_y
            coef[points, 6:6 + n, 2] += -rr
        for col, dof in enumerate(lateral):
            dofs[points, 6 + n + col] = dof[points]
            valid[points, 6 + n + col] = True
            coef[points, 6 + n + col, 1] += N[col].ravel()[points]
    keep = valid & np.any(coef != 0.0, axis=2)
    k3 = np.stack([kz[:, None] * w, ky[:, None] * w, kz[:, None] * w * b2], axis=2)
    c3 = np.stack([cz[:, None] * w, cy[:, None] * w, cz[:, None] * w * b2], axis=2)
    links.add_triples(keep.sum(axis=1), dofs[keep], coef[keep], k3.reshape(-1, 3),
                      c3.reshape(-1, 3), "ca")


def _ca_triples_by_point(links: LinkAccumulator, slab_elems: list, spans: list,
                         span_dof0: list, props: Mapping[str, np.ndarray], cfg: dict,
                         track_offsets: np.ndarray, cant, plan_offset: np.ndarray,
                         curved_span: list, t_half: float, b2: float, h_deck: float) -> None:
    """:func:`_ca_triples` one quadrature point at a time: the obviously correct reference of
    tests/test_structure_matrices.py."""
    kz_all, cz_all, ky_all, cy_all = _ca_foundation_coefficients(slab_elems, props, cfg)

    def span_rows(x: float):
        """(span index, z row, y row, roll row) of the girder under x, or None."""
        for s, red in enumerate(spans):
            if red.start_m - 1e-9 <= x <= red.start_m + red.length_m + 1e-9:
                return s, *red.rows_at(x)
        return None

    for j, (xa, xb, da, db, zone, t) in enumerate(slab_elems):
        e_track = float(track_offsets[t])
        kz, cz, ky, cy = kz_all[j], cz_all[j], ky_all[j], cy_all[j]
        Ls = xb - xa
        for g_index, (xi_g, w_g) in enumerate(GAUSS3):
            x = xa + xi_g * Ls
            w = w_g * Ls
            N = hermite_shape(xi_g, Ls)
            zd, zc = [da, da + 1, db, db + 1], list(N)
            zd += [da + 4, db + 4]; zc += [0.0, 0.0]
            yd = [da + 2, da + 3, db + 2, db + 3, da + 4, db + 4]
            yc = [*N, t_half * (1 - xi_g), t_half * xi_g]
            rdofs, rc = [da + 4, db + 4], [1 - xi_g, xi_g]
            g = span_rows(x) if zone == "bridge" else None
            if g is not None:
                s, rz, ry, rr = g
                o = span_dof0[s]
                idx = list(range(o, o + spans[s].n))
                theta = 0.0 if cant is None else float(np.interp(x, cant[0], cant[1]))
                e_here = e_track
                if curved_span[s]:
                    e_here = e_track + float(plan_offset[j, g_index])
                deck_z, deck_y = _ca_deck_rows(rz, ry, rr, e_here, h_deck, theta)
                zd, zc = zd + idx, zc + list(-deck_z)
                yd, yc = yd + idx, yc + list(-deck_y)
                rdofs, rc = rdofs + idx, rc + list(-rr)
            links.add_triple([(zd, zc), (yd, yc), (rdofs, rc)],
                             (kz * w, ky * w, kz * w * b2), (cz * w, cy * w, cz * w * b2), "ca")


def _assemble(cfg: dict, layout: Layout, props: Mapping[str, np.ndarray],
              cant: tuple[np.ndarray, np.ndarray] | None = None,
              plan: tuple[np.ndarray, np.ndarray] | None = None) -> StructureModel:
    """DOF numbering, lumped masses, beams, links and span blocks -> StructureModel
    (``cant``, ``plan``: as :func:`build_structure`)."""
    cfg = copy.deepcopy(cfg)
    lay = cfg["layout"]
    rail_c, fas, slab_c, g_c = cfg["rail"], cfg["fastener"], cfg["slab"], cfg["girder"]
    brg, pier_c, bal = cfg["bearing"], cfg["pier"], cfg["ballasted"]
    has_track = lay["bridge_track"] != "none"
    if lay["bridge_track"] not in ("slab", "rigid", "none"):
        raise ValueError(f"structure.layout.bridge_track: {lay['bridge_track']!r}; expected "
                         "slab | rigid | none")
    if lay["approach_track"] not in ("ballasted", "slab", "rigid"):
        raise ValueError(f"structure.layout.approach_track: {lay['approach_track']!r}; expected "
                         "ballasted | slab | rigid")

    # ---- DOF numbering -------------------------------------------------------------------
    n_rn = layout.rail_x.size if has_track else 0
    n_tracks = layout.n_tracks
    n_rails = 2 * n_tracks if has_track else 0
    off = {"rail": 0}
    n = n_rails * 5 * n_rn
    off["slab"] = n
    # slab units track after track (each track its own slab on the same units)
    slab_node_dof0, slab_unit_track = [], []
    for t in range(n_tracks):
        for _, xs in (layout.slab_units if has_track else []):
            slab_node_dof0.append(n + 5 * np.arange(xs.size))
            slab_unit_track.append(t)
            n += 5 * xs.size
    ballasted_nodes = np.flatnonzero(layout.rail_zone == "approach") \
        if has_track and lay["approach_track"] == "ballasted" else np.zeros(0, np.int64)
    off["sleeper"] = n
    sleeper_of_node = -np.ones(n_rn, dtype=np.int64)
    sleeper_of_node[ballasted_nodes] = np.arange(ballasted_nodes.size)
    ns_track = ballasted_nodes.size        # sleepers per track; track t's are t*ns_track + j
    n += 3 * n_tracks * ns_track
    off["ballast"] = n
    n += 2 * n_tracks * ns_track
    n_piers = max(layout.n_spans - 1, 0)
    tall_piers = pier_c.get("height_m") is not None
    off["pier"] = n
    if not tall_piers:
        n += 3 * n_piers
    n_diag = n
    off["span"] = n

    # ---- girder spans ----------------------------------------------------------------------
    spans: list[SpanReduction] = []
    span_dof0 = []
    nu_g = float(g_c["poisson"])
    e0 = 0
    for s, (x0, L) in enumerate(zip(layout.span_starts_m, layout.span_lengths_m)):
        ne = layout.girder_n_el[s]
        sl = slice(e0, e0 + ne)
        e0 += ne
        E = props["girder_E"][sl]
        mass = props["girder_mass"][sl]
        Iy, Iz = props["girder_Iy"][sl], props["girder_Iz"][sl]
        roll_inertia = mass / float(g_c["area_m2"]) * (Iy + Iz)
        red = reduce_span(float(x0), float(L), ne, E, E / (2 * (1 + nu_g)), mass, Iy, Iz,
                          np.full(ne, float(g_c["J_m4"])), roll_inertia,
                          girder_damping_ratio(float(L), g_c), str(g_c["damping_model"]),
                          g_c["rayleigh_frequencies_hz"],
                          float(g_c["max_mode_frequency_hz"]),
                          int(g_c["min_modes_per_direction"]))
        spans.append(red)
        span_dof0.append(n)
        n += red.n
    # piers of a given height: dense reduced blocks after the spans; else 3 lumped DOFs each
    piers: list[PierReduction] = []
    pier_top_dof0 = []
    for p in range(n_piers):
        if tall_piers:
            piers.append(pier_from_config(pier_c))
            pier_top_dof0.append(n)
            n += piers[-1].n
        else:
            pier_top_dof0.append(off["pier"] + 3 * p)
    n_dof = n
    fixed = np.zeros(n_dof, dtype=bool)
    if brg["rigid"]:
        for o in span_dof0:
            fixed[o:o + 6] = True

    # ---- lumped masses -------------------------------------------------------------------
    mass = np.zeros(n_diag)
    beam_a, beam_b, beam_L, beam_EIv, beam_EIl, beam_GK = [], [], [], [], [], []
    if has_track:
        h = float(layout.rail_x[1] - layout.rail_x[0])
        rho_I0_per_m = float(rail_c["density_kg_m3"]) * float(rail_c["I0_m4"])
        m_ref = float(rail_c["mass_kg_m"])
        GK0, E0 = float(rail_c["GK_Nm2"]), float(rail_c["E_Pa"])
        rot = float(rail_c["rotary_inertia_scaling"]) / 78.0   # HRZ lumping: m L^3 / 78
        for r in range(n_rails):
            m_el = props["rail_mass"][r]
            node0 = 5 * r * n_rn + 5 * np.arange(n_rn - 1)
            for a_dofs, sign in ((node0, 0), (node0 + 5, 1)):
                np.add.at(mass, a_dofs, 0.5 * m_el * h)
                np.add.at(mass, a_dofs + 2, 0.5 * m_el * h)
                np.add.at(mass, a_dofs + 1, rot * m_el * h ** 3)
                np.add.at(mass, a_dofs + 3, rot * m_el * h ** 3)
                # roll inertia rho*I0 scales with the mass factor (same density change)
                np.add.at(mass, a_dofs + 4, 0.5 * rho_I0_per_m * (m_el / m_ref) * h)
            beam_a.append(node0); beam_b.append(node0 + 5); beam_L.append(np.full(n_rn - 1, h))
            E = props["rail_E"][r]
            beam_EIv.append(E * props["rail_Iy"][r]); beam_EIl.append(E * props["rail_Iz"][r])
            beam_GK.append(GK0 * E / E0)   # G = E / (2 (1 + nu)) scales with E
        # slab beams: rigid cross-section 3-D beam (vertical, lateral bending, roll)
        b_s, t_s = float(slab_c["width_m"]), float(slab_c["thickness_m"])
        E_s, rho_s = float(slab_c["E_Pa"]), float(slab_c["density_kg_m3"])
        G_s = E_s / (2 * (1 + float(slab_c["poisson"])))
        K_tor = b_s * t_s ** 3 / 3 * (1 - 0.63 * t_s / b_s)   # Roark, thin rectangle
        m_s = rho_s * b_s * t_s
        J_s = rho_s * (b_s * t_s ** 3 + t_s * b_s ** 3) / 12
        rot_s = float(slab_c["rotary_inertia_scaling"]) / 78.0
        rot_sl = float(slab_c["lateral_rotary_inertia_scaling"]) / 78.0
        for (zone, xs), d0 in zip(layout.slab_units * n_tracks, slab_node_dof0):
            Ls = np.diff(xs)
            for a_dofs in (d0[:-1], d0[1:]):
                np.add.at(mass, a_dofs, 0.5 * m_s * Ls)
                np.add.at(mass, a_dofs + 2, 0.5 * m_s * Ls)
                np.add.at(mass, a_dofs + 1, rot_s * m_s * Ls ** 3)
                np.add.at(mass, a_dofs + 3, rot_sl * m_s * Ls ** 3)
                np.add.at(mass, a_dofs + 4, 0.5 * J_s * Ls)
            beam_a.append(d0[:-1]); beam_b.append(d0[1:]); beam_L.append(Ls)
            beam_EIv.append(np.full(Ls.size, E_s * b_s * t_s ** 3 / 12))
            beam_EIl.append(np.full(Ls.size, E_s * t_s * b_s ** 3 / 12))
            beam_GK.append(np.full(Ls.size, G_s * K_tor))
        ns = n_tracks * ns_track
        sl0 = off["sleeper"] + 3 * np.arange(ns)
        mass[sl0] = float(bal["sleeper_mass_kg"])
        mass[sl0 + 1] = float(bal["sleeper_mass_kg"])
        mass[sl0 + 2] = float(bal["sleeper_roll_inertia_kgm2"])
        mass[off["ballast"]:off["ballast"] + 2 * ns] = float(bal["ballast_mass_kg"])
    if not tall_piers:
        p0 = off["pier"] + 3 * np.arange(n_piers)
        mass[p0] = float(pier_c["mass_kg"]); mass[p0 + 1] = float(pier_c["mass_kg"])
        mass[p0 + 2] = float(pier_c["roll_inertia_kgm2"])
    if np.any(mass <= 0):
        raise RuntimeError(f"internal: {int(np.sum(mass <= 0))} diagonal DOFs without mass")
    inv_mass = np.zeros(n_dof)
    inv_mass[:n_diag] = 1.0 / mass
    inv_mass[fixed] = 0.0

    # ---- links ------------------------------------------------------------------------------
    links = LinkAccumulator()
    slab_elems = []        # (xa, xb, dof_a, dof_b, zone, track)
    for (zone, xs), d0, t in zip(layout.slab_units * n_tracks if has_track else [],
                                 slab_node_dof0, slab_unit_track):
        for i in range(xs.size - 1):
            slab_elems.append((xs[i], xs[i + 1], d0[i], d0[i + 1], zone, t))
    slab_x = np.array([[e[0], e[1]] for e in slab_elems]).reshape(-1, 2)

    # rail pads, compact form (kernels._pad_forces), grouped slab / ballasted / rigid:
    # (rail DOF, seat a, seat b, (xi, L, e), k3, c3) per pad
    pad_arrays = _pad_arrays({kind: [] for kind in PAD_KINDS})
    bal_sleeper = bal_block = bal_next = np.zeros(0, dtype=np.int64)
    half_gauge = 0.5 * float(fas["rail_centre_distance_m"])
    d_f = float(rail_c["foot_depth_m"])
    t_half = 0.5 * float(slab_c["thickness_m"])
    if has_track:
        bf2 = float(rail_c["foot_width_m"]) ** 2 / 12.0
        pad_arrays = _rail_pads(layout, lay["bridge_track"], lay["approach_track"], slab_elems,
                                props, n_tracks, half_gauge, bf2, off["sleeper"], ns_track,
                                sleeper_of_node)
        # ballast (kernels._ballast_forces): per sleeper its DOFs, its blocks, whether the next
        # sleeper is adjacent (shear springs between neighbouring blocks); track after track,
        # each on its own ballast (no shear between the tracks' blocks)
        ns = n_tracks * ns_track
        bal_sleeper = off["sleeper"] + 3 * np.arange(ns, dtype=np.int64)
        bal_block = off["ballast"] + 2 * np.arange(ns, dtype=np.int64)
        next_one = np.zeros(ns_track, dtype=np.int64)
        if ns_track > 1:
            next_one[:-1] = (np.diff(ballasted_nodes) == 1).astype(np.int64)
        bal_next = np.tile(next_one, n_tracks)
        # CA mortar (bridge) or foundation (slab on subgrade), per slab element
        b2 = float(slab_c["width_m"]) ** 2 / 12.0
        placement = str(g_c["placement_on_curves"])
        if placement not in PLACEMENTS:
            raise ValueError(f"structure.girder.placement_on_curves {placement!r}; expected one "
                             f"of {', '.join(PLACEMENTS)}")
        curved_span = [span_is_curved(plan, red.start_m, red.length_m) for red in spans]
        _check_rails_on_deck(g_c, layout, spans, plan, placement, half_gauge)
        plan_offset = _plan_offsets_at_ca_points(slab_elems, spans, curved_span, plan, placement)
        _ca_triples(links, slab_elems, spans, span_dof0, props, cfg,
                    np.asarray(layout.track_offsets_m, dtype=float), cant, plan_offset,
                    curved_span, t_half, b2, float(g_c["deck_height_m"]))
    # bearings: girder end (z, y, roll) -> pier (y, z, roll) or abutment (ground)
    if not brg["rigid"]:
        eb = 0.5 * float(brg["lateral_spacing_m"])
        hb = float(brg["height_m"])
        for s in range(layout.n_spans):
            o = span_dof0[s]
            for end in range(2):
                gz, gy, gr = o + 3 * end, o + 3 * end + 1, o + 3 * end + 2
                pier = s - 1 if end == 0 else s
                has_pier = 0 <= pier < n_piers
                pd = pier_top_dof0[pier] if has_pier else -1
                for e_b in (eb, -eb):
                    zd, zc = [gz, gr], [1.0, e_b]
                    if has_pier:
                        zd += [pd + 1, pd + 2]; zc += [-1.0, -e_b]
                    links.add(zd, zc, brg["kz_N_m"], brg["cz_Ns_m"], "bearing_z")
                yd, yc = [gy, gr], [1.0, hb]
                if has_pier:
                    yd += [pd]; yc += [-1.0]
                links.add(yd, yc, 2 * float(brg["ky_N_m"]), 2 * float(brg["cy_Ns_m"]),
                          "bearing_y")
    for p in range(n_piers if not tall_piers else 0):
        pd = off["pier"] + 3 * p
        links.add([pd], [1.0], pier_c["ky_N_m"], pier_c["cy_Ns_m"], "pier_y")
        links.add([pd + 1], [1.0], pier_c["kz_N_m"], pier_c["cz_Ns_m"], "pier_z")
        links.add([pd + 2], [1.0], pier_c["kroll_Nm_rad"], pier_c["croll_Nms_rad"], "pier_roll")

    # ---- span blocks ----------------------------------------------------------------------------
    mat0, Kf, Cf, Mi = [], [], [], []
    pos = 0
    # dense blocks: the girder spans, then the piers of a given height
    block_dof0 = list(span_dof0) + (pier_top_dof0 if tall_piers else [])
    blocks = list(spans) + piers
    for o, red in zip(block_dof0, blocks):
        free = ~fixed[o:o + red.n]
        minv = np.zeros((red.n, red.n))
        minv[np.ix_(free, free)] = np.linalg.inv(red.M[np.ix_(free, free)])
        mat0.append(pos); pos += red.n * red.n
        Kf.append(red.K.ravel()); Cf.append(red.C.ravel()); Mi.append(minv.ravel())
    ptr, ldof, lcoef, lk, lc = links.arrays()
    tptr, tdof, tcoef, tk, tc = links.triple_arrays()
    tri_group_end, tri_kernel_dof, tri_kernel_coef, tri_run_of_three = group_triple_entries(
        tptr, tdof, tcoef)
    cat = lambda parts, dt=float: (np.concatenate(parts).astype(dt) if parts  # noqa: E731
                                   else np.zeros(0, dtype=dt))
    packed = StructurePacked(
        n_dof=int(n_dof), n_diag=int(n_diag), inv_mass=inv_mass,
        beam_dof_a=cat(beam_a, np.int64), beam_dof_b=cat(beam_b, np.int64),
        beam_L=cat(beam_L), beam_EIv=cat(beam_EIv), beam_EIl=cat(beam_EIl),
        beam_GK=cat(beam_GK),
        link_ptr=ptr, link_dof=ldof, link_coef=lcoef, link_k=lk, link_c=lc,
        span_dof0=np.array(block_dof0, dtype=np.int64),
        span_n=np.array([red.n for red in blocks], dtype=np.int64),
        span_mat0=np.array(mat0, dtype=np.int64), span_K=cat(Kf), span_C=cat(Cf),
        span_Minv=cat(Mi), span_scratch=np.zeros(max([red.n for red in blocks] + [1])),
        n_rails=n_rails, rail_x0=float(layout.rail_x[0]),
        rail_dx=float(layout.rail_x[1] - layout.rail_x[0]), rail_n_nodes=int(n_rn),
        rail_dof0=5 * n_rn * np.arange(max(n_rails, 2), dtype=np.int64),
        tri_ptr=tptr, tri_dof=tdof, tri_coef=tcoef, tri_k=tk, tri_c=tc,
        **pad_arrays,
        pad_foot_depth=d_f, pad_seat_half_thickness=t_half,
        bal_sleeper=bal_sleeper, bal_block=bal_block, bal_next=bal_next,
        bal_k=np.array([bal["ballast_kz_N_m"], bal["subgrade_k_N_m"], bal["shear_k_N_m"],
                        bal["ballast_ky_N_m"]], dtype=float),
        bal_c=np.array([bal["ballast_cz_Ns_m"], bal["subgrade_c_Ns_m"], bal["shear_c_Ns_m"],
                        bal["ballast_cy_Ns_m"]], dtype=float),
        bal_half_gauge=half_gauge,
        tri_group_end=tri_group_end, tri_kernel_dof=tri_kernel_dof,
        tri_kernel_coef=tri_kernel_coef,
        tri_run_of_three=tri_run_of_three,
    )
    info = dict(off, n_diag=n_diag, n_dof=n_dof, span_dof0=span_dof0, n_piers=n_piers,
                pier_top_dof0=pier_top_dof0, block_dof0=block_dof0,
                block_mass=[red.M for red in blocks],
                n_sleepers=int(n_tracks * ns_track), n_rail_nodes=n_rn,
                slab_node_dof0=slab_node_dof0, span_block_mass=[red.M for red in spans])
    node_a = np.array([e[2] for e in slab_elems], dtype=np.int64)
    return StructureModel(config=cfg, layout=layout, properties=dict(props), packed=packed,
                          spans=spans, piers=piers, dof_info=info, slab_elements=slab_x,
                          slab_element_node0=node_a, fixed=fixed,
                          link_kinds=[links.kind[i] for i in links.order],
                          triple_kinds=list(links.tri_kind), cant=cant, plan=plan,
                          slab_element_track=np.array([e[5] for e in slab_elems],
                                                      dtype=np.int64))
