"""Contact of a yawed wheelset: the trace line against a search over the whole wheel surface,
the yaw layers of the two-point tables, and the kernel's use of them.

Second method: the wheel's surface of revolution is sampled in its profile coordinate and its
angle about the axle, every point placed in track axes exactly (yaw about the vertical), and the
smallest vertical gap to the straight rail taken (a coarse grid over the lower quarter of the
wheel, then a fine grid around its best point). Tolerances: the fine grid's angle step 2e-5 rad
(R d theta = 9 um along x, a gap error below 1e-3 um), the profile's sample step 0.02 mm.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ttbpipe.vehicle.contact import COL_DZ, COL_LEAD, build_geometry, wheel_contact_points
from ttbpipe.vehicle.contact_geometry import ContactPair
from ttbpipe.vehicle.parameters import ContactParameters
from ttbpipe.vehicle.profile_contact import zone_tables
from ttbpipe.vehicle.profiles import profile_by_name_or_path

MM = 1e-3


@pytest.fixture(scope="module")
def pair():
    return ContactPair(profile_by_name_or_path("s1002", "wheel"),
                       profile_by_name_or_path("60e1", "rail"))


def _surface_search(pair, y, yaw):
    """Smallest vertical gap between the left wheel's surface (yawed by ``yaw``, shifted by
    ``y``, no roll) and its rail: (gap, track y, x) of the best surface point."""
    w, rail = pair._wheels[0], pair._rails[0]
    u_all = w.base + w.s
    r_all = pair._radius(0) - w.zw
    sp, cp = np.sin(yaw), np.cos(yaw)

    def best(idx, theta):
        u, r = u_all[idx][:, None], r_all[idx][:, None]
        st, ct = np.sin(theta)[None, :], np.cos(theta)[None, :]
        y_t = y + u * cp + r * st * sp
        z = -r * ct
        x = -u * sp + r * st * cp
        z_rail = np.interp(y_t, rail.u, rail.z, left=np.nan, right=np.nan)
        gap = np.where(np.isfinite(z_rail), z - z_rail, np.inf)
        k = np.unravel_index(np.argmin(gap), gap.shape)
        return gap[k], y_t[k], x[k], idx[k[0]], theta[k[1]]

    _, _, _, i0, t0 = best(np.arange(u_all.size), np.linspace(-0.25, 0.25, 501))
    window = np.arange(max(i0 - 60, 0), min(i0 + 61, u_all.size))
    gap, y_t, x, _, _ = best(window, t0 + np.linspace(-2e-3, 2e-3, 201))
    return gap, y_t, x


@pytest.mark.parametrize("yaw", [0.01, 0.03])
@pytest.mark.parametrize("y", [0.0, 4 * MM, 6.5 * MM, 8 * MM])
def test_trace_line_contact_matches_a_search_over_the_wheel_surface(pair, y, yaw):
    """S1002 on 60E1 at 1:40: tread (0, 4 mm), tread or flange root (6.5 mm) and flange (8 mm)
    at 10 and 30 mrad yaw. The trace line's contact equals the surface search's best point:
    gap within 0.01 um, track lateral within 0.02 mm, lead within 0.05 mm. The yaw changes the
    gap by 0.9-530 um here: the comparison would see a trace line that is wrong."""
    got = pair._contact(0, np.array([y]), np.zeros(1), np.zeros(1), yaw)
    gap, y_t, x = _surface_search(pair, y, yaw)
    assert got["gap"][0] == pytest.approx(gap, abs=1e-8)
    assert got["track_position"][0] == pytest.approx(y_t, abs=2e-5)
    assert got["longitudinal_position"][0] == pytest.approx(x, abs=5e-5)
    unyawed = pair._contact(0, np.array([y]), np.zeros(1), np.zeros(1))
    assert abs(unyawed["gap"][0] - gap) > 5e-7
    assert unyawed["longitudinal_position"][0] == 0.0


def test_flange_contact_leads_the_axle_by_the_closed_form(pair):
    """In flange contact the point on the trace line lies ahead of the wheel's plane by
    R sin(theta), sin(theta) = tan(delta) tan(psi) (Wang 1984; to first order the flange-contact
    lead R tan(delta) psi), delta the contact angle (wheel and rail share the tangent; no roll),
    the wheel's plane itself at -u sin(psi). Checked with the contact's own radius and angle at
    y = 9 mm (delta about 70 degrees), where the lead is over 10 mm at 10 mrad."""
    yaw = 0.01
    got = pair._contact(0, np.array([9 * MM]), np.zeros(1), np.zeros(1), yaw)
    assert np.degrees(got["angle"][0]) > 60.0
    r = got["rolling_radius"][0]
    u = got["track_position"][0] - 9 * MM           # the point's lateral from the wheelset centre
    lead_from_plane = got["longitudinal_position"][0] + u * np.sin(yaw)
    expected = r * np.tan(got["angle"][0]) * np.tan(yaw) * np.cos(yaw)
    assert lead_from_plane == pytest.approx(expected, rel=2e-3)
    assert lead_from_plane > 10 * MM


@pytest.fixture(scope="module")
def geometries():
    p = ContactParameters(profile="profiles", wheel_radius=0.46)
    return p, build_geometry(p), build_geometry(dataclasses.replace(p, yaw_layers=1))


def test_zero_yaw_layer_is_the_unyawed_table(geometries):
    p, geom, flat = geometries
    layers = geom.zone_array()
    assert layers.shape[:2] == (2, p.yaw_layers)
    np.testing.assert_array_equal(layers[:, 0], flat.zones)
    np.testing.assert_array_equal(geom.zones, flat.zones)
    # at zero yaw the kernel gives the yaw-free geometry's forces bit for bit
    for y in (0.0, 3 * MM, 7.5 * MM):
        ws = {"y": y, "z": -1e-4, "vy": 0.01, "vyaw": 0.02}
        np.testing.assert_array_equal(wheel_contact_points(1.0, geom, 80.0, ws, {}),
                                      wheel_contact_points(1.0, flat, 80.0, ws, {}))


@pytest.mark.parametrize("yaw", [0.003, 0.007, 0.013, 0.022, 0.027])
def test_yaw_layers_interpolate_the_direct_tables(geometries, yaw):
    """The kernel's penetration at table rows (y on the grid) and a yaw between layers (5 mrad
    apart) against the zone tables computed directly at that yaw. Away from the rows where the
    flange zone's own contact jumps from the root to the flank (6.2-7.0 mm: the jump moves
    with yaw, a kink no table resolves within one step) the contact's gap change is nearly
    quadratic in yaw, and linear interpolation in yaw^2 between neighbouring layers holds it to
    1 % of the yaw's effect plus 0.2 um (measured 0.05-4.1 um against effects of 7-600 um;
    layers uniform in yaw^2, 0 and 18 mrad apart at small yaw, missed by 9 %)."""
    p, geom, _ = geometries
    direct = zone_tables(p, yaw=yaw, split=geom.flange_cut)[0]
    y_grid = direct[0, :, 0]
    rows = np.flatnonzero((np.abs(y_grid) <= 12 * MM) & ((y_grid < 6.2 * MM) | (y_grid > 7.0 * MM)))
    got = np.empty(rows.size)
    for n, i in enumerate(rows):
        out = wheel_contact_points(1.0, geom, 80.0, {"y": float(y_grid[i]), "yaw": yaw}, {})
        got[n] = out[6]                           # largest penetration at z_w = z_rail = 0
    expected = direct[:, rows, 2].max(axis=0)
    effect = np.abs(expected - geom.zones[:, rows, COL_DZ].max(axis=0))
    assert np.all(np.abs(got - expected) <= 0.01 * effect.max() + 2e-7)
    assert effect.max() > 5e-6


def test_right_wheel_mirrors_the_left(geometries):
    """Mirror symmetry through the track's centre plane: the right wheel at (-y, -yaw) with
    mirrored velocities carries the left wheel's forces with F_y, the yaw and the roll moments
    negated (the lead is odd in yaw: a sign slip would break this)."""
    _, geom, _ = geometries
    for y, yaw in ((7.5 * MM, 0.012), (2 * MM, -0.02), (8 * MM, 0.03)):
        ws = {"y": y, "z": -5e-5, "yaw": yaw, "vy": 0.02, "vyaw": 0.05, "vpitch": -80.0 / 0.46}
        mirrored = {"y": -y, "z": -5e-5, "yaw": -yaw, "vy": -0.02, "vyaw": -0.05,
                    "vpitch": -80.0 / 0.46}
        left = wheel_contact_points(1.0, geom, 80.0, ws, {})
        right = wheel_contact_points(-1.0, geom, 80.0, mirrored, {})
        sign = np.array([1, -1, 1, -1, 1, -1, 1, -1, 1, -1, -1])
        np.testing.assert_allclose(right, sign * left, rtol=1e-12, atol=1e-9)


def test_lead_enters_the_yaw_moment_and_the_lateral_creepage(geometries):
    """With every point's lead set to L, the wheel's forces equal those of the lead-free tables
    with the wheelset's lateral velocity raised by yaw' L (the point's own velocity), and its
    yaw moment exceeds theirs by L F_y (the lateral force acting L ahead of the axle)."""
    _, geom, _ = geometries
    lead = 0.012
    layers = geom.zone_array().copy()
    layers[..., COL_LEAD] = lead
    led = dataclasses.replace(geom, zone_layers=layers)
    layers0 = layers.copy()
    layers0[..., COL_LEAD] = 0.0
    free = dataclasses.replace(geom, zone_layers=layers0)
    for y in (1 * MM, 8.5 * MM):
        ws = {"y": y, "z": -5e-5, "yaw": 0.004, "vy": 0.01, "vyaw": 0.2, "vpitch": -80.0 / 0.46}
        got = wheel_contact_points(1.0, led, 80.0, ws, {})
        ref = wheel_contact_points(1.0, free, 80.0, {**ws, "vy": 0.01 + 0.2 * lead}, {})
        np.testing.assert_allclose(got[:9], ref[:9], rtol=1e-12, atol=1e-9)
        assert got[9] - ref[9] == pytest.approx(lead * got[1], rel=1e-9)
        assert abs(lead * got[1]) > 1.0


def test_contact_geometry_command_takes_the_yaw(tmp_path, pair):
    """`ttbpipe contact-geometry --yaw-mrad 10` writes the yawed wheelset's table: the leads are
    those of the pair's own search at that yaw (left and right wheel, odd in the side), the
    yaw is recorded in the provenance."""
    import pandas as pd

    from ttbpipe.cli import main
    from ttbpipe.io import read_provenance

    out = tmp_path / "cg.parquet"
    assert main(["contact-geometry", "--wheel", "s1002", "--rail", "60e1", "--y-max-mm", "8",
                 "--step-mm", "4", "--yaw-mrad", "10", "--out", str(out)]) == 0
    table = pd.read_parquet(out)
    expected = pair.solve(np.array([-8, -4, 0, 4, 8]) * MM, yaw=0.01)
    np.testing.assert_allclose(table["contact_lead_left_mm"], expected["contact_lead_left_mm"])
    # on the tread the contact follows its wheel's plane: the left one lags the axle by about
    # a psi (7.5 mm), the right one leads it; at +8 mm the left flange's lead (R tan(delta) psi)
    # nearly cancels the lag
    assert (table["contact_lead_left_mm"].iloc[:4] < -5.0).all()
    assert abs(table["contact_lead_left_mm"].iloc[4]) < 1.0
    # mirror image: the right wheel at -y leads as much as the left one at +y lags
    np.testing.assert_allclose(table["contact_lead_right_mm"].to_numpy()[::-1],
                               -table["contact_lead_left_mm"].to_numpy(), atol=1e-9)
    assert read_provenance(out)["config"]["yaw_mrad"] == 10.0


def test_wheelset_yaw_beyond_the_tables_is_reported(caplog):
    """A car curving on R = 600 m yaws its wheelsets by up to 1.6 mrad: with tables that cover
    0.1 mrad the run warns with the remedy (the kernel held the last layer); with the default
    30 mrad it does not, and the largest yaw is returned."""
    import logging

    from test_curving import _one_car_on_a_curve

    from ttbpipe.simulation.coupled import check_yaw_range, integrate, prepare

    contact = {"profile": "profiles", "yaw_max_rad": 1e-4, "yaw_layers": 2}
    case = _one_car_on_a_curve(120.0, 600.0, 100.0, length_m=15.0, contact=contact)
    setup = prepare(case)
    raw = integrate(setup)
    with caplog.at_level(logging.WARNING, logger="ttbpipe.simulation.coupled"):
        yaw = check_yaw_range(setup, raw.train)
    assert yaw > 1e-3
    assert "beyond the 0.1 mrad that the contact tables cover" in caplog.text
    assert "raise yaw_max_rad" in caplog.text
    caplog.clear()
    setup = prepare(_one_car_on_a_curve(120.0, 600.0, 100.0, length_m=15.0,
                                        contact={"profile": "profiles"}))
    with caplog.at_level(logging.WARNING, logger="ttbpipe.simulation.coupled"):
        yaw_default = check_yaw_range(setup, integrate(setup).train)
    assert 1e-3 < yaw_default < 0.03
    assert "contact tables cover" not in caplog.text
