"""Wheel-rail contact laws against their formulas and published tables (ttbpipe.vehicle.contact)."""

import dataclasses

import numpy as np
import pytest

from ttbpipe.vehicle.contact import (COL_DELTA, COL_DZ, COL_R, KALKER_C11, KALKER_C22, KALKER_C23,
                                     KALKER_C33, _hertz_force, _she_factor, build_geometry,
                                     conical_geometry, equivalent_conicity, hertz_ellipse_mn,
                                     hertz_g, kalker_coefficients, table_geometry, wheel_contact)
from ttbpipe.vehicle.parameters import ContactParameters


def test_hertz_constant_and_stiffness_match_physics_md():
    """G and k_H = 1.5 P^(1/3)/G at R = 0.43 m, P = 70 kN (physics.md s.4 [C]: 5.18e-8 / 4.25e-8
    m/N^(2/3); 1.19e9 / 1.45e9 N/m). Tolerance 0.5 % (the reference values have 3 digits)."""
    assert hertz_g(0.43, "cone") == pytest.approx(5.18e-8, rel=5e-3)
    assert hertz_g(0.43, "worn") == pytest.approx(4.25e-8, rel=5e-3)
    for tread, k_ref in (("cone", 1.19e9), ("worn", 1.45e9)):
        g = hertz_g(0.43, tread)
        delta = g * 70e3 ** (2 / 3)           # penetration at 70 kN
        h = 1e-9
        k = (_hertz_force(delta + h, g) - _hertz_force(delta - h, g)) / (2 * h)
        assert k == pytest.approx(k_ref, rel=5e-3)


@pytest.mark.parametrize("penetration", [1e-6, 2e-5, 8e-5, 2e-4])
def test_hertz_law_at_tabulated_points(penetration):
    """P = (dZ/G)^1.5 exactly (physics.md s.4), and zero on separation (physics.md s.7 item 12)."""
    g = hertz_g(0.43, "cone")
    assert _hertz_force(penetration, g) == pytest.approx((penetration / g) ** 1.5, rel=1e-14)
    assert _hertz_force(-penetration, g) == 0.0
    assert _hertz_force(0.0, g) == 0.0


@pytest.mark.parametrize("theta_deg, m_ref, n_ref", [
    (30.0, 2.731, 0.493), (45.0, 1.926, 0.604), (60.0, 1.486, 0.717), (90.0, 1.0, 1.0)])
def test_hertz_ellipse_coefficients_match_classic_table(theta_deg, m_ref, n_ref):
    """Hertz m, n vs theta = arccos(|B-A|/(A+B)) (Timoshenko & Goodier, Theory of Elasticity,
    sec. 140 table; 3-4 digits printed): tolerance 0.1 %."""
    c = np.cos(np.radians(theta_deg))
    m, n = hertz_ellipse_mn(1.0 - c, 1.0 + c)   # A < B: major axis along x
    assert m == pytest.approx(m_ref, rel=1e-3)
    assert n == pytest.approx(n_ref, rel=1e-3)
    n2, m2 = hertz_ellipse_mn(1.0 + c, 1.0 - c)  # swapped curvatures swap the axes
    assert (m2, n2) == pytest.approx((m, n), rel=1e-12)


def test_hertz_ellipse_circular_limit_second_method():
    """Equal curvatures: a = (3 N R / 4 E*)^(1/3) with 1/R = 2(A+B)/2, 1/E* = 2(1-nu^2)/E
    (Johnson eq. 4.22); compared with m c of physics.md's formula. Tolerance 1e-10."""
    e, nu, n_force, a_curv = 2.1e11, 0.3, 80e3, 1.0
    m, _ = hertz_ellipse_mn(a_curv, a_curv)
    c = (3 * n_force * (1 - nu ** 2) / (2 * e * 2 * a_curv)) ** (1 / 3)
    r_eff = 1 / (2 * a_curv)
    e_star = e / (2 * (1 - nu ** 2))
    assert m * c == pytest.approx((3 * n_force * r_eff / (4 * e_star)) ** (1 / 3), rel=1e-10)


def test_kalker_table_points_and_c23_typo():
    """Tabulated a/b points are returned exactly (physics.md Kalker table, nu = 0.25); the
    printed C23 = 1.15 at a/b = 0.8 is corrected to 1.25, which makes C23 strictly monotone."""
    ab = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    for i, g in enumerate(ab):
        assert kalker_coefficients(g) == pytest.approx(
            (KALKER_C11[i], KALKER_C22[i], KALKER_C23[i], KALKER_C33[i]), rel=1e-12)
    for i, ba in enumerate([0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1]):
        assert kalker_coefficients(1 / ba)[0] == pytest.approx(KALKER_C11[10 + i], rel=1e-12)
    assert kalker_coefficients(0.8)[2] == 1.25
    assert np.all(np.diff(KALKER_C23) > 0)
    assert np.all(np.diff(KALKER_C11) > 0) and np.all(np.diff(KALKER_C22) > 0)


