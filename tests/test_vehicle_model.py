"""35-DOF car matrices (ttbpipe.vehicle.model) and parameters (ttbpipe.vehicle.parameters)."""

import numpy as np
import pytest
import scipy.linalg as sla

from ttbpipe.vehicle.model import (DOF_PER_BODY, DOF_PER_CAR, PITCH, ROLL, YAW, Y, Z,
                                   _body_positions, build_train_model, car_elements)
from ttbpipe.vehicle.parameters import (TrainParameters, motor_car, trailer_car,
                                        train_from_config)


def _single(car):
    return build_train_model(TrainParameters(cars=[car]))


def test_matrices_symmetric_positive_semidefinite():
    """K = sum k N^T N and C = sum c N^T N are symmetric PSD by construction (seed App. B)."""
    m = build_train_model(TrainParameters())
    for mat in (m.stiffness, m.damping):
        dense = mat.toarray()
        assert np.allclose(dense, dense.T, atol=1e-6)
        assert np.linalg.eigvalsh(dense).min() > -1e-6 * np.abs(dense).max()
    assert m.n_dof == 35 * 5 and np.all(m.mass > 0)


def _rigid_mode(car, r0, kind):
    """Whole-car rigid motion: translation y/z or small rotation (roll, pitch, yaw) about the car
    centre at rail level; each body's DOFs from u + theta x r."""
    pos = _body_positions(car, r0)
    q = np.zeros(DOF_PER_CAR)
    for b in range(7):
        x, _, z = pos[b]
        d = q[DOF_PER_BODY * b:DOF_PER_BODY * (b + 1)]
        if kind == "y":
            d[Y] = 1
        elif kind == "z":
            d[Z] = 1
        elif kind == "roll":
            d[ROLL], d[Y] = 1, -z
        elif kind == "pitch":
            d[PITCH], d[Z] = 1, -x
        elif kind == "yaw":
            d[YAW], d[Y] = 1, x
    return q


@pytest.mark.parametrize("kind", ["y", "z", "roll", "pitch", "yaw"])
def test_rigid_body_motions_are_stress_free(kind):
    """A rigid motion of the whole car stretches no suspension element: K q_rigid = 0.
    (Wheelset pitch is its spin and is not touched by the suspension, so rigid pitch leaves it at
    any value.) Rigid pitch also needs different longitudinal translations of bodies at different
    heights, which the 35-DOF model (no x DOF, like the seed paper's App. B N_sx with its H_cb,
    H_bt terms) cannot represent, so for pitch the longitudinal springs are switched off.
    Tolerance 1e-9 of the largest force of a unit body displacement."""
    import dataclasses
    car = trailer_car()
    if kind == "pitch":
        car = dataclasses.replace(car, primary_kx=0.0, secondary_kx=0.0)
    m = _single(car)
    q = _rigid_mode(car, m.params.contact.wheel_radius, kind)
    for w in m.wheelset_dofs:
        q[w[PITCH]] = 0.0
    f = m.stiffness @ q
    assert np.max(np.abs(f)) < 1e-9 * abs(m.stiffness).max()


def test_secondary_vertical_shape_vector_matches_appendix_b():
    """N_sz1,1 = [1 -d_s -l_c -1 d_s] on (z_c, roll_c, pitch_c, z_Gq, roll_Gq) (seed paper App. B),
    up to the roll sign convention (this model: roll lifts the left side)."""
    car = trailer_car()
    els = [e for e in car_elements(car, 0.43) if e.name == "secondary_z"]
    front_left = els[0]
    coeffs = dict(zip(front_left.dofs.tolist(), front_left.shape.tolist()))
    got = [coeffs[Z], coeffs[ROLL], coeffs[PITCH], coeffs[5 + Z], coeffs[5 + ROLL]]
    ds, lc = car.secondary_half_spacing, car.bogie_half_spacing
    assert np.allclose(np.abs(got), [1, ds, lc, 1, ds])
    assert got[0] == 1 and got[3] == -1 and got[2] == -lc


def test_bounce_frequencies_per_bogie_units():
    """Car-body bounce 0.75 Hz and bogie bounce 6.0 Hz with wheelsets held (physics.md s.6 [C]:
    these reproduce the paper only with Zeng's per-bogie/per-wheelset stiffness, i.e. per-spring
    values halved; physics.md section 7 item 8). Tolerance 2 % (physics.md gives 2 digits)."""
    car = trailer_car()
    m = _single(car)
    keep = np.arange(15)  # car body and bogies; wheelsets fixed
    k = m.stiffness.toarray()[np.ix_(keep, keep)]
    mass = np.diag(m.mass[keep])
    freqs = np.sqrt(np.abs(sla.eigh(k, mass, eigvals_only=True))) / (2 * np.pi)
    # car-body bounce: series secondary (4 springs) and primary (8 springs), closed form
    k_s, k_p = 4 * car.secondary_kz, 8 * car.primary_kz
    f_car = np.sqrt(k_s * k_p / (k_s + k_p) / car.car_mass) / (2 * np.pi)
    assert f_car == pytest.approx(0.75, rel=0.02)
    assert np.min(np.abs(freqs - f_car)) < 0.02 * f_car
    f_bogie = np.sqrt((4 * car.primary_kz + 2 * car.secondary_kz) / car.bogie_mass) / (2 * np.pi)
    assert f_bogie == pytest.approx(6.0, rel=0.02)
    assert np.min(np.abs(freqs - f_bogie)) < 0.02 * f_bogie


