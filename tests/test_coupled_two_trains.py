"""Coupled runs on a double-track deck: a train on either track in either direction, and two
trains meeting on the bridge.

The bridge (three 32 m spans between 30 m slab approaches, the tracks at +2.5 m and -2.5 m from
the girders' axis) is symmetric under a half-turn about the vertical axis through the middle
of the middle span (x -> L - x, y -> -y), which takes track 0 to track 1, rail 0 to rail 3 and
rail 1 to rail 2, and a train running +x to one running -x with its own axes turned round
(its left wheel on the right rail of its track). Under that half-turn vertical displacements
are unchanged and lateral displacements and rolls change sign; span 1 and span 3 swap. So
(reference: the symmetry, independent of the code):

* the same train on track 0 running +x and on track 1 running -x over mirrored
  irregularities (z_left(x) <-> z_right(L - x), y_left(x) <-> -y_right(L - x)) gives the same
  wheel forces in its own axes (P and Q of its left wheel, ...) and mirrored girder responses:
  vertical equal, lateral and roll of opposite sign, span 1 <-> span 3;
* with both trains in the same run (they meet at the middle of the middle span), the system
  is its own mirror image: the two trains' wheel forces are equal at every instant, and at the
  middle of the middle span the girder neither moves laterally nor rolls.

The irregularity is a synthetic TB/T 3352 profile on all four channels, so the lateral
dynamics (wheelset hunting motion, lateral wheel forces, the girder's lateral and roll
response) are excited: a sign error of the -x placement (lateral kinematics, lateral forces,
roll, rails swapped) breaks the symmetry (a wrong sign of the lateral kinematics or of the
lateral loads makes the -x run diverge). Tolerance 1e-6 of each history's peak (round-off of a
mesh symmetric to ~1e-12; measured 3e-13 for the wheel forces, 3e-11 for the girder).

A third test measures what the second track changes for one train (the added mass of its
slab and rails lowers the girder's first vertical frequency; Rayleigh's added-mass estimate
f2/f1 = sqrt((m_g + m_t)/(m_g + 2 m_t)) with m_t the track's mass per metre, within 0.5 %).

Run time: about 10 s with the numba cache warm (three 1-car runs of 15 000 steps, one of them
with two cars); about 60 s on a cold cache, which compiles the coupled kernels and the
two-train loop.
"""

from __future__ import annotations

import numpy as np
import pytest

from ttbpipe.irregularity.track_input import Irregularity
from ttbpipe.simulation.coupled import prepare, run_coupled
from ttbpipe.structure import build_structure
from ttbpipe.structure.modal import modal_analysis

TOL = 1e-6
SPANS = [32.0, 32.0, 32.0]


def _monitors():
    out = []
    for s in range(3):
        out.append({"name": f"g{s + 1}", "kind": "girder", "span": s, "position": 0.5,
                    "directions": ["z", "y", "roll"],
                    "quantities": ["displacement", "acceleration"]})
    return out


def _case(track_index: int, direction: int, second: dict | None = None) -> dict:
    case = {"structure": {"layout": {"approach_length_m": 30.0, "spans_m": SPANS,
                                     "approach_track": "slab", "tracks": 2}},
            "train": {"composition": ["trailer"]},
            "simulation": {"speed_kmh": 300.0, "time_step_s": 1e-4, "track_index": track_index,
                           "direction": direction},
            "irregularity": {"source": "synthetic", "seed": 7, "scale": 1.0},
            "monitors": _monitors()}
    if second is not None:
        case["second_train"] = second
    return case


def _mirror(irr: Irregularity, length: float) -> Irregularity:
    """The profile of the half-turned track: z_left'(x) = z_right(L - x), z_right' = z_left,
    y_left'(x) = -y_right(L - x), y_right' = -y_left; slopes d/dx f(L - x) = -f'(L - x)."""
    n = irr.values.shape[1]
    x0 = length - (irr.x0 + (n - 1) * irr.dx)
    swap = [1, 0, 3, 2]
    sign = np.array([1.0, 1.0, -1.0, -1.0])[:, None]
    values = sign * irr.values[swap, ::-1]
    slopes = -sign * irr.slopes[swap, ::-1]
    return Irregularity(x0, irr.dx, np.ascontiguousarray(values), np.ascontiguousarray(slopes))


@pytest.fixture(scope="module")
def runs():
    setup_a = prepare(_case(0, 1))
    length = setup_a.structure.rail_x_range[1]
    assert setup_a.structure.rail_x_range[0] == 0.0
    mirrored = _mirror(setup_a.irregularity, length)
    table_a, summary_a = run_coupled(_case(0, 1), track=setup_a.irregularity)
    table_b, summary_b = run_coupled(_case(1, -1), track=mirrored)
    table_ab, summary_ab = run_coupled(_case(0, 1, {}), track=setup_a.irregularity,
                                       second_track=mirrored)
    return {"A": (table_a, summary_a), "B": (table_b, summary_b), "AB": (table_ab, summary_ab),
            "length": length}


