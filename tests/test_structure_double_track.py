"""A double-track deck (``structure.layout.tracks: 2``): two tracks on the same girders.

Statics of a simply supported span with fork supports (``bearing.rigid``: z, y and roll fixed at
both ends), the tracks at e = +2.5 m and -2.5 m from the shear centre, a static axle load P at
midspan. References (beam theory, independent of the code; as tests/test_structure_eccentric_track.py):

* St Venant torsion of a bar fixed against roll at both ends under a torque T = P e applied
  about midspan: between a support and the loaded zone theta(x) = -(T/2) x / (G J); a load on
  the right-hand track (e < 0) twists the girder the other way.
* Equal loads on both tracks: the torques P e and -P e cancel, the girder does not roll
  (antisymmetric torques on a structure symmetric about its axis); the vertical deflection is
  twice one load's, 2 P L^3 / (48 E I) (superposition; vertical bending and torsion decouple
  where shear centre and centroid coincide).

Tolerances: 1 % for the torsion (the rails' differential bending and the slabs' torsion carry
less than 0.1 % of the torque, tests/test_structure_eccentric_track.py), 3 % for P L^3/48EI
(the CA mortar spreads the load over a few metres, about 1 %), 0.5 % against the single-track
model (the second track adds its own bending stiffness, slab and rails: about 2e-4 of the
girder's E I), and 1e-6 of one load's roll for the cancellation (round-off).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import linalg as splinalg

from ttbpipe.structure import build_structure
from ttbpipe.structure.kernels import structure_accelerations
from ttbpipe.structure.monitors import compile_monitors, default_monitors
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh
from ttbpipe.structure.static import StructureStatic

AXLE_LOAD_N = 170_000.0
SPAN_M = 32.0
APPROACH_M = 30.0
OFFSETS_M = (2.5, -2.5)


def _model(tracks: int):
    girder = {"element_length_m": 1.0, "max_mode_frequency_hz": 1.0e5}
    girder.update({"track_offsets_m": list(OFFSETS_M)} if tracks == 2
                  else {"track_offset_m": OFFSETS_M[0]})
    return build_structure({
        "layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M], "tracks": tracks,
                   "approach_track": "slab", "bridge_track": "slab"},
        "bearing": {"rigid": True}, "girder": girder})


def _solve(model, tracks: tuple[int, ...]):
    """Static axle load at midspan on each of ``tracks`` (half on each of its two rails)."""
    xs = model.layout.rail_x
    x = xs[int(np.argmin(np.abs(xs - (APPROACH_M + 0.5 * SPAN_M))))]
    force = np.zeros(model.n_dof)
    mesh = rail_mesh(model.packed, 0.0)
    for t in tracks:
        for rail in (2 * t, 2 * t + 1):
            add_rail_point_load(mesh, rail, x, -0.5 * AXLE_LOAD_N, 0.0, 0.0, force)
    return StructureStatic(model).solve(force), x


def _girder(model, u, x):
    """(vertical, roll) of the girder's shear centre at x."""
    red = model.spans[0]
    o = model.dof_info["span_dof0"][0]
    rz, _, rr = red.rows_at(x)
    return rz @ u[o:o + red.n], rr @ u[o:o + red.n]


@pytest.fixture(scope="module")
def double():
    model = _model(2)
    return model, {k: _solve(model, k) for k in ((0,), (1,), (0, 1))}


def test_each_track_twists_the_girder_by_its_own_offset(double):
    model, sol = double
    g = model.config["girder"]
    gj = g["E_Pa"] / (2.0 * (1.0 + g["poisson"])) * g["J_m4"]
    for track, e in enumerate(OFFSETS_M):
        u, _ = sol[(track,)]
        for fraction in (0.125, 0.25):
            x = APPROACH_M + fraction * SPAN_M
            expected = -0.5 * AXLE_LOAD_N * e * fraction * SPAN_M / gj
            assert _girder(model, u, x)[1] == pytest.approx(expected, rel=0.01), (track, x)


