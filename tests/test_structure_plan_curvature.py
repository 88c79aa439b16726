"""A track curved in plan on straight spans: its eccentricity on the girder, against closed forms.

References (geometry and beam theory, independent of the code):

* the centre line of a circular arc of radius R entered at x0 lies (x - x0)^2 / (2 R) off the
  tangent, that of a clothoid of length l_t into R lies s^3 / (6 R l_t) off it (s from its
  start; the small-angle forms that the track frame uses); the arc's offset from a chord of
  length L is the parabola x' (L - x') / (2 R), the versine L^2 / (8 R) at mid-chord;
* St Venant torsion of a girder held against roll at both ends (fork supports) under a
  distributed torque t(x): G J theta'' = t(x), theta(0) = theta(L) = 0. A uniform vertical load
  q on a track whose centre line is e(x) to the left of the shear centre gives t = q e (the sign
  of tests/test_structure_eccentric_track.py: a load left of the axis rolls the girder
  negatively between a support and the load). For e = -a x (L - x) + b:
  theta(x) = (q a / G J) (L^3 x / 12 - L x^3 / 6 + x^4 / 12) + (q b / 2 G J) (x^2 - L x).

Tolerance 1 % on the roll, as for the eccentric straight track (the other torque paths, the
rails' differential bending and the slab's torsion, are below 0.1 % of the girder's; the CA
mortar spreads the nodal loads of the rails over a few metres, which a uniform load does not
see away from the span's ends).
"""

from __future__ import annotations

import numpy as np
import pytest

from ttbpipe.structure import build_structure
from ttbpipe.structure.monitors import default_monitors
from ttbpipe.structure.plan import plan_eccentricity_m
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh
from ttbpipe.structure.static import StructureStatic
from ttbpipe.vehicle.curving import centreline_offset, plan_knots

SPAN_M = 32.0
APPROACH_M = 30.0
RADIUS_M = 1000.0
LOAD_N_PER_M = 60_000.0   # about a high-speed train's weight per metre


def _arc(direction: str = "left") -> dict:
    """One circular arc over the whole model (no transitions)."""
    return {"curves": [{"start_x_m": -10.0, "transition_m": 0.0, "length_m": 200.0,
                        "radius_m": RADIUS_M, "direction": direction}]}


def _config(placement: str) -> dict:
    return {"layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                       "approach_track": "slab", "bridge_track": "slab"},
            "bearing": {"rigid": True},
            "girder": {"element_length_m": 1.0, "max_mode_frequency_hz": 1.0e5,
                       "placement_on_curves": placement}}


def test_centre_line_offset_of_an_arc_and_a_clothoid_against_the_closed_forms():
    x0, lt, radius = 20.0, 60.0, 2500.0
    xs, ks = plan_knots({"curves": [{"start_x_m": x0, "transition_m": lt, "length_m": 100.0,
                                     "radius_m": radius}]})
    s = np.linspace(0.0, lt, 13)
    assert centreline_offset(xs, ks, x0 + s) == pytest.approx(s ** 3 / (6 * radius * lt),
                                                              rel=1e-12, abs=1e-15)
    # on the arc: the clothoid's end offset and heading carried on, plus the arc's parabola
    u = np.linspace(0.0, 100.0, 11)
    y_end, heading_end = lt ** 2 / (6 * radius), lt / (2 * radius)
    assert centreline_offset(xs, ks, x0 + lt + u) == pytest.approx(
        y_end + heading_end * u + u ** 2 / (2 * radius), rel=1e-12)


@pytest.mark.parametrize("direction", ["left", "right"])
def test_eccentricity_is_the_arc_offset_from_the_chord_and_its_split(direction):
    plan = plan_knots(_arc(direction))
    sign = 1.0 if direction == "left" else -1.0
    x = APPROACH_M + np.linspace(0.0, SPAN_M, 9)
    u = x - APPROACH_M
    off_chord = -sign * u * (SPAN_M - u) / (2 * RADIUS_M)   # a left curve bows to the right
    versine = SPAN_M ** 2 / (8 * RADIUS_M)
    chord = plan_eccentricity_m(plan, APPROACH_M, SPAN_M, x, "chord")
    split = plan_eccentricity_m(plan, APPROACH_M, SPAN_M, x, "split_versine")
    assert chord == pytest.approx(off_chord, abs=1e-12)
    assert split == pytest.approx(off_chord + sign * 0.5 * versine, abs=1e-12)
    # the split placement: half the versine inside over the bearings, half outside mid-span
    assert split[[0, 4, 8]] == pytest.approx(sign * versine * np.array([0.5, -0.5, 0.5]))
    with pytest.raises(ValueError, match="placement_on_curves"):
        plan_eccentricity_m(plan, APPROACH_M, SPAN_M, x, "tangent")


def _uniform_load_roll(model) -> tuple[np.ndarray, np.ndarray]:
    """Roll of the girder at the quarter points under LOAD_N_PER_M on the span's rail nodes."""
    xs = model.layout.rail_x
    on_span = np.flatnonzero((xs > APPROACH_M) & (xs < APPROACH_M + SPAN_M))
    spacing = float(np.median(np.diff(xs[on_span])))
    force = np.zeros(model.n_dof)
    mesh = rail_mesh(model.packed, 0.0)
    for i in on_span:
        for rail in range(2):
            add_rail_point_load(mesh, rail, xs[i], -0.5 * LOAD_N_PER_M * spacing, 0.0, 0.0,
                                force)
    u = StructureStatic(model).solve(force)
    red = model.spans[0]
    o = model.dof_info["span_dof0"][0]
    at = APPROACH_M + SPAN_M * np.array([0.25, 0.5, 0.75])
    roll = np.array([red.rows_at(x)[2] @ u[o:o + red.n] for x in at])
    return at - APPROACH_M, roll