def _wheel_columns(table):
    return [c for c in table.columns if c.startswith("car") and c.endswith(("_P_N", "_Q_N"))]


def _close(a, b, scale):
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= TOL * scale


def test_the_train_running_minus_x_on_track_1_mirrors_the_train_on_track_0(runs):
    (ta, sa), (tb, sb) = runs["A"], runs["B"]
    assert sb["trains"] == [{"track_index": 1, "direction": -1, "speed_kmh": 300.0,
                             "x_lead0_m": pytest.approx(runs["length"] - sa["trains"][0][
                                 "x_lead0_m"])}]
    assert np.allclose(tb["x_lead_m"], runs["length"] - ta["x_lead_m"], atol=1e-9)
    for col in _wheel_columns(ta):
        assert _close(tb[col], ta[col], np.abs(ta[col]).max()), col
    # the lateral forces are not negligible: the irregularity excites the lateral dynamics
    assert sa["max_wheel_lateral_force_N"] > 2e3
    for s_a, s_b in ((1, 3), (2, 2), (3, 1)):
        for q in ("disp_mm", "acc_m_s2"):
            za, zb = ta[f"g{s_a}_z_{q}"], tb[f"g{s_b}_z_{q}"]
            assert _close(zb, za, np.abs(za).max()), (s_a, q)
            ya, yb = ta[f"g{s_a}_y_{q}"], tb[f"g{s_b}_y_{q}"]
            assert _close(yb, -ya, np.abs(ya).max()), (s_a, q)
        rq = ("disp_mrad", "acc_rad_s2")
        for q in rq:
            ra, rb = ta[f"g{s_a}_roll_{q}"], tb[f"g{s_b}_roll_{q}"]
            assert _close(rb, -ra, np.abs(ra).max()), (s_a, q)


def test_two_trains_meeting_mirror_each_other(runs):
    (ta, sa), (tab, sab) = runs["A"], runs["AB"]
    assert [t["track_index"] for t in sab["trains"]] == [0, 1]
    assert [t["direction"] for t in sab["trains"]] == [1, -1]
    assert np.allclose(tab["train2_x_lead_m"], runs["length"] - tab["x_lead_m"], atol=1e-9)
    for col in _wheel_columns(ta):
        assert _close(tab[f"train2_{col}"], tab[col], np.abs(tab[col]).max()), col
    # at the middle of the middle span the girder does not move laterally nor roll; its
    # vertical response is about twice one train's
    for q, rq in (("disp_mm", "disp_mrad"), ("acc_m_s2", "acc_rad_s2")):
        assert np.abs(tab[f"g2_y_{q}"]).max() <= TOL * np.abs(ta[f"g2_y_{q}"]).max()
        assert np.abs(tab[f"g2_roll_{rq}"]).max() <= TOL * np.abs(ta[f"g2_roll_{rq}"]).max()
    peak_both, peak_one = np.abs(tab["g2_z_disp_mm"]).max(), np.abs(ta["g2_z_disp_mm"]).max()
    assert 1.8 * peak_one < peak_both < 2.2 * peak_one
    # the run's indices cover both trains; each train's are named
    assert sab["max_wheel_vertical_force_N"] == max(sab["train1_max_wheel_vertical_force_N"],
                                                    sab["train2_max_wheel_vertical_force_N"])
    assert sab["train2_max_wheel_vertical_force_N"] == pytest.approx(
        sab["train1_max_wheel_vertical_force_N"], rel=TOL)
    static_2 = np.array(list(sab["second_train"]["static_wheel_load_N"].values()))
    static_1 = np.array(list(sab["static_wheel_load_N"].values()))
    assert np.abs(static_2 - static_1).max() <= TOL * static_1.max()


def test_the_second_track_lowers_the_span_frequency_by_its_mass():
    """One 32 m span with its track(s), on its bearings: the first vertical girder mode of the
    double-track deck against the single-track deck's, scaled by Rayleigh's added-mass ratio
    (the track moves with the girder at 5-6 Hz: CA and pads are 1e3 times stiffer than the
    mode's modal stiffness per metre); within 0.5 %."""
    freq, mass = {}, {}
    for tracks in (1, 2):
        girder = {"track_offsets_m": [2.5, -2.5]} if tracks == 2 else {"track_offset_m": 2.5}
        model = build_structure({"layout": {"approach_length_m": 0.0, "spans_m": [32.0],
                                            "tracks": tracks}, "girder": girder})
        freq[tracks] = modal_analysis(model, n_modes=8).first("girder_vertical", 0.3)
        c = model.config
        mass[tracks] = (c["girder"]["mass_kg_m"] + tracks * (
            2 * c["rail"]["mass_kg_m"] + c["slab"]["density_kg_m3"] * c["slab"]["width_m"]
            * c["slab"]["thickness_m"]))
    expected = np.sqrt(mass[1] / mass[2])
    assert freq[2] / freq[1] == pytest.approx(expected, rel=0.005), (freq, expected)