def test_she_saturation_formula_continuity_and_bound():
    """Shen-Hedrick-Elkins: F' = mu N (b - b^2/3 + b^3/27), b <= 3; mu N beyond (physics.md s.4).
    Continuous at b = 3 (both sides -> mu N within 1e-6), monotone, never above mu N, and
    F'/F -> 1 for small creep forces (linear Kalker regime)."""
    mu, normal = 0.3, 70e3
    limit = mu * normal
    betas = np.linspace(1e-4, 8.0, 4001)
    sat = np.array([_she_factor(b * limit, 0.0, mu, normal) * b * limit for b in betas])
    ref = np.where(betas <= 3, limit * (betas - betas ** 2 / 3 + betas ** 3 / 27), limit)
    assert np.allclose(sat, ref, rtol=1e-12)
    assert np.all(sat <= limit * (1 + 1e-12))
    assert np.all(np.diff(sat) >= -1e-9)
    lo = _she_factor((3 - 1e-7) * limit, 0.0, mu, normal) * (3 - 1e-7) * limit
    hi = _she_factor((3 + 1e-7) * limit, 0.0, mu, normal) * (3 + 1e-7) * limit
    assert lo == pytest.approx(limit, rel=1e-6) and hi == pytest.approx(limit, rel=1e-12)
    assert _she_factor(1e-6 * limit, 0.0, mu, normal) == pytest.approx(1.0, rel=1e-5)
    # direction preserved: the factor depends on |F| only
    f1 = _she_factor(0.6 * limit, 0.8 * limit, mu, normal)
    f2 = _she_factor(limit, 0.0, mu, normal)
    assert f1 == pytest.approx(f2, rel=1e-12)
    assert _she_factor(1.0, 1.0, mu, 0.0) == 0.0


def test_conical_geometry_table():
    """Cone: r = r0 + lambda y, gap change lambda y, contact angle atan(lambda) (physics.md s.4)."""
    p = ContactParameters(conicity=0.05)
    geom = conical_geometry(p)
    y = geom.table[:, 0]
    assert np.allclose(geom.table[:, COL_R], 0.43 + 0.05 * y, atol=1e-15)
    assert np.allclose(geom.table[:, COL_DZ], 0.05 * y, atol=1e-15)
    assert np.allclose(geom.table[:, COL_DELTA], np.arctan(0.05))
    assert equivalent_conicity(geom) == pytest.approx(0.05, rel=1e-12)


def test_demo_worn_table_is_consistent_circle_geometry():
    """Demonstration worn table (two circular arcs in internal tangency): the contact point moves
    on the tread by R_w/D times the wheelset shift and the tread slope there is tan(delta), so
    dr/dy = (R_w/D) tan(delta) (finite differences, 1 %); equivalent conicity
    ~ delta0 R_w/(R_w - R_r) = 0.0625 (small-angle closed form, 2 %)."""
    geom = table_geometry(ContactParameters(profile="table"))
    y, r, d = geom.table[:, 0], geom.table[:, COL_R], geom.table[:, COL_DELTA]
    dr = np.gradient(r, y)
    inner = slice(5, -5)
    # dr/dy = R_w sin(delta) ddelta/dy = R_w sin(delta) / (D cos delta) = tan(delta) R_w / D
    assert np.allclose(dr[inner], np.tan(d[inner]) * 0.5 / 0.2, rtol=1e-2)
    assert equivalent_conicity(geom) == pytest.approx(0.025 * 0.5 / 0.2, rel=2e-2)
    assert geom.hertz_g == pytest.approx(hertz_g(0.43, "worn"))


def _linear_creep_reference(p, normal, xi_x, xi_y, xi_sp):
    """Independent Kalker linear forces for the cone at y = 0 (physics.md s.4 formulas)."""
    e, nu = p.youngs_modulus, p.poisson
    gs = e / (2 * (1 + nu))
    curv_a, curv_b = 0.5 / p.wheel_radius, 0.5 / p.rail_head_radius
    m, n = hertz_ellipse_mn(curv_a, curv_b)
    c = (3 * normal * (1 - nu ** 2) / (2 * e * (curv_a + curv_b))) ** (1 / 3)
    a, b = m * c, n * c
    c11, c22, c23, c33 = kalker_coefficients(a / b)
    f11, f22 = gs * a * b * c11, gs * a * b * c22
    f23, f33 = gs * (a * b) ** 1.5 * c23, gs * (a * b) ** 2 * c33
    return -f11 * xi_x, -f22 * xi_y - f23 * xi_sp, f23 * xi_y - f33 * xi_sp