def test_equal_loads_on_both_tracks_cancel_the_roll_and_double_the_deflection(double):
    model, sol = double
    g = model.config["girder"]
    gj = g["E_Pa"] / (2.0 * (1.0 + g["poisson"])) * g["J_m4"]
    one_roll = 0.5 * AXLE_LOAD_N * OFFSETS_M[0] * 0.25 * SPAN_M / gj
    u, x_load = sol[(0, 1)]
    for fraction in (0.125, 0.25, 0.5):
        _, roll = _girder(model, u, APPROACH_M + fraction * SPAN_M)
        assert abs(roll) < 1e-6 * one_roll, fraction
    z_both, _ = _girder(model, u, x_load)
    closed_form = 2.0 * AXLE_LOAD_N * SPAN_M ** 3 / (48.0 * g["E_Pa"] * g["Iy_m4"])
    assert -z_both == pytest.approx(closed_form, rel=0.03)
    # against one axle on the single-track deck: twice its deflection
    single = _model(1)
    u1, x1 = _solve(single, (0,))
    assert x1 == x_load
    assert z_both == pytest.approx(2.0 * _girder(single, u1, x1)[0], rel=0.005)


def test_double_track_kernel_matches_the_assembled_matrices():
    """structure_accelerations == M^-1 (f - K u - C v) with the sparse matrices assembled from
    the same arrays (as tests/test_structure_kernels.py), with ballasted approaches: four rails,
    two slabs, two sets of sleepers and ballast, CA at both offsets (1e-10 relative)."""
    m = build_structure({"layout": {"approach_length_m": 12.0, "spans_m": [16.0, 12.0],
                                    "approach_track": "ballasted", "tracks": 2},
                         "girder": {"element_length_m": 2.0}})
    M, K, C = m.matrices()
    rng = np.random.default_rng(1)
    u, v, f = (rng.normal(size=m.n_dof) for _ in range(3))
    acc = np.zeros(m.n_dof)
    structure_accelerations(m.packed, u, v, f, acc)
    ref = splinalg.spsolve(M.tocsc(), f - K @ u - C @ v)
    assert np.max(np.abs(acc - ref)) <= 1e-10 * np.max(np.abs(ref))
    assert abs(K - K.T).max() <= 1e-9 * abs(K).max()


def test_double_track_default_monitors():
    """Deck monitors under each rail of each track at its offset, the deck edges, both rails
    and the slab of each track; every name unique and compiled."""
    m = build_structure({"layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                                    "approach_track": "slab", "tracks": 2},
                         "girder": {"deck_width_m": 12.0}})
    specs = default_monitors(m)
    half_gauge = 0.5 * m.config["fastener"]["rail_centre_distance_m"]
    deck = {s["name"]: s["lateral_offset_m"] for s in specs if s.get("deck_surface")}
    assert deck == pytest.approx({
        "deck_track1_left_span1_mid": 2.5 + half_gauge, "deck_track1_right_span1_mid": 2.5 - half_gauge,
        "deck_track2_left_span1_mid": -2.5 + half_gauge, "deck_track2_right_span1_mid": -2.5 - half_gauge,
        "deck_edge_left_span1_mid": 6.0, "deck_edge_right_span1_mid": -6.0})
    rails = {s["name"]: s["rail"] for s in specs if s["kind"] == "rail"}
    assert rails == {"rail_track1_left_span1_mid": 0, "rail_track1_right_span1_mid": 1,
                     "rail_track2_left_span1_mid": 2, "rail_track2_right_span1_mid": 3}
    assert {s["name"]: s["track"] for s in specs if s["kind"] == "slab"} == {
        "slab_track1_span1_mid": 0, "slab_track2_span1_mid": 1}
    names = compile_monitors(m, specs).names
    assert len(names) == len(set(names))


def test_track_offsets_are_validated():
    base = {"layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M], "tracks": 2}}
    with pytest.raises(ValueError, match="one per track"):
        build_structure({**base, "girder": {"track_offsets_m": [2.5]}})
    with pytest.raises(ValueError, match="track_offsets_m"):
        build_structure({**base, "girder": {"track_offset_m": 2.5}})
    with pytest.raises(ValueError, match="on top of each other"):
        build_structure({**base, "girder": {"track_offsets_m": [1.0, -1.0]}})
    with pytest.raises(ValueError, match="1 or 2"):
        build_structure({"layout": {"tracks": 3}})
