"""Hunting stability on rigid straight track: the linear theory of the model's own vehicle
(ttbpipe.vehicle.hunting) against closed forms and against the time loop
(ttbpipe.simulation.hunting).

References: the kinematic oscillation of a coned wheelset (Klingel 1883; Wickens, Fundamentals
of Rail Vehicle Dynamics, 2003; Iwnicki (ed.), Handbook of Railway Vehicle Dynamics, 2006),
f = V / (2 pi) sqrt(lambda / (r0 a0)); the Routh-Hurwitz critical speed of Wickens' linear
wheelset with lateral and yaw springs (derived in
:func:`ttbpipe.vehicle.hunting.wheelset_critical_speed`); a linear critical speed is the speed at
which a small disturbance of the nonlinear system stops decaying (Hopf bifurcation), so the time
loop's growth rates must change sign there (a second method). Every test runs in a few seconds
(the time-loop ones 3-6 s).
"""

from __future__ import annotations

import numpy as np
import pytest

from ttbpipe.simulation import hunting as sim
from ttbpipe.vehicle import hunting as lin
from ttbpipe.vehicle.contact import (COL_C23, COL_C33, COL_DELTA, COL_DZ, build_geometry,
                                     creep_coefficients)
from ttbpipe.vehicle.kernels import contact_forces
from ttbpipe.vehicle.model import build_train_model
from ttbpipe.vehicle.parameters import CarParameters, ContactParameters, train_from_config

CAR = CarParameters()
LOAD = 70.0e3          # N per wheel


def _rolling_radius_only(conicity):
    """Wickens' idealised wheelset: the cone's rolling radii, but no contact angle, no gap
    change (no roll or gravitational coupling) and no spin creep (C23 = C33 = 0)."""
    geom = build_geometry(ContactParameters(conicity=conicity))
    geom.table[:, COL_DZ] = 0.0
    geom.table[:, COL_DELTA] = 0.0
    geom.table[:, COL_C23] = 0.0
    geom.table[:, COL_C33] = 0.0
    return geom


def _wheelset(geom, speed, k_y=0.0, k_yaw=0.0, held=0.0):
    """One wheelset on its two contacts with a lateral and a yaw spring to ground; ``held``: a
    vertical and roll spring (the closed form has neither DOF); vertical dampers keep the
    Hertz bounce from being undamped."""
    mass = np.array([CAR.wheelset_mass, CAR.wheelset_mass, CAR.wheelset_roll_inertia,
                     CAR.wheelset_spin_inertia, CAR.wheelset_yaw_inertia])
    k = np.diag([k_y, held, held, 0.0, k_yaw])
    c = np.diag([0.0, 8.0e4, 8.0e4, 0.0, 0.0])
    return lin.linear_system(mass, k, c, np.array([[0, 1, 2, 3, 4]]), geom,
                             lin.contact_slopes(geom), speed, np.array([[LOAD, LOAD]]))


@pytest.mark.parametrize("profile", ["conical", "profiles"])
def test_linearised_contact_equals_the_kernels_derivatives(profile):
    """The written-out linearisation (Hertz, contact angle, roll, Kalker with its load and table
    dependence, Shen-Hedrick-Elkins about the static spin creep force) against central
    differences of the coupled loop's own contact kernel at the static state of one wheelset
    (70 kN per wheel, 80 m/s): every entry within 1e-5 of its row's largest (measured 1.3e-8 for
    the cone, 7.8e-7 for S1002/60E1, whose table is piecewise linear on 0.1 mm)."""
    # the one-point contact the linear analysis covers (profiles: contact_points 1)
    geom = build_geometry(ContactParameters(profile=profile, contact_points=1))
    slopes = lin.contact_slopes(geom)
    speed = 80.0
    p0 = geom.hertz_g * LOAD ** (2.0 / 3.0) / np.cos(slopes.row0[COL_DELTA])
    z0 = slopes.row0[COL_DZ] - p0
    dofs = np.array([[0, 1, 2, 3, 4]])

    def force(x, part=0):
        q, v = x[:5].copy(), x[5:].copy()
        q[1] += z0
        return contact_forces(q, v, dofs, geom, speed, np.zeros((1, 2, 4)))[part]

    assert np.allclose(force(np.zeros(10), 1)[0, :, 4], LOAD, rtol=1e-9)   # normal forces
    numeric = np.zeros((5, 10))
    for j in range(10):
        eps = 1e-8 if j < 5 else 1e-6
        dx = np.zeros(10)
        dx[j] = eps
        numeric[:, j] = (force(dx) - force(-dx)) / (2 * eps)
    analytic = (lin.wheel_jacobian(geom, slopes, 1.0, speed, LOAD)
                + lin.wheel_jacobian(geom, slopes, -1.0, speed, LOAD))
    scale = np.abs(numeric).max(axis=1, keepdims=True)
    assert np.all(np.abs(analytic - numeric) <= 1e-5 * scale)