def test_wheel_contact_forces_match_kalker_and_she_formulas():
    """One wheel with a small yaw angle: normal force from Hertz, creep forces from Kalker
    (independent re-implementation above) scaled by SHE, resolved into track axes with the
    contact angle. Relative tolerance 1e-9."""
    p = ContactParameters()
    geom = build_geometry(p)
    speed = 80.0
    g = geom.hertz_g
    pen = 1.0e-4
    yaw = 2e-4
    out = wheel_contact(1.0, geom, speed, {"z": -pen, "yaw": yaw}, {})
    delta = np.arctan(p.conicity)
    normal = (pen * np.cos(delta) / g) ** 1.5
    assert out[4] == pytest.approx(normal, rel=1e-12)
    xi_y = -yaw * np.cos(delta)             # v_lat = -V yaw
    xi_sp = -np.sin(delta) / p.wheel_radius  # left wheel, no yaw rate
    tx, ty, mz = _linear_creep_reference(p, normal, 0.0, xi_y, xi_sp)
    beta = np.hypot(tx, ty) / (p.friction * normal)
    k = p.friction * normal * (beta - beta ** 2 / 3 + beta ** 3 / 27) / np.hypot(tx, ty)
    assert out[0] == pytest.approx(k * tx, abs=1e-9)
    assert out[3] == pytest.approx(k * mz, rel=1e-9)
    fy = -normal * np.sin(delta) + k * ty * np.cos(delta)
    fz = normal * np.cos(delta) + k * ty * np.sin(delta)
    assert out[1] == pytest.approx(fy, rel=1e-9)
    assert out[2] == pytest.approx(fz, rel=1e-9)


def test_loss_of_contact_and_flange_spring():
    """Lifted wheel: no normal or creep force. Beyond the flange clearance: lateral force
    -k_f (y - gap) on the left wheel, +k_f(-y - gap) on the right (Knudsen et al. 1991 model)."""
    p = ContactParameters()
    geom = build_geometry(p)
    out = wheel_contact(1.0, geom, 80.0, {"z": 1e-4}, {})
    assert out[4] == 0.0 and out[0] == 0.0 and out[1] == 0.0 and out[2] == 0.0
    y = p.flange_clearance + 2e-3
    lifted = {"z": 1.0, "y": y}
    assert wheel_contact(1.0, geom, 80.0, lifted, {})[1] == pytest.approx(-p.flange_stiffness * 2e-3)
    assert wheel_contact(-1.0, geom, 80.0, {"z": 1.0, "y": -y}, {})[1] == pytest.approx(
        p.flange_stiffness * 2e-3)
    # inside the clearance: no flange force
    assert wheel_contact(1.0, geom, 80.0, {"z": 1.0, "y": y - 3e-3}, {})[1] == 0.0
    # a rail moved by the same amount as the wheelset: no relative displacement, no flange force
    assert wheel_contact(1.0, geom, 80.0, {"z": 1.0, "y": y}, {"y": y})[1] == 0.0


def test_gravitational_and_creep_restoring_directions():
    """Physical signs (Wickens, Fundamentals of rail vehicle dynamics, ch. 2: kinematic
    oscillation): a wheelset yawed to the left (psi > 0) and held laterally slides to the right
    relative to its rolling direction, so the creep force pushes it LEFT, along its heading
    (F_y > 0 summed over both wheels); a wheelset displaced left rolls on a larger left radius,
    so the left wheel's contact slides backwards and its creep force points forward (F_x > 0),
    the right one backward: the yaw moment turns it back to the centre."""
    geom = build_geometry(ContactParameters())
    ws = {"z": -1e-4, "yaw": 1e-3}
    fy = wheel_contact(1.0, geom, 80.0, ws, {})[1] + wheel_contact(-1.0, geom, 80.0, ws, {})[1]
    assert fy > 0
    ws = {"z": -1e-4, "y": 2e-3}
    assert wheel_contact(1.0, geom, 80.0, ws, {})[0] > 0
    assert wheel_contact(-1.0, geom, 80.0, ws, {})[0] < 0


def test_profile_table_file_errors(tmp_path):
    """Bad profile tables fail with the file and column named."""
    import pandas as pd
    path = tmp_path / "profile.csv"
    pd.DataFrame({"y_rel_m": [0.0, 0.001, 0.002], "rolling_radius_m": [0.43, 0.43, np.nan],
                  "gap_change_m": 0.0, "contact_angle_rad": 0.02,
                  "wheel_transverse_radius_m": -0.5}).to_csv(path, index=False)
    p = dataclasses.replace(ContactParameters(), profile="table", profile_table=str(path))
    with pytest.raises(ValueError, match="rolling_radius_m"):
        table_geometry(p)
