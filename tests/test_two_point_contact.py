"""Two-point wheel-rail contact on real profiles (``train.contact: {profile: profiles,
contact_points: 2}``): tread and flange with forces of their own, Hertz from the curvatures, and
the quasi-static flange climb against Nadal's limit.

References (independent of the code):
* Hertz, elliptical contact (Johnson, Contact Mechanics, 1985, section 4.2): the surface
  displacement at the centre of the pressure p0 sqrt(1 - x^2/a^2 - y^2/b^2) is
  (1/(pi E*)) int int p / rho dA (eq. 3.22 for each body, 1/E* = sum (1 - nu^2)/E); with
  rho < R(theta) = 1/sqrt(cos^2/a^2 + sin^2/b^2) the radial integral is p0 pi R(theta)/4, so the
  approach is delta = (p0 / 4 E*) int_0^2pi R(theta) dtheta, evaluated here by quadrature (a
  second method for the closed form with K(e)); circular limit delta = a^2/R (eq. 4.23).
* Nadal, M. J., "Theorie de la stabilite des locomotives, part 2: mouvement de lacet", Annales
  des Mines 10 (1908) 232-255: a flange touching the rail at the contact angle gamma with its
  tangential force saturated at mu N and acting up the flange starts climbing at
  Q/P = (tan gamma - mu) / (1 + mu tan gamma) (Marquis & Greif, "Application of Nadal limit in
  the prediction of wheel climb derailment", ASME/IEEE Joint Rail Conference 2011, JRC2011-56064:
  accurate for a wheel at a large angle of attack with no longitudinal creep force; with a
  longitudinal creep force sharing the saturation the climb L/V is higher). S1002's flange
  flank is straight at 70 degrees (EN 13715 section E).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ttbpipe.vehicle.contact import (COL_A, COL_DELTA, COL_DZ, COL_E, COL_G, build_geometry,
                                     hertz_constant, hertz_ellipse_mn, wheel_contact,
                                     wheel_contact_points, zone_columns)
from ttbpipe.vehicle.kernels import contact_forces
from ttbpipe.vehicle.parameters import ContactParameters
from ttbpipe.vehicle.profile_contact import profile_pair, profile_table

E_STEEL, NU = 2.059e11, 0.30


@pytest.fixture(scope="module")
def s1002():
    """S1002 on 60E1 at 1:40, gauge 1435 mm, flange back 1360 mm, two-point contact."""
    return build_geometry(ContactParameters(profile="profiles"))


@pytest.mark.parametrize("ratio", [1.0, 0.3, 3.0, 10.0, 100.0])
def test_hertz_constant_against_the_surface_displacement_integral(ratio):
    """G N^(2/3) (closed form with K(e)) equals the approach from integrating the Hertz pressure
    (module docstring) over theta by the midpoint rule (4000 points, spectrally accurate for a
    smooth periodic integrand): tolerance 1e-9. Equal curvatures: delta = a^2 / R, 1e-12."""
    curv_a, load = 1.1, 7.0e4
    curv_b = ratio * curv_a
    g = hertz_constant(curv_a, curv_b, E_STEEL, NU)
    m, n = hertz_ellipse_mn(curv_a, curv_b)
    c = (3 * load * (1 - NU ** 2) / (2 * E_STEEL * (curv_a + curv_b))) ** (1 / 3)
    a, b = m * c, n * c
    e_star = E_STEEL / (2 * (1 - NU ** 2))
    p0 = 3 * load / (2 * np.pi * a * b)
    theta = (np.arange(4000) + 0.5) * 2 * np.pi / 4000
    radius = 1.0 / np.sqrt(np.cos(theta) ** 2 / a ** 2 + np.sin(theta) ** 2 / b ** 2)
    delta = p0 / (4 * e_star) * np.sum(radius) * 2 * np.pi / 4000
    assert g * load ** (2 / 3) == pytest.approx(delta, rel=1e-9)
    if ratio == 1.0:
        r_eff = 1.0 / (curv_a + curv_b)
        assert delta == pytest.approx(a * a / r_eff, rel=1e-12)


def test_zone_tables_split_the_wheel_at_the_tread_flange_jump(s1002):
    """The cut lies between the tread contact and the flange-root contact of the rigid pair's
    jump (at about 5.2 mm: -17.8 and -28.7 mm on the wheel; the Manchester benchmark's jump
    from the tread to the flange root, docs/contact_geometry.md section 4); the larger of the
    zones' gap changes is the one-point table's (the smallest gap over the whole wheel is the
    smaller of the zones' smallest gaps: a second method for the same number; 5e-8 m, as the
    one-point table keeps the smallest sampled gap where the zones refine it by a parabola
    through three samples 0.02 mm apart, measured at most 1.7e-8 m); the
    flange zone carries the flange angle (70 degrees, EN 13715) where it is the contact."""
    assert -28.7e-3 < s1002.flange_cut < -17.8e-3
    zones = s1002.zones
    assert zones.shape[0] == 2
    one, _ = profile_table(ContactParameters(profile="profiles"))
    np.testing.assert_allclose(zones[:, :, COL_DZ].max(axis=0), one[:, 2], rtol=0, atol=5e-8)
    flange_is_contact = zones[0, :, COL_DZ] >= zones[1, :, COL_DZ]
    assert np.degrees(zones[0, flange_is_contact, COL_DELTA].max()) == pytest.approx(70.0, abs=0.05)
    # both zones within 0.1 mm of contact (a two-point contact under the static Hertz
    # approach of about 0.1 mm) only around the jump
    y = zones[0, :, 0]
    both = np.abs(zones[0, :, COL_DZ] - zones[1, :, COL_DZ]) < 1e-4
    assert np.all((y[both] > 4.0e-3) & (y[both] < 6.0e-3)) and both.sum() >= 5
    # Hertz from the curvatures at the centred tread contact: the same order as Zhai's
    # empirical worn-tread G (4.25e-8 m/N^(2/3) at r = 0.43 m; physics.md section 4)
    centre = zones.shape[1] // 2
    assert 0.7 < zones[1, centre, COL_G] / 4.25e-8 < 1.1
    # lateral position of each zone's load: the centroid of its overlap (virtual penetration
    # 0.05 mm). Around the centred position the tread's rigid contact jumps between two points
    # 10.6 mm apart on the wheel (753.2 and 741.8 mm from the wheelset centre, within 0.01 mm
    # in gap: section 4 of docs/contact_geometry.md); the load's position lies between them and
    # moves by less than 1 mm per 0.1 mm row, where the rigid point jumps by 11 mm
    one_point = profile_pair(ContactParameters(profile="profiles"))._contact(
        0, y, np.zeros_like(y), np.zeros_like(y))["track_position"] - y
    tread = np.abs(y) < 3.0e-3
    assert np.max(np.abs(np.diff(one_point[tread]))) > 0.010
    assert np.max(np.abs(np.diff(zones[1, tread, COL_A]))) < 1.0e-3
    assert np.max(np.abs(np.diff(zones[1, tread, COL_E]))) < 1.0e-3
    assert 0.7418 < zones[1, centre, COL_A] < 0.7532
    assert zones[0, -1, COL_A] < 0.712


def test_one_zone_in_contact_gives_the_one_point_normal_force():
    """With Zhai's worn-tread G in both models and the flange zone open (y_rel = 2 mm), the
    two-point kernel's normal force equals the one-point kernel's (same gap, angle and law: two
    code paths for one number) to 3e-4: the zone tables refine the smallest gap by a parabola
    (at most 1.7e-8 m against an approach of 1e-4 m, so 1.5 x 1.7e-4 in the force; the one
    point keeps the sampled minimum); in the two-point band (5.0 mm) both points carry
    load and the sum of the vertical forces exceeds that of the one point (two Hertz springs:
    the second point's gap is within the approach)."""
    p1 = ContactParameters(profile="profiles", contact_points=1)
    p2 = ContactParameters(profile="profiles", contact_points=2, hertz_law="worn")
    g1, g2 = build_geometry(p1), build_geometry(p2)
    pen = g1.hertz_g * 7.0e4 ** (2 / 3)
    kin = {"y": 2.0e-3, "z": float(np.interp(2.0e-3, g1.table[:, 0], g1.table[:, 2])) - pen}
    one = wheel_contact(1.0, g1, 83.3, kin, {})
    two, normals = wheel_contact_points(1.0, g2, 83.3, kin, {}, points=True)
    assert one[4] == pytest.approx(7.0e4 * np.cos(g1.table[g1.table.shape[0] // 2 + 20, 3]) ** 1.5,
                                   rel=1e-3)
    assert two[4] == pytest.approx(one[4], rel=3e-4)
    assert normals[0] == 0.0 and normals[1] > 0.0
    y = 5.0e-3
    kin = {"y": y, "z": float(np.interp(y, g1.table[:, 0], g1.table[:, 2])) - pen}
    one = wheel_contact(1.0, g1, 83.3, kin, {})
    two, normals = wheel_contact_points(1.0, g2, 83.3, kin, {}, points=True)
    assert np.all(normals > 0.05 * normals.sum())
    assert two[2] > one[2]


def _climb_path(geom, yaw, spin, load=7.0e4, y_mm=np.arange(4.0, 9.6, 0.05)):
    """Quasi-static path of a wheelset pushed towards the left rail (module docstring of the
    test below): for each prescribed lateral displacement y, Newton on the vertical force, roll
    moment and spin condition; returns rows (y, H, Q/P left, tread N, flange N, tangential
    creep force over mu N at the flange, contact angle at the flange). Where Newton does not
    converge from the previous point the step in y is halved (the contact can jump onto the
    flank within a fraction of a step); where no equilibrium is found within 1e-4 mm of the
    last one the path ends there (past the climb)."""
    ws = np.array([[0, 1, 2, 3, 4]])
    rail = np.zeros((1, 2, 4))
    speed = 20.0

    def residual(y, x):
        q = np.array([y, x[0], x[1], 0.0, yaw])
        v = np.array([0.0, 0.0, 0.0, x[2], 0.0])
        f, wheel = contact_forces(q, v, ws, geom, speed, rail)
        third = wheel[0, 0, 0] if spin == "wheel" else f[3]
        return np.array([(f[1] - 2 * load) / load, f[2] / load, third / load]), f, wheel, q, v

    def newton(y, x):
        for _ in range(100):
            r = residual(y, x)[0]
            jac = np.empty((3, 3))
            for k, h in enumerate((1e-8, 1e-8, 1e-5)):
                dx = np.zeros(3)
                dx[k] = h
                jac[:, k] = (residual(y, x + dx)[0] - residual(y, x - dx)[0]) / (2 * h)
            step = np.linalg.solve(jac, -r)
            # steps of at most 0.02 mm / 0.02 mrad and a creepage change of 1e-3 (r dw / V):
            # a saturated creep force is flat in the spin rate beyond
            step *= min(1.0, 2e-5 / max(abs(step[0]), abs(step[1]), 1e-30),
                        1e-3 * speed / geom.wheel_radius / max(abs(step[2]), 1e-30))
            x = x + step
            if max(abs(step[0]), abs(step[1])) < 1e-13 and abs(step[2]) < 1e-10:
                break
        return x, np.max(np.abs(residual(y, x)[0])) < 1e-8

    # start: both wheels on their rails with the static approach (the right wheel reads the
    # table at -y)
    y0 = y_mm[0] * 1e-3
    dz_left, dz_right = np.interp([y0, -y0], geom.table[:, 0], geom.table[:, COL_DZ])
    x = np.array([0.5 * (dz_left + dz_right) - geom.hertz_g * load ** (2 / 3),
                  (dz_left - dz_right) / (2 * geom.contact_half_distance), 0.0])
    rows = []
    y_done = None
    for y in y_mm * 1e-3:
        targets = [y]
        while targets:
            x_new, converged = newton(targets[-1], x)
            if converged:
                x, y_done = x_new, targets.pop()
            elif y_done is None:
                raise AssertionError(f"no equilibrium at the start, y = {y}")
            elif targets[-1] - y_done < 1e-7:
                return np.array(rows)
            else:
                targets.append(0.5 * (y_done + targets[-1]))
        r, f, wheel, q, v = residual(y, x)
        kin = {"y": q[0], "z": q[1], "roll": q[2], "yaw": q[4], "vpitch": v[3]}
        out, normals = wheel_contact_points(1.0, geom, speed, kin, {}, points=True)
        delta = float(zone_columns(geom, y, yaw)[0, COL_DELTA])   # the flange's, at this yaw
        # creep force in the contact plane, across the rolling direction (force_y, force_z of
        # the left wheel: -N sin d + F cos d, N cos d + F sin d)
        lateral = out[1] * np.cos(delta) + out[2] * np.sin(delta)
        saturation = np.hypot(out[0], lateral) / (geom.friction * normals.sum())
        rows.append((y, -f[0], -wheel[0, 0, 1] / wheel[0, 0, 2], normals[1], normals[0],
                     saturation, delta))
    return np.array(rows)


def nadal(gamma, mu):
    return (np.tan(gamma) - mu) / (1 + mu * np.tan(gamma))


def test_quasi_static_flange_climb_at_nadals_limit(s1002):
    """A wheelset (70 kN per wheel through its axle boxes) with a yaw angle of attack of
    10 mrad, pushed towards the left rail by a lateral force H at its centre that grows slowly:
    the quasi-static path, followed by prescribing its lateral displacement (the path can be
    followed past the largest force, which a force ramp cannot), has a largest H; a ramped force
    beyond it finds no equilibrium short of the flange top, so the wheel climbs there. Nadal's
    conditions are set up: the positive angle of attack makes the flange slide down the rail
    (its lateral creepage -yaw cos(delta)) and the flanging wheel turns freely (no longitudinal
    creep force: the spin rate is solved for F_x = 0 on that wheel, as for Nadal's single
    wheel). At the climb the tread has lifted, the flange's creep force is saturated at mu N
    (asserted), the contact sits on S1002's 70-degree flank, and the wheel's Q/P equals
    Nadal's (tan 70 - 0.3) / (1 + 0.3 tan 70) = 1.342 within 2 % (measured +0.08 %).

    A solid wheelset (one spin rate, the creep moments about the axle balanced) carries a
    longitudinal creep force at the flange, which shares the saturation: it climbs at a Q/P
    not below Nadal's (Marquis & Greif 2011; measured +0.3 %: in this model the flange's spin
    creepage, sin(70 deg)/r0 = 2.2 rad/m, dominates the creep force's direction).
    """
    mu = s1002.friction
    limit = nadal(np.radians(70.0), mu)
    path = _climb_path(s1002, 0.010, "wheel")
    k = int(np.argmax(path[:, 1]))
    assert 0 < k < path.shape[0] - 1            # H rises to a maximum and falls beyond it
    y, h, qp, tread_n, flange_n, saturation, delta = path[k]
    assert tread_n == 0.0 and flange_n > 0.0
    assert saturation == pytest.approx(1.0, abs=1e-6)
    assert np.degrees(delta) == pytest.approx(70.0, abs=0.3)
    assert qp == pytest.approx(limit, rel=0.02)
    # below the climb the wheel's Q/P stays under the limit; the tread unloads on the way
    assert np.all(path[:k, 2] <= qp + 1e-9)
    assert path[0, 3] > 0.0
    solid = _climb_path(s1002, 0.010, "axle")
    qp_solid = solid[int(np.argmax(solid[:, 1])), 2]
    assert qp_solid >= qp - 1e-6
    assert qp_solid == pytest.approx(limit, rel=0.02)


def test_quasi_static_flange_climb_with_polach(s1002):
    """The flange climb of the test above with ``creep_law: polach`` (Polach 1999: the spin
    enters the lateral force through the area of adhesion only, so a large spin does not
    saturate it). On S1002's 70-degree flank the spin creepage is sin(70 deg)/r0 = 2.2 rad/m on
    an ellipse a = 21 mm long (a/b = 18): the equivalent creepage xi_sp a = 0.046 dominates the
    lateral creepage yaw cos(70 deg) of any angle of attack up to 40 mrad, and the flange's
    creep force stays well below mu N. So at a small angle of attack (1 mrad) the wheel climbs
    at a Q/P clearly above Nadal's (more than 10 %; Marquis & Greif 2011: Nadal is conservative
    at small angles of attack), H has an interior maximum as with the default law, and a
    larger angle of attack (20 mrad, more lateral creepage up the flank) does not raise the
    climbing Q/P. Regression values of this model (not references): Q/P 1.6154 at 1 mrad and
    1.6127 at 20 mrad, within 1e-3 (1.6141 with the contact tables at zero yaw: the flange's
    contact on the yawed wheel's trace line lowers it by 0.09 %) -- with Polach the climb does not approach Nadal at 10-20
    mrad as the literature finds with Kalker's exact theory (docs/contact_geometry.md section
    7, benchmarks/flange_climb_creep_laws.py: FASTSIM's lateral force on the same flank rises
    from 0.64 to 0.87 mu N over 0-20 mrad, Polach's stays at 0.42-0.43)."""
    geom = build_geometry(ContactParameters(profile="profiles", creep_law="polach"))
    limit = nadal(np.radians(70.0), geom.friction)
    climbs = {}
    for yaw in (0.001, 0.020):
        path = _climb_path(geom, yaw, "wheel")
        k = int(np.argmax(path[:, 1]))
        assert 0 < k < path.shape[0] - 1
        assert np.degrees(path[k, 6]) == pytest.approx(70.0, abs=0.3)
        climbs[yaw] = path[k, 2]
    assert climbs[0.001] > 1.1 * limit
    assert climbs[0.020] <= climbs[0.001]
    assert climbs[0.001] == pytest.approx(1.6154, abs=1e-3)
    assert climbs[0.020] == pytest.approx(1.6127, abs=1e-3)


def test_vertical_loads_twist_the_rail_about_its_shear_centre():
    """Rail loads at the real contact positions (seed paper eq. 31: M_T = F_Z l_h + F_Y l_v).

    1. Statics of a normal force: on S1002's 70-degree flank (y_rel = 7.5 mm, the tread open,
       friction off: no creep force) the rail's moment about its shear centre h = 0.095 m below
       the crown, h F_y (the lateral force's, all that one-point contact applies) minus the
       vertical force's s l F_z, equals the moment of the normal force N acting along the
       contact normal through the contact point, -N (e cos d + h (sin d - sin b cos d)) with e
       the contact's offset from the crown and d its angle from the rigid search of the
       one-point table (an independent call, zero roll) and b the 1:40 cant: 1 %.
    2. Kinematics and loads are each other's transpose (virtual work): with the rail's roll
       theta in the penetration, d F_z(wheel) / d theta = d Q_theta / d z_wheel, Q_theta =
       -M_rail the generalised force on the rail's roll, by central differences in the
       two-point band (both points loaded, each with its own lever): 1e-4 relative.
    """
    p = ContactParameters(profile="profiles", friction=0.0)
    geom = dataclasses.replace(build_geometry(p), rail_head_height=0.095)
    h, sin_b = 0.095, geom.rail_cant
    assert sin_b == pytest.approx(np.sin(np.arctan(1 / 40)), rel=1e-12)
    load = 7.0e4
    pen = 3.8e-8 * load ** (2 / 3)
    y = 7.5e-3
    dz = max(float(np.interp(y, geom.zones[k, :, 0], geom.zones[k, :, COL_DZ])) for k in range(2))
    out, normals = wheel_contact_points(1.0, geom, 83.3, {"y": y, "z": dz - pen}, {}, points=True)
    assert normals[1] == 0.0 and normals[0] > 0.0
    m_rail = h * out[1] - out[10]
    rigid = profile_pair(p)._contact(0, np.array([y]), np.zeros(1), np.zeros(1))
    e, d = rigid["rail_offset"][0], rigid["angle"][0]
    expected = -normals.sum() * (e * np.cos(d) + h * (np.sin(d) - sin_b * np.cos(d)))
    assert m_rail == pytest.approx(expected, rel=0.01)

    y = 5.0e-3
    dz = max(float(np.interp(y, geom.zones[k, :, 0], geom.zones[k, :, COL_DZ])) for k in range(2))
    base = {"y": y, "z": dz - pen}

    def fz(theta, z):
        out, normals = wheel_contact_points(1.0, geom, 83.3, {**base, "z": z}, {"roll": theta},
                                            points=True)
        return out[2], -out[10], normals

    _, _, normals = fz(0.0, base["z"])
    assert np.all(normals > 0.05 * normals.sum())
    eps_t, eps_z = 1e-5, 1e-8
    dfz_dtheta = (fz(eps_t, base["z"])[0] - fz(-eps_t, base["z"])[0]) / (2 * eps_t)
    dq_dz = (fz(0.0, base["z"] + eps_z)[1] - fz(0.0, base["z"] - eps_z)[1]) / (2 * eps_z)
    assert dfz_dtheta == pytest.approx(dq_dz, rel=1e-4)


def test_steady_curving_on_two_point_contact():
    """One car on S1002 / 60E1 with two-point contact on a 1000 m curve at 160 km/h with 60 mm
    cant (run from the steady state on the arc, 200 m): the rails' lateral forces on the eight
    wheels add up to m (V^2/R cos theta - g sin theta) (the closed form of tests/test_curving.py)
    within 1 % (measured < 0.01 %, 92.4 kN), the leading wheelset sits outwards in the
    two-point band of the pair (4.4-5.6 mm: tread and flange root both within the static
    approach, test above; measured 5.4 mm) and its outer wheel's tread and flange root both
    carry load (evaluated at the run's last state)."""
    from test_curving import _one_car_on_a_curve, steady_lateral_force

    from ttbpipe.simulation.coupled import integrate, prepare

    radius, speed_kmh, cant_mm = 1000.0, 160.0, 60.0
    setup = prepare(_one_car_on_a_curve(speed_kmh, radius, cant_mm, length_m=200.0,
                                        contact={"profile": "profiles"}))
    run = integrate(setup)
    wheel = run.wheel
    lateral, expected = steady_lateral_force(setup, run, speed_kmh, radius, cant_mm)
    assert lateral == pytest.approx(expected, rel=0.01)
    v = speed_kmh / 3.6
    y_lead = -wheel[-1, 0, 1, 3]            # the outer (right) wheel's y_rel, towards its rail
    assert 4.4e-3 < y_lead < 5.6e-3
    m = setup.model
    dofs = m.wheelset_dofs[0]
    q = run.q[-1]
    kin = {"y": q[dofs[0]], "z": q[dofs[1]], "roll": q[dofs[2]], "yaw": q[dofs[4]]}
    _, normals = wheel_contact_points(-1.0, setup.geom, v, kin, {}, points=True)
    assert np.all(normals > 0.02 * normals.sum()), normals