@pytest.mark.parametrize("conicity", [0.04, 0.2])
def test_free_wheelset_oscillates_at_klingels_kinematic_frequency(conicity):
    """A free wheelset (no springs) at low speed (1 m/s: the inertia terms vanish against the
    creep terms) oscillates at Klingel's kinematic frequency: within 0.1 % for the idealised
    rolling-radius contact (measured 1.2e-5), and for the model's cone (contact angle and
    gap change lambda y: the wheelset rolls by lambda y / a0) within 0.1 % of Klingel's
    frequency divided by sqrt(1 + lambda r0/a0 + lambda tan delta0) (measured 1.2e-5), i.e.
    1.2 % (lambda 0.04) and 7 % (0.2) below Klingel's."""
    speed = 1.0
    for geom, angle in ((_rolling_radius_only(conicity), None),
                        (build_geometry(ContactParameters(conicity=conicity)),
                         float(np.arctan(conicity)))):
        w, _ = _wheelset(geom, speed).modes()
        osc = w[np.abs(w.imag) > 1e-9]
        kinematic = osc[np.argmin(np.abs(osc))]
        reference = lin.klingel_frequency(speed, conicity, geom.wheel_radius,
                                          geom.contact_half_distance, angle)
        assert abs(kinematic.imag) / (2 * np.pi) == pytest.approx(reference, rel=1e-3)
        # a free wheelset is unstable at every speed (Wickens), only slowly at low speed
        assert 0.0 < kinematic.real < 0.1 * abs(kinematic.imag)
    plain = lin.klingel_frequency(speed, conicity, geom.wheel_radius, geom.contact_half_distance)
    assert abs(kinematic.imag) / (2 * np.pi) < (1.0 - 0.01) * plain


@pytest.mark.parametrize("conicity", [0.04, 0.2])
@pytest.mark.parametrize("k_y, k_yaw", [(2.0e6, 5.0e6), (1.0e7, 1.0e6)])
def test_sprung_wheelset_critical_speed_is_wickens_routh_hurwitz(conicity, k_y, k_yaw):
    """The idealised wheelset with lateral and yaw springs to ground, its vertical and roll
    motion held (1e14 N/m, N m/rad): the eigenvalue scan's critical speed and frequency equal
    the Routh-Hurwitz closed form of Wickens' equations within 1e-4 (measured 1e-7). With the
    spring pair (5e5, 2e7) it is stable at every speed, as the closed form says."""
    geom = _rolling_radius_only(conicity)
    f11, f22, _, _ = creep_coefficients(geom, LOAD)
    v_ref, f_ref = lin.wheelset_critical_speed(
        CAR.wheelset_mass, CAR.wheelset_yaw_inertia, k_y, k_yaw, f11, f22, conicity,
        geom.wheel_radius, geom.contact_half_distance)
    found = lin.critical_speed(lambda v: _wheelset(geom, v, k_y, k_yaw, held=1e14), 1.0, 400.0, 80)
    assert 20.0 < v_ref < 300.0
    assert found.speed_m_s == pytest.approx(v_ref, rel=1e-4)
    assert found.frequency_hz == pytest.approx(f_ref, rel=1e-4)
    stable = lin.wheelset_critical_speed(CAR.wheelset_mass, CAR.wheelset_yaw_inertia, 5e5, 2e7,
                                         f11, f22, conicity, geom.wheel_radius,
                                         geom.contact_half_distance)[0]
    assert stable == float("inf")
    scan = lin.critical_speed(lambda v: _wheelset(geom, v, 5e5, 2e7, held=1e14), 1.0, 400.0, 20)
    assert np.isnan(scan.speed_m_s)


def _car(contact):
    train = train_from_config({"composition": ["trailer"], "contact": contact})
    return lin.car_statics(build_train_model(train), build_geometry(train.contact))


@pytest.mark.parametrize("conicity", [0.04, 0.2])
def test_time_loop_hunts_above_the_linear_critical_speed_of_a_cone(conicity):
    """One trailer car on rigid straight track with coned wheels (the default conicity 0.04,
    car-body hunting at 2.6 Hz, and 0.2, bogie hunting at 5.0 Hz): the linear critical speed
    from the eigenvalues (682.5 and 566.0 km/h) against the time loop, whose leading wheelset
    is moved 0.5 mm at t = 0 and followed for 10 s at 2.5 % below and above it. Below, the
    oscillation decays, above it grows; the speed where the fitted growth rate changes sign is
    within 1 % of the linear one (measured 0.01 % and 0.04 % in benchmarks/hunting_stability.py),
    and each growth rate is within 0.01 1/s of the linear least-damped eigenvalue's real part
    and its frequency within 1 % (the nonlinear model linearised exactly: measured within
    0.003 1/s and 0.1 %)."""
    contact = {"conicity": conicity}
    statics = _car(contact)
    slopes = lin.contact_slopes(statics.geom)
    crit = lin.critical_speed(lambda v: lin.car_system(statics, slopes, v), 100.0, 250.0, 16)
    assert 3.6 * 100.0 < crit.speed_kmh < 3.6 * 250.0
    speeds = [0.975 * crit.speed_kmh, 1.025 * crit.speed_kmh]
    rates = []
    for v in speeds:
        run = sim.disturbed_run(sim.hunting_case(contact, v), 10.0, 5e-4)
        rate, freq = sim.growth_rate(run.time, run.lateral[:, 0], 5.0)
        mode = lin.least_damped(lin.car_system(statics, slopes, v / 3.6), min_frequency_hz=1.0)
        assert rate == pytest.approx(mode["real_1_s"], abs=0.01)
        assert freq == pytest.approx(mode["frequency_hz"], rel=0.01)
        rates.append(rate)
    assert rates[0] < 0.0 < rates[1]
    assert sim.zero_crossing(speeds, rates) == pytest.approx(crit.speed_kmh, rel=0.01)


