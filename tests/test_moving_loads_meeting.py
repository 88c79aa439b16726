"""Two trains of moving constant forces meeting on a double-track span.

Two 2-car axle trains (70 kN wheel loads, 300 km/h): train A on track 0 (+2.5 m) running +x,
train B on track 1 (-2.5 m) running -x, placed so that they meet at midspan of a 32 m span
between 30 m slab approaches. References, independent of the code:

* Superposition: the structure is linear, so the response to both trains is the sum of the
  responses to each alone (time histories of the girder's vertical, lateral and roll
  displacement and acceleration at midspan and of the deck under the rails), to round-off;
  tolerance 1e-6 of each history's peak.
* Symmetry: the bridge is symmetric under a half-turn about the vertical axis through the
  span's centre (x -> L - x, y -> -y), which takes track 0 to track 1 and a train running +x
  to one running -x. So train B's response is train A's turned round: at midspan the vertical
  displacement and acceleration are equal, the lateral ones and the roll change sign, and the
  deck under track 1's left rail (y = -1.75 m) moves as the deck under track 0's right rail
  (y = +1.75 m) did. Hence with both trains the girder does not roll at midspan (the two
  trains' torques cancel at every instant) and its deflection doubles. Tolerance 1e-6 of the
  peak (the mesh is symmetric to round-off).

Runs: three moving-load runs of 11 000 steps on 4 500 DOF, about 3 s in all after compilation.
"""

from __future__ import annotations

import numpy as np
import pytest

from ttbpipe.structure import build_structure
from ttbpipe.structure.moving_loads import build_loads, default_duration, simulate

SPAN_M = 32.0
APPROACH_M = 30.0
SPEED_KMH = 300.0
DT_S = 1.0e-4
TOL = 1e-6


def _monitors():
    mid = {"kind": "girder", "span": 0, "position": 0.5,
           "quantities": ["displacement", "acceleration"]}
    return [dict(mid, name="girder", directions=["z", "y", "roll"]),
            dict(mid, name="deck_t1_right", deck_surface=True, lateral_offset_m=2.5 - 0.7525,
                 directions=["z", "y"]),
            dict(mid, name="deck_t2_left", deck_surface=True, lateral_offset_m=-2.5 + 0.7525,
                 directions=["z", "y"])]


@pytest.fixture(scope="module")
def runs():
    model = build_structure({"layout": {"approach_length_m": APPROACH_M, "spans_m": [SPAN_M],
                                        "approach_track": "slab", "tracks": 2}})
    total = model.layout.total_m
    train = {"cars": 2, "wheel_load_N": 70_000.0, "speed_kmh": SPEED_KMH}
    # the fronts at t = 0 mirror each other about the span's centre: they meet there
    a = dict(train, track=0, direction=1, front_x0_m=10.0)
    b = dict(train, track=1, direction=-1, front_x0_m=total - 10.0)
    out = {}
    for name, trains in (("A", [a]), ("B", [b]), ("AB", [a, b])):
        loads = build_loads({"axle_trains": trains}, model)
        duration = default_duration(model, build_loads({"axle_trains": [a, b]}, model))
        df, _ = simulate(model, loads, DT_S, duration, _monitors(), output_every=1,
                         check_dt=False)
        out[name] = df
    return out


def _peak(series):
    return float(np.abs(series).max())


def test_both_trains_are_the_sum_of_each_alone(runs):
    both, a, b = runs["AB"], runs["A"], runs["B"]
    for col in both.columns[1:]:
        total = a[col].to_numpy() + b[col].to_numpy()
        scale = max(_peak(a[col]), _peak(b[col]))
        assert np.abs(both[col].to_numpy() - total).max() <= TOL * scale, col


def test_the_train_in_minus_x_on_track_1_is_the_turned_round_train_on_track_0(runs):
    a, b = runs["A"], runs["B"]
    for quantity in ("disp_mm", "acc_m_s2"):
        z = f"girder_z_{quantity}"
        assert _peak(a[z]) > 0
        assert np.abs(b[z] - a[z]).max() <= TOL * _peak(a[z])
        for col in (f"girder_y_{quantity}",
                    f"girder_roll_{'disp_mrad' if quantity == 'disp_mm' else 'acc_rad_s2'}"):
            assert _peak(a[col]) > 1e-3 * _peak(a[z]) * (1e-3 if "roll" in col else 1.0)
            assert np.abs(b[col] + a[col]).max() <= TOL * _peak(a[col]), col
        left2, right1 = f"deck_t2_left_z_{quantity}", f"deck_t1_right_z_{quantity}"
        assert np.abs(b[left2] - a[right1]).max() <= TOL * _peak(a[right1])


def test_meeting_trains_do_not_roll_the_girder_at_midspan(runs):
    both, a = runs["AB"], runs["A"]
    assert _peak(both["girder_roll_disp_mrad"]) <= TOL * _peak(a["girder_roll_disp_mrad"])
    assert _peak(both["girder_roll_acc_rad_s2"]) <= TOL * _peak(a["girder_roll_acc_rad_s2"])
    assert np.abs(both["girder_z_disp_mm"] - 2 * a["girder_z_disp_mm"]).max() \
        <= TOL * _peak(a["girder_z_disp_mm"])


def test_loads_on_the_girder_act_at_their_track_offset():
    """Girder-only model (``bridge_track: none``, ``target: girder``): a train on track 1
    (e = -2.5 m) twists the girder the other way from the same train on track 0 (torque e F_z,
    paper eq. 24) and bends it the same (same symmetry argument, exact to round-off)."""
    model = build_structure({"layout": {"approach_length_m": 0.0, "spans_m": [SPAN_M],
                                        "bridge_track": "none", "tracks": 2}})
    mon = [{"name": "g", "kind": "girder", "span": 0, "position": 0.25,
            "directions": ["z", "roll"], "quantities": ["displacement"]}]
    res = {}
    for track in (0, 1):
        loads = build_loads({"target": "girder", "axle_trains": [
            {"cars": 1, "wheel_load_N": 70_000.0, "speed_kmh": SPEED_KMH, "track": track,
             "front_x0_m": 0.0}]}, model)
        res[track], _ = simulate(model, loads, DT_S, 0.5, mon, check_dt=False)
    z0, r0 = res[0]["g_z_disp_mm"], res[0]["g_roll_disp_mrad"]
    assert _peak(r0) > 0.01
    assert np.abs(res[1]["g_roll_disp_mrad"] + r0).max() <= TOL * _peak(r0)
    assert np.abs(res[1]["g_z_disp_mm"] - z0).max() <= TOL * _peak(z0)