def test_config_overrides_and_errors():
    """Every parameter is overridable; unknown keys and wrong kinds fail with the key path."""
    train = train_from_config({"composition": ["motor", "trailer"], "trailer": {"car_mass": 40000},
                               "car_overrides": {0: {"bogie_mass": 3500}},
                               "contact": {"conicity": 0.03}, "coupler": {"ky": 0}})
    assert train.cars[1].car_mass == 40000 and train.cars[0].bogie_mass == 3500
    assert train.cars[0].car_mass == motor_car().car_mass
    assert train.contact.conicity == 0.03 and train.coupler.ky == 0
    with pytest.raises(ValueError, match="train.trailer"):
        train_from_config({"trailer": {"car_mas": 1}})
    with pytest.raises(ValueError, match=r"composition\[1\]"):
        train_from_config({"composition": ["motor", "locomotive"]})
    with pytest.raises(ValueError, match="expected a number"):
        train_from_config({"motor": {"car_mass": "heavy"}})


def test_train_layout_and_static_loads():
    """Default train: motor, 3 trailers, motor; 25 m cars; axle pattern 2.5 / 14.875 / 5.125 m;
    static wheel load = g (Mc/8 + Mt/4 + Mw/2)."""
    m = build_train_model(TrainParameters())
    assert [c.kind for c in m.params.cars] == ["motor", "trailer", "trailer", "trailer", "motor"]
    gaps = -np.diff(m.wheelset_x[:5])
    assert np.allclose(gaps, [2.5, 14.875, 2.5, 5.125])
    motor = motor_car()
    assert m.static_wheel_load[0] == pytest.approx(9.80665 * (48000 / 8 + 3200 / 4 + 2400 / 2))
    # couplers present between 4 pairs of cars, acting in y and z
    assert m.coupler_stiffness.nnz > 0


def test_coupler_acts_between_car_ends_in_y_and_z():
    """Coupler element: a lateral shift of car 1's body loads car 1 and car 2 with -+k_y; a yaw of
    car 1 moves its rear coupler head by -L/2 * yaw, so the coupler force is k_y L/2 per radian
    and the yaw moment k_y (L/2)^2 (lever arithmetic, exact). Vertical likewise with pitch."""
    train = TrainParameters(cars=[trailer_car(), trailer_car()])
    m = build_train_model(train)
    kc = m.coupler_stiffness
    ky, kz, half = train.coupler.ky, train.coupler.kz, train.cars[0].car_length / 2
    q = np.zeros(m.n_dof)
    q[Y] = 1.0
    f = kc @ q
    assert f[Y] == pytest.approx(ky) and f[DOF_PER_CAR + Y] == pytest.approx(-ky)
    q = np.zeros(m.n_dof)
    q[YAW] = 1.0
    f = kc @ q
    assert f[DOF_PER_CAR + Y] == pytest.approx(ky * half)   # head moved to -y; elastic force -Kq on car 2 also -y
    assert f[YAW] == pytest.approx(ky * half ** 2)
    q = np.zeros(m.n_dof)
    q[PITCH] = 1.0   # rear head (x = -L/2) moves up by +L/2
    f = kc @ q
    assert f[DOF_PER_CAR + Z] == pytest.approx(-kz * half)
    assert f[PITCH] == pytest.approx(kz * half ** 2)


def test_csr_kernel_matches_scipy_on_the_train_matrices():
    """The loop's suspension product (``csr_matvec_sub``: out -= A x, unsigned indices) against
    scipy.sparse on the 5-car train's K and C: the same row sums in the same order, so equal to
    1e-14 of the largest term (scipy's CSR product is the independent reference)."""
    from ttbpipe.vehicle.kernels import csr_matvec_sub

    m = build_train_model(TrainParameters())
    rng = np.random.default_rng(5)
    x, out0 = rng.normal(size=m.n_dof), rng.normal(size=m.n_dof)
    for mat in (m.stiffness.tocsr(), m.damping.tocsr()):
        out = out0.copy()
        csr_matvec_sub(mat.indptr.astype(np.int64), mat.indices.astype(np.int64), mat.data,
                       x, out)
        ref = out0 - mat @ x
        scale = np.abs(mat).max() * np.abs(x).max()
        assert np.max(np.abs(out - ref)) <= 1e-14 * scale
        assert not np.allclose(out, out0)