def test_s1002_hunts_on_a_limit_cycle_between_the_quasi_linear_and_the_tangent_speed():
    """S1002 on 60E1 at 1:40: the rigid contact jumps 0.25 mm off centre (tread to a second
    point towards the flange), so the equivalent conicity rises from 0.11 (tangent, |y| < 0.25
    mm) to about 0.63 at 0.35-0.4 mm and falls to 0.17 at 3 mm. Linear theory at the tangent
    slopes puts the critical speed near 880 km/h, at the equivalent conicity (EN 15302, the
    quasi-linear method) its minimum over the amplitude near 210 km/h. The time loop must show
    both: at 1.2 times that minimum a 0.05 mm disturbance decays (the centred run is stable),
    while a 2 mm one settles on a limit cycle (last 2 s: amplitude 0.1-1 mm, not decaying:
    subcritical bifurcation); at 0.9 times the minimum the 2 mm disturbance dies out
    (below 1e-3 of it after 6 s). Measured: 8e-7 of the small disturbance left, a 0.395 mm
    limit cycle, 5e-7 of the large one left below (benchmarks/hunting_stability.py maps the
    whole branch: it dies between 215 and 216 km/h, 3.7 % above the quasi-linear 207.9)."""
    contact = {"profile": "profiles", "contact_points": 1}
    statics = _car(contact)
    centre = lin.contact_slopes(statics.geom)
    tangent = lin.critical_speed(lambda v: lin.car_system(statics, centre, v), 100.0, 300.0, 20)
    quasi = []
    for a in (0.3e-3, 0.35e-3, 0.4e-3, 0.5e-3):
        sl = lin.contact_slopes(statics.geom, a)
        crit = lin.critical_speed(lambda v: lin.car_system(statics, sl, v), 20.0, 150.0, 14)
        quasi.append(crit.speed_kmh)
    v_min = min(quasi)
    assert 3 * v_min < tangent.speed_kmh
    above, below = 1.2 * v_min, 0.9 * v_min
    small = sim.disturbed_run(sim.hunting_case(contact, above), 6.0, 5e-5)
    assert small.amplitude(1.0) < 0.1 * 5e-5
    large = sim.disturbed_run(sim.hunting_case(contact, above), 6.0, 2e-3)
    amp_late, amp_mid = large.amplitude(1.0), large.amplitude(3.0)
    assert 1e-4 < amp_late < 1e-3
    assert amp_late > 0.95 * amp_mid
    dies = sim.disturbed_run(sim.hunting_case(contact, below), 6.0, 2e-3)
    assert dies.amplitude(1.0) < 1e-3 * 2e-3


def test_growth_rate_of_a_damped_sinusoid():
    """The estimator on y = e^(sigma t) cos(2 pi f t + 0.3) sampled at 0.1 ms: sigma and f
    within 1e-3 (relative for f, absolute 1/s for sigma)."""
    t = np.arange(0.0, 8.0, 1e-4)
    for sigma, f in ((-0.37, 2.6), (0.12, 8.4)):
        rate, freq = sim.growth_rate(t, np.exp(sigma * t) * np.cos(2 * np.pi * f * t + 0.3), 2.0)
        assert rate == pytest.approx(sigma, abs=1e-3)
        assert freq == pytest.approx(f, rel=1e-3)


def test_two_point_geometry_is_refused_with_the_remedy():
    """The linearisation covers one contact point per wheel; a profile pair's two-point
    geometry (the default for profiles) must be refused, naming contact_points: 1."""
    geom = build_geometry(ContactParameters(profile="profiles"))
    with pytest.raises(ValueError, match="contact_points: 1"):
        _wheelset(geom, 50.0, k_y=1e6, k_yaw=1e6)
    # and a creep law it does not linearise (creep_law: polach), naming the one it does
    geom = build_geometry(ContactParameters(creep_law="polach"))
    with pytest.raises(ValueError, match="creep_law: kalker_she"):
        _wheelset(geom, 50.0, k_y=1e6, k_yaw=1e6)
