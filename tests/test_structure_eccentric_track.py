"""A track off the girder's axis (seed paper eq. 24): statics against closed forms.

A simply supported span with fork supports (``bearing.rigid``: z, y and roll fixed at both
ends) under a static vertical axle load P at midspan, on a track ``e`` to the left of the shear
centre. The deck carries the torque T = P e (statics). References (beam theory, independent of
the code):

* St Venant torsion of a bar fixed against roll at both ends under a torque applied
  symmetrically about midspan: each support takes T/2, so between a support and the loaded
  zone the roll is linear, theta(x) = -(T/2) x / (G J) (negative: the load presses the left
  side down; z + e roll is the vertical at e). At the quarter point theta = -T L / (8 G J)
  whatever the spread of the torque over the CA mortar near midspan (it spreads over a few
  metres, well inside the middle half).
* The vertical bending of the girder does not depend on e (vertical and torsion decouple in
  a beam whose shear centre and centroid coincide).

Tolerance 1 %: the other paths that carry torque to the abutments (the rails' differential
bending, the slab's own torsion) are below 0.1 % of the girder's G J / L here (rails:
2 EI_r (s/2)^2 (pi/L)^2 = 3e4 N m / rad per m against G J / L^2 = 1.5e7), and all fixed-interface
modes of the 1 m girder mesh are kept, so the reduced girder is the full finite-element one
(linear torsion elements are exact for nodal torques).
"""

from __future__ import annotations

import numpy as np
import pytest

from ttbpipe.structure import build_structure
from ttbpipe.structure.monitors import default_monitors
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh
from ttbpipe.structure.static import StructureStatic

AXLE_LOAD_N = 170_000.0
SPAN_M = 32.0
APPROACH_M = 30.0


def _model(track_offset_m: float):
    return build_structure({
        "layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                   "approach_track": "slab", "bridge_track": "slab"},
        "bearing": {"rigid": True},
        "girder": {"track_offset_m": track_offset_m, "element_length_m": 1.0,
                   "max_mode_frequency_hz": 1.0e5},
    })


def _girder_rows(model, x: float):
    red = model.spans[0]
    o = model.dof_info["span_dof0"][0]
    return slice(o, o + red.n), red.rows_at(x)


def _static_axle_at_midspan(model):
    xs = model.layout.rail_x
    x_mid = APPROACH_M + 0.5 * SPAN_M
    i = int(np.argmin(np.abs(xs - x_mid)))
    force = np.zeros(model.n_dof)
    for rail in range(2):
        add_rail_point_load(rail_mesh(model.packed, 0.0), rail, xs[i], -0.5 * AXLE_LOAD_N, 0.0,
                            0.0, force)
    return StructureStatic(model).solve(force), xs[i]


@pytest.fixture(scope="module")
def solutions():
    return {e: (_model(e), *_static_axle_at_midspan(_model(e))) for e in (0.0, 2.5)}


def test_eccentric_track_twists_the_girder_as_a_fork_supported_bar(solutions):
    e = 2.5
    model, u, x_load = solutions[e]
    g = model.config["girder"]
    shear_modulus = g["E_Pa"] / (2.0 * (1.0 + g["poisson"]))
    torque = AXLE_LOAD_N * e
    for fraction in (0.125, 0.25):
        sl, (_, _, rr) = _girder_rows(model, APPROACH_M + fraction * SPAN_M)
        expected = -0.5 * torque * fraction * SPAN_M / (shear_modulus * g["J_m4"])
        assert rr @ u[sl] == pytest.approx(expected, rel=0.01), fraction
    # a centred track does not twist the girder
    model0, u0, _ = solutions[0.0]
    sl, (_, _, rr) = _girder_rows(model0, APPROACH_M + 0.25 * SPAN_M)
    assert abs(rr @ u0[sl]) < 1e-6 * abs(expected)


def test_eccentric_track_leaves_vertical_bending_unchanged(solutions):
    (m0, u0, x), (m1, u1, _) = solutions[0.0], solutions[2.5]
    sl, (rz, _, _) = _girder_rows(m0, x)
    z0 = rz @ u0[sl]
    sl, (rz, _, _) = _girder_rows(m1, x)
    assert rz @ u1[sl] == pytest.approx(z0, rel=0.01)
    # simply supported beam, central point load (Timoshenko): P L^3 / (48 E I), within 3 %
    # (the CA mortar spreads the load over a few metres, which lowers the peak by about 1 %)
    g = m0.config["girder"]
    assert -z0 == pytest.approx(AXLE_LOAD_N * SPAN_M ** 3 / (48 * g["E_Pa"] * g["Iy_m4"]),
                                rel=0.03)


def test_default_deck_monitors_sit_under_the_rails_of_the_offset_track(solutions):
    model, _, _ = solutions[2.5]
    half_gauge = 0.5 * model.config["fastener"]["rail_centre_distance_m"]
    offsets = {m["name"]: m["lateral_offset_m"] for m in default_monitors(model)
               if m.get("deck_surface")}
    assert offsets == pytest.approx({"deck_left_span1_mid": 2.5 + half_gauge,
                                     "deck_right_span1_mid": 2.5 - half_gauge})


def test_deck_edge_monitors_follow_the_deck_width():
    """With girder.deck_width_m, the default monitors add both deck edges (vertical), where the
    roll of an eccentric load shows most: z + (W/2) roll, larger than under the track."""
    model = build_structure({
        "layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                   "approach_track": "slab", "bridge_track": "slab"},
        "girder": {"track_offset_m": 2.5, "deck_width_m": 12.0}})
    edges = {m["name"]: m["lateral_offset_m"] for m in default_monitors(model)
             if m["name"].startswith("deck_edge")}
    assert edges == {"deck_edge_left_span1_mid": 6.0, "deck_edge_right_span1_mid": -6.0}
    centred = build_structure({"layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                                          "approach_track": "slab", "bridge_track": "slab"}})
    assert not [m for m in default_monitors(centred) if m["name"].startswith("deck_edge")]