@pytest.mark.parametrize("placement,direction", [("chord", "left"), ("split_versine", "left"),
                                                 ("chord", "right")])
def test_uniform_load_on_a_curved_track_twists_the_straight_girder_as_theory(placement,
                                                                            direction):
    model = build_structure(_config(placement), plan=plan_knots(_arc(direction)))
    x, roll = _uniform_load_roll(model)
    g = model.config["girder"]
    gj = g["E_Pa"] / (2.0 * (1.0 + g["poisson"])) * g["J_m4"]
    sign = 1.0 if direction == "left" else -1.0
    a = sign / (2 * RADIUS_M)                          # e = -a x (L - x) + b
    b = a * SPAN_M ** 2 / 8 if placement == "split_versine" else 0.0
    q, L = LOAD_N_PER_M, SPAN_M
    expected = (q * a / gj * (L ** 3 * x / 12 - L * x ** 3 / 6 + x ** 4 / 12)
                + q * b / (2 * gj) * (x ** 2 - L * x))
    assert roll == pytest.approx(expected, rel=0.01)
    # a tangent track on the axis does not roll the girder at all
    _, roll0 = _uniform_load_roll(build_structure(_config(placement)))
    assert np.all(np.abs(roll0) < 1e-6 * np.abs(expected).max())


def test_curves_off_the_bridge_leave_the_structure_bit_for_bit():
    tangent = build_structure(_config("split_versine"))
    elsewhere = build_structure(_config("split_versine"), plan=plan_knots(
        {"curves": [{"start_x_m": APPROACH_M + SPAN_M + 1.0, "transition_m": 20.0,
                     "length_m": 50.0, "radius_m": 800.0}]}))
    assert elsewhere.plan is not None
    for name, a, b in zip(tangent.packed._fields, tangent.packed, elsewhere.packed):
        assert np.array_equal(a, b), name
    curved = build_structure(_config("split_versine"), plan=plan_knots(_arc()))
    assert not np.array_equal(tangent.packed.tri_coef, curved.packed.tri_coef)


@pytest.mark.parametrize("tracks", [1, 2])
def test_deck_monitors_under_the_rails_follow_the_curved_track(tracks):
    cfg = _config("chord")
    cfg["layout"]["tracks"] = tracks
    model = build_structure(cfg, plan=plan_knots(_arc()))
    straight = build_structure(cfg)
    versine = SPAN_M ** 2 / (8 * RADIUS_M)
    curved = {m["name"]: m["lateral_offset_m"] for m in default_monitors(model)
              if m.get("deck_surface")}
    level = {m["name"]: m["lateral_offset_m"] for m in default_monitors(straight)
             if m.get("deck_surface")}
    assert curved.keys() == level.keys()
    for name, e in level.items():
        assert curved[name] == pytest.approx(e - versine, abs=1e-12), name   # left curve: right


def test_monitors_added_for_the_assessment_sit_on_the_curved_track():
    """The deck monitors a case gets for the EN 1990 deck checks come from the structure on the
    case's own layout, as the run's structure does (not from a straight one)."""
    from ttbpipe.assessment.monitors import case_with_deck_monitors

    case = {"structure": _config("chord"), "simulation": {"layout": _arc()}}
    monitors = {m["name"]: m for m in case_with_deck_monitors(case)["monitors"]}
    straight = {m["name"]: m for m in case_with_deck_monitors(
        {"structure": _config("chord")})["monitors"]}
    versine = SPAN_M ** 2 / (8 * RADIUS_M)
    deck = [name for name, m in straight.items() if m.get("deck_surface")]
    assert deck
    # the studies' path: the monitors the EN 1990 profile adds to every sample's case
    from ttbpipe.assessment.study import run_case

    en1990 = {"standard": ["en1990"], "options": {"en1990": {"twist": True}}}
    in_study = {m["name"]: m for m in run_case(case, en1990)["monitors"]}
    for name in deck:
        assert monitors[name]["lateral_offset_m"] == pytest.approx(
            straight[name]["lateral_offset_m"] - versine, abs=1e-12), name
        assert in_study[name]["lateral_offset_m"] == monitors[name]["lateral_offset_m"], name


def test_a_rail_off_the_deck_is_refused_with_its_track_span_and_remedy():
    """With girder.deck_width_m every rail must lie on the deck; a curve's offset from the
    straight girder counts (a 32 m span on R = 100 m bows 1.28 m off its chord; the rails are
    0.7525 m either side of the track's centre line, fastener.rail_centre_distance_m 1.505)."""
    cfg = _config("chord")
    cfg["girder"]["deck_width_m"] = 3.0
    build_structure(cfg, plan=plan_knots(_arc()))     # 0.128 + 0.7525 m < 1.5 m: on the deck
    tight = {"curves": [{"start_x_m": -10.0, "transition_m": 0.0, "length_m": 100.0,
                         "radius_m": 100.0}]}
    with pytest.raises(ValueError, match=r"track 1 on span 1: a rail lies 2\.03\d m .*1\.280 m "
                                         r"from the curve in plan.*split_versine"):
        build_structure(cfg, plan=plan_knots(tight))
    cfg["girder"]["track_offset_m"] = 1.0             # 1.0 + 0.7525 > 1.5: off the deck
    with pytest.raises(ValueError, match=r"track 1 on span 1: a rail lies 1\.75\d m from the "
                                         r"girder's axis, beyond"):
        build_structure(cfg)
