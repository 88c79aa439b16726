"""Curves with cant and clothoid transitions (ttbpipe.vehicle.curving).

References: the steady-state lateral equilibrium of a vehicle on a curve (every body needs the
centripetal force m V^2 / R in the horizontal plane; in the canted track plane the rails supply
m (V^2/R cos theta - g sin theta), the cant deficiency force; Iwnicki (ed.), Handbook of Railway
Vehicle Dynamics, 2006), and the pure-rolling line of a coned wheelset (Wickens,
Fundamentals of Rail Vehicle Dynamics, 2003, the classical kinematic result: on a curve of radius R a wheelset rolls
without longitudinal creep at the outward offset y = r0 a0 / (lambda R)).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from ttbpipe.constants import STANDARD_GRAVITY
from ttbpipe.simulation.loop import integrate
from ttbpipe.simulation.setup import prepare
from ttbpipe.vehicle.contact import wheel_contact
from ttbpipe.vehicle.curving import CANT_BASE_M, curve_arrays, frame_at, layout_knots


def _one_car_on_a_curve(speed_kmh, radius_m, cant_mm, length_m=400.0, transition_m=None,
                        contact=None):
    # the whole run on the arc, or entering it from tangent track through a clothoid
    start, lt = (-1000.0, 0.0) if transition_m is None else (40.0, transition_m)
    curve = {"start_x_m": start, "transition_m": lt, "length_m": 5000.0,
             "radius_m": radius_m, "cant_mm": cant_mm, "direction": "left"}
    train = {"composition": ["trailer"]}
    if contact is not None:
        train["contact"] = contact
    return {"train": train,
            "simulation": {"track": "rigid", "speed_kmh": speed_kmh, "rigid_length_m": length_m,
                           "time_step_s": 1e-4, "layout": {"curves": [curve]}},
            "irregularity": {"source": "none"}}


@pytest.mark.parametrize("speed_kmh, cant_mm, transition_m",
                         [(200.0, 100.0, None), (120.0, 150.0, None), (200.0, 100.0, 120.0)])
def test_steady_curving_rails_carry_the_cant_deficiency_force(speed_kmh, cant_mm, transition_m):
    """One car on a 2000 m curve, from tangent-track statics on the arc itself or entering it
    through a 120 m clothoid (curvature and cant ramped, the suspension twisted on the way):
    once the transient has died out (last 20 % of 400 m, on the arc), the lateral forces of
    the rails on the eight wheels add up to m (V^2/R cos theta - g sin theta) of the car's
    total mass within 1 % (the issue's tolerance; measured 0.02 % (51.7 kN), 0.008 % and
    0.15 % through the clothoid). The second case has a cant excess (-25.0 kN: the rails hold
    the car from sliding inwards), and the inner wheels carry the larger loads; otherwise the
    outer ones."""
    radius = 2000.0
    setup = prepare(_one_car_on_a_curve(speed_kmh, radius, cant_mm, transition_m=transition_m))
    run = integrate(setup)
    wheel = run.wheel
    lateral, expected = steady_lateral_force(setup, run, speed_kmh, radius, cant_mm)
    assert abs(lateral - expected) < 0.01 * abs(expected), (lateral, expected)
    last = slice(int(0.8 * wheel.shape[0]), None)
    outer, inner = wheel[last, :, 1, 2].mean(), wheel[last, :, 0, 2].mean()
    if expected > 0:
        assert outer > inner
    else:
        assert inner > outer


def steady_lateral_force(setup, run, speed_kmh, radius_m, cant_mm):
    """(the rails' lateral force on all wheels, averaged over the last 20 % of the run; the cant
    deficiency force m (V^2/R cos theta - g sin theta) of the train's total mass)."""
    lateral = run.wheel[int(0.8 * run.wheel.shape[0]):, :, :, 1].sum(axis=(1, 2)).mean()
    mass = setup.model.mass[0::5].sum()
    theta = np.arcsin(cant_mm / 1000.0 / CANT_BASE_M)
    v = speed_kmh / 3.6
    return lateral, mass * (v * v / radius_m * np.cos(theta) - STANDARD_GRAVITY * np.sin(theta))


def test_coned_wheelset_rolls_without_longitudinal_creep_at_the_pure_rolling_offset():
    """A coned wheelset (lambda 0.04) aligned with the track on a 1500 m left curve: its frame
    turns at V/R, so the longitudinal creepages vanish at y = -r0 a0 / (lambda R) (outwards)
    and nowhere else; the yaw moment of the creep forces about the wheelset centre (-a0 (F_x,left
    - F_x,right)) turns it back towards that line from either side."""
    setup = prepare({"train": {"composition": ["trailer"]},
                     "simulation": {"track": "rigid", "speed_kmh": 80.0, "time_step_s": 1e-4},
                     "irregularity": {"source": "none"}})
    geom, contact = setup.geom, setup.train.contact
    radius, v = 1500.0, 80.0 / 3.6
    a0, r0, lam = geom.scalars()[6], contact.wheel_radius, contact.conicity
    pure = -r0 * a0 / (lam * radius)

    def longitudinal(y):
        ws = {"y": y, "z": -5.0e-4, "vyaw": v / radius}      # frame yaw rate V/R, own yaw 0
        return np.array([wheel_contact(side, geom, v, ws, {})[0] for side in (1.0, -1.0)])

    at_pure = longitudinal(pure)
    normal = wheel_contact(1.0, geom, v, {"y": pure, "z": -5.0e-4, "vyaw": v / radius}, {})[4]
    assert normal > 1e4
    assert np.abs(at_pure).max() < 1e-6 * normal
    for dy in (-1.0e-3, 1.0e-3):
        fx = longitudinal(pure + dy)
        assert np.abs(fx).max() > 1e-3 * normal
        yaw_moment = -a0 * (fx[0] - fx[1])
        # inside the pure-rolling line (dy > 0, towards the centre) the wheelset must steer
        # outwards (negative yaw on a left curve) and vice versa: the moment opposes dy
        assert np.sign(yaw_moment) == -np.sign(dy)


@pytest.mark.parametrize("radius_m", [1500.0, 3000.0])
def test_free_coned_wheelset_on_a_curve_oscillates_about_the_pure_rolling_offset(radius_m):
    """The free coned wheelset on a curve (lambda 0.04, r0 0.43 m, a0 0.7465 m), in the time
    loop: one trailer car whose wheelsets are free in yaw (primary_kx = 0) and laterally (a
    vanishing 1 kN/m per axle box keeps the static problem regular: ky/m = 0.8 1/s^2 against
    the kinematic omega^2 = 15 1/s^2) at 40 km/h on a curve with the balancing cant (no
    lateral force is needed). Kinematic theory (Wickens 2003, section 2; Iwnicki 2006) puts the
    wheelset at the pure-rolling offset r0 a0 / (lambda R) (5.35 mm and 2.67 mm outwards).

    - The static state on the arc has every wheelset there within 0.1 % (measured 3e-5).
    - Moved 1 mm off that line, the leading wheelset does not settle: a free wheelset is
      unstable at every speed (Wickens; tests/test_hunting.py), so it performs the kinematic
      oscillation *about* the pure-rolling line, slowly growing. A least-squares fit of
      y_c + exp(sigma t) (a cos omega t + b sin omega t) to 20 s of it gives the centre y_c
      within 0.1 % of r0 a0 / (lambda R) (measured 3e-5), omega within 0.1 % of Klingel's
      kinematic frequency for the model's cone (the closed form of
      ttbpipe.vehicle.hunting.klingel_frequency; measured 1.1e-4) and sigma within 5 % of the
      real part of the linear free-wheelset eigenvalue (the wheelset alone, the rest held;
      measured 0.7 %), a growth of 0.018 1/s."""
    from scipy.optimize import curve_fit

    from ttbpipe.vehicle import hunting as lin
    from ttbpipe.vehicle.contact import build_geometry
    from ttbpipe.vehicle.model import build_train_model
    from ttbpipe.vehicle.parameters import train_from_config

    speed_kmh, v = 40.0, 40.0 / 3.6
    balancing_cant_mm = v * v / radius_m / STANDARD_GRAVITY * CANT_BASE_M * 1000.0
    curve = {"start_x_m": -1000.0, "transition_m": 0.0, "length_m": 5000.0,
             "radius_m": radius_m, "cant_mm": balancing_cant_mm, "direction": "left"}
    train = {"composition": ["trailer"], "trailer": {"primary_kx": 0.0, "primary_ky": 1.0e3}}
    setup = prepare({"train": train,
                     "simulation": {"track": "rigid", "speed_kmh": speed_kmh, "duration_s": 20.0,
                                    "time_step_s": 1e-4, "output_every": 10,
                                    "layout": {"curves": [curve]}},
                     "irregularity": {"source": "none"}})
    geom, contact = setup.geom, setup.train.contact
    a0, r0, lam = geom.scalars()[6], contact.wheel_radius, contact.conicity
    pure = -r0 * a0 / (lam * radius_m)        # outwards of a left-hand curve: negative y
    ws_y = setup.model.wheelset_dofs[:, 0]
    assert np.abs(setup.q0[ws_y] / pure - 1.0).max() < 1e-3

    q = setup.q0.copy()
    q[ws_y[0]] += 1.0e-3
    setup.q0 = q
    run = integrate(setup)
    lead = run.q[:, ws_y[0]]

    def oscillation(t, centre, a, b, sigma, omega):
        return centre + np.exp(sigma * t) * (a * np.cos(omega * t) + b * np.sin(omega * t))

    klingel = 2.0 * np.pi * lin.klingel_frequency(v, lam, r0, a0, float(np.arctan(lam)))
    fit, _ = curve_fit(oscillation, run.time, lead, p0=[pure, 1e-3, 0.0, 0.0, klingel])
    centre, sigma, omega = fit[0], fit[3], fit[4]
    assert abs(centre / pure - 1.0) < 1e-3, (centre, pure)
    assert omega == pytest.approx(klingel, rel=1e-3)

    model_train = train_from_config(train)
    statics = lin.car_statics(build_train_model(model_train), build_geometry(model_train.contact))
    eig, _ = lin.car_system(statics, lin.contact_slopes(statics.geom), v, bodies=(3,)).modes()
    kinematic = eig[np.argmin(np.abs(np.abs(eig.imag) - klingel))]
    assert kinematic.real > 0.0 and sigma > 0.0
    assert sigma == pytest.approx(kinematic.real, rel=0.05)


def test_layout_heading_and_offset_integrate_the_curvature():
    """Heading and lateral offset of the track frame through clothoid transitions and a reverse
    curve against a second method (trapezoidal integration of the same curvature on a 1 cm
    grid): within 1e-7 rad and 1e-6 m. Curvature and cant ramp linearly over the transitions."""
    layout = {"curves": [
        {"start_x_m": 0.0, "transition_m": 80.0, "length_m": 120.0, "radius_m": 1200.0,
         "cant_mm": 120.0, "direction": "left"},
        {"start_x_m": 300.0, "transition_m": 50.0, "length_m": 60.0, "radius_m": 800.0,
         "cant_mm": 90.0, "direction": "right"}]}
    setup = prepare({"train": {"composition": ["trailer"]},
                     "simulation": {"track": "rigid", "speed_kmh": 80.0, "time_step_s": 1e-4},
                     "irregularity": {"source": "none"}})
    curve = curve_arrays(setup.model, layout)
    x = np.arange(-50.0, 600.0, 0.01)
    frames = [frame_at(curve, xi) for xi in x]
    kappa = np.array([f["curvature_1_m"] for f in frames])
    heading = np.array([f["heading_rad"] for f in frames])
    offset = np.array([f["offset_m"] for f in frames])
    h2 = heading[0] + cumulative_trapezoid(kappa, x, initial=0.0)
    y2 = offset[0] + cumulative_trapezoid(h2, x, initial=0.0)
    assert np.abs(heading - h2).max() < 1e-7
    assert np.abs(offset - y2).max() < 1e-6
    mid = frame_at(curve, 40.0)                     # half-way along the first transition
    assert mid["curvature_1_m"] == pytest.approx(0.5 / 1200.0, rel=1e-12)
    assert mid["cant_angle_rad"] == pytest.approx(-0.5 * np.arcsin(0.12 / 1.5), rel=1e-12)
    arc = frame_at(curve, 400.0)
    assert arc["curvature_1_m"] == pytest.approx(-1.0 / 800.0, rel=1e-12)
    assert arc["cant_angle_rad"] == pytest.approx(np.arcsin(0.09 / 1.5), rel=1e-12)
    assert frame_at(curve, 590.0)["curvature_1_m"] == 0.0


def test_overlapping_curves_and_bad_values_are_named():
    base = {"start_x_m": 0.0, "transition_m": 50.0, "length_m": 100.0, "radius_m": 1000.0}
    with pytest.raises(ValueError, match=r"curves\[1\].*overlaps"):
        layout_knots({"curves": [base, dict(base, start_x_m=150.0)]})
    with pytest.raises(ValueError, match="radius_m must be positive"):
        layout_knots({"curves": [dict(base, radius_m=-5.0)]})
    with pytest.raises(ValueError, match="cant_mm"):
        layout_knots({"curves": [dict(base, cant_mm=2000.0)]})


def test_a_run_starting_on_the_arc_starts_in_its_steady_state():
    """The static state on a curve (ttbpipe.vehicle.static with the track frame's loads): a car
    starting on the 2000 m arc at 200 km/h with 100 mm cant has, from its first step, the
    steady cant-deficiency force (within 1 % of the closed form at every output step of the
    first 0.5 s) and its wheelsets' lateral offsets stay within 0.05 mm of the static ones:
    no start transient."""
    setup = prepare(_one_car_on_a_curve(200.0, 2000.0, 100.0, length_m=40.0))
    run = integrate(setup)
    lateral = run.wheel[:, :, :, 1].sum(axis=(1, 2))
    mass = setup.model.mass[0::5].sum()
    theta = np.arcsin(0.1 / CANT_BASE_M)
    v = 200.0 / 3.6
    expected = mass * (v * v / 2000.0 * np.cos(theta) - STANDARD_GRAVITY * np.sin(theta))
    first = run.time <= 0.5
    assert np.abs(lateral[first] - expected).max() < 0.01 * expected
    ws_y = setup.model.wheelset_dofs[:, 0]
    assert np.abs(run.q[first][:, ws_y] - setup.q0[ws_y]).max() < 5e-5


def _car_on_a_canted_bridge(cant_mm: float, speed_kmh: float = 200.0, radius_m: float = 4000.0,
                            direction: int = 1, tracks: int = 1):
    """One trailer car standing (statics at speed) in the middle of three 32 m slab-track spans,
    the whole model on a left-hand arc of ``radius_m`` with ``cant_mm``, running +x or -x;
    ``tracks: 2`` a double-track deck with a second car on the other track running the other
    way, beside the first."""
    curve = {"start_x_m": -1000.0, "transition_m": 0.0, "length_m": 5000.0,
             "radius_m": radius_m, "cant_mm": cant_mm, "direction": "left"}
    # the wheelsets at 75, 77.5, 92.5 and 95 m (middle span 62-94 m) in either direction
    start, end = (95.0, 96.0) if direction == 1 else (75.0, 74.0)
    case = {"train": {"composition": ["trailer"]},
            "structure": {"layout": {"approach_length_m": 30.0, "spans_m": [32.0, 32.0, 32.0],
                                     "approach_track": "slab", "bridge_track": "slab",
                                     "tracks": tracks}},
            "simulation": {"speed_kmh": speed_kmh, "start_x_m": start, "end_x_m": end,
                           "direction": direction, "time_step_s": 1e-4,
                           "layout": {"curves": [curve]}},
            "irregularity": {"source": "none"}}
    if tracks == 2:
        case["second_train"] = {"start_x_m": 75.0 if direction == 1 else 95.0}
    return case


def _bearing_reactions(setup) -> tuple[float, float]:
    """Total lateral and vertical forces the girders pass to their bearings in the static state
    (N, global axes: + left, + up): the forces k d of every bearing link."""
    packed, structure = setup.packed, setup.structure
    totals = {"bearing_y": 0.0, "bearing_z": 0.0}
    for link, kind in enumerate(structure.link_kinds):
        if kind in totals:
            j = slice(packed.link_ptr[link], packed.link_ptr[link + 1])
            elongation = packed.link_coef[j] @ setup.disp0[packed.link_dof[j]]
            totals[kind] += packed.link_k[link] * elongation
    return totals["bearing_y"], totals["bearing_z"]


@pytest.mark.parametrize("cant_mm, direction", [(118.0, 1), (60.0, 1), (0.0, 1), (60.0, -1)])
def test_the_girders_carry_the_weight_down_and_the_centrifugal_force_outwards(cant_mm, direction):
    """A car on a canted curve over a bridge: the track (rails, pads, slab) lies in the canted
    plane and the CA mortar turns its loads into the level girder. Statics (independent of the
    model): a body moving at V on a horizontal arc of radius R needs the horizontal centripetal
    force m V^2 / R and the vertical m g, whatever the cant; the structure receives their
    opposites, so the girders' bearings take m g downwards and m V^2 / R outwards. Checked at
    balanced cant (118 mm at 200 km/h on R = 4000 m: the wheel forces are normal to the track
    plane, nearly no lateral force in it), at a cant deficiency (60 mm) and on level track (0),
    within 1 % of m V^2 / R and 0.1 % of m g (the part the rails carry past the bridge ends is
    below 1e-4 with the car in the middle span; measured 0.015-0.02 % and 4e-6). Without the
    rotation at the CA mortar the girders took the track-plane forces as if they were level:
    -0.3 % of m V^2 / R at balanced cant, 49 % at 60 mm (measured; the test fails).

    A car running -x meets the same curve as a right-hand one (ttbpipe.vehicle.curving.
    layout_along): the bearings still take the centrifugal force outwards (global -y), and
    the rails' lateral force on the wheels, in the car's own axes, changes sign."""
    setup = prepare(_car_on_a_canted_bridge(cant_mm, direction=direction))
    lateral, vertical = _bearing_reactions(setup)
    mass = setup.model.mass[0::5].sum()
    v = 200.0 / 3.6
    centrifugal = mass * v * v / 4000.0
    # the structure is pushed outwards: to the right (-y) on a left-hand curve
    assert lateral == pytest.approx(-centrifugal, rel=0.01), (lateral, -centrifugal)
    assert vertical == pytest.approx(-mass * STANDARD_GRAVITY, rel=1e-3)
    theta = np.arcsin(cant_mm / 1000.0 / CANT_BASE_M)
    in_plane = direction * setup.static_wheel[:, :, 1].sum()
    assert in_plane == pytest.approx(mass * (v * v / 4000.0 * np.cos(theta)
                                             - STANDARD_GRAVITY * np.sin(theta)),
                                     rel=0.01, abs=0.01 * centrifugal)


@pytest.mark.parametrize("direction", [1, -1])
def test_two_trains_passing_on_a_canted_double_track_curve(direction):
    """Two cars side by side on the two tracks of a double-track deck on a left-hand curve of
    4000 m with 60 mm cant, running opposite ways: the bearings take the centrifugal force of
    both, 2 m V^2 / R outwards, and 2 m g, within 1 % and 0.1 % (statics, as the one-car
    test; both cars see the layout's radius, the tracks' own radii differ from it by half their
    spacing: 0.06 %; measured 0.04-0.05 % and 5e-6), and each car's rails push it inwards with the same cant-deficiency force
    in its own axes (one running +x on a left-hand curve, the other -x on what is for it a
    right-hand one)."""
    setup = prepare(_car_on_a_canted_bridge(60.0, direction=direction, tracks=2))
    lateral, vertical = _bearing_reactions(setup)
    mass = setup.model.mass[0::5].sum()
    v = 200.0 / 3.6
    centrifugal = mass * v * v / 4000.0
    assert lateral == pytest.approx(-2.0 * centrifugal, rel=0.01), (lateral, -2 * centrifugal)
    assert vertical == pytest.approx(-2.0 * mass * STANDARD_GRAVITY, rel=1e-3)
    theta = np.arcsin(0.06 / CANT_BASE_M)
    deficiency = mass * (v * v / 4000.0 * np.cos(theta) - STANDARD_GRAVITY * np.sin(theta))
    first = direction * setup.static_wheel[:, :, 1].sum()
    second = -direction * setup.second.static_wheel[:, :, 1].sum()
    assert first == pytest.approx(deficiency, rel=0.01)
    assert second == pytest.approx(deficiency, rel=0.01)
