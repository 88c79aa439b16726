"""Mass, stiffness and damping matrices of a train of 35-DOF cars (seed paper 2.2.3, Appendix B).

Degrees of freedom
------------------
Each car has 7 rigid bodies, in this order: 0 car body, 1 front bogie frame, 2 rear bogie frame,
3-6 wheelsets front to rear (direction of travel +x). Each body has 5 DOF, in this order:

    0 y (lateral, +left)   1 z (vertical, +up)   2 roll (about x)   3 pitch (about y)   4 yaw (about z)

so DOF ``35*car + 5*body + k``; right-handed small rotations. For a wheelset "pitch" is the spin
perturbation (rotation about the axle on top of the rolling speed V/r0); no suspension element
acts on it (the axle turns in its axle-box bearings). Displacements are measured from the
nominal unloaded geometry (wheel on undeformed rail, springs unstressed); gravity is an applied
force, so the static state has non-zero z.

Suspension elements (seed paper Appendix B: K = sum k N^T N)
----------------------------------------------------------
Every spring or damper is a linear element along a track axis between a point of body A and a
point of body B. With small rotations the displacement of a body point at offset r = (rx, ry, rz)
from the body's centre of gravity is u + theta x r, so its component along

    x: pitch*rz - yaw*ry,   y: y - roll*rz + yaw*rx,   z: z + roll*ry - pitch*rx.

The element's elongation is N q with N = n_A - n_B (the rows above for the two points), and the
element contributes k N^T N to K and c N^T N to C. This reproduces the shape vectors of the seed
paper's Appendix B (e.g. N_sz1,1 = [1 -d_s -l_c -1 d_s] for z_c, roll_c, pitch_c, z_Gq, roll_Gq up to
the sign convention of the rotations) and also yields the terms that Appendix B drops (the lever
arms of the lateral springs in roll), without transcription errors from the garbled print.

Elements per car: 4 air springs (z, y, x) at (+-l_c, +-d_s, H_s); 4 anti-yaw dampers (x) at
(+-l_c, +-d_yd, H_s); 8 axle-box spring groups (z, y, x) at (x_wheelset, +-d_w, H_p).

Couplers: between the rear coupler head of car i, (-L_i/2, 0, H_k), and the front head of car i+1,
(+L_{i+1}/2, 0, H_k): a spring-damper in y and one in z. They are stress-free in the static
equilibrium (see :mod:`ttbpipe.vehicle.static`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .parameters import GRAVITY, CarParameters, TrainParameters

DOF_PER_BODY = 5
BODIES_PER_CAR = 7
DOF_PER_CAR = DOF_PER_BODY * BODIES_PER_CAR
Y, Z, ROLL, PITCH, YAW = range(5)
CAR_BODY, FRONT_BOGIE, REAR_BOGIE = 0, 1, 2
WHEELSETS = (3, 4, 5, 6)
BODY_NAMES = ("carbody", "bogie1", "bogie2", "ws1", "ws2", "ws3", "ws4")
DOF_NAMES = ("y", "z", "roll", "pitch", "yaw")


def point_row(offset: np.ndarray, direction: int, spin_free: bool = False) -> np.ndarray:
    """Row (5,) giving the displacement along ``direction`` (0 x, 1 y, 2 z) of a body point.

    ``offset`` is the point's position relative to the body's centre of gravity. ``spin_free``
    zeroes the pitch coefficient (a wheelset's pitch DOF is its spin, decoupled by the bearings).
    """
    rx, ry, rz = offset
    row = np.zeros(DOF_PER_BODY)
    if direction == 0:
        row[PITCH], row[YAW] = rz, -ry
    elif direction == 1:
        row[Y], row[ROLL], row[YAW] = 1.0, -rz, rx
    elif direction == 2:
        row[Z], row[ROLL], row[PITCH] = 1.0, ry, -rx
    else:  # pragma: no cover - programming error
        raise ValueError(direction)
    if spin_free:
        row[PITCH] = 0.0
    return row


@dataclass
class Element:
    """A linear spring-damper along a track axis between two body points (global DOF indices)."""

    dofs: np.ndarray      # (10,) global DOFs: 5 of body A then 5 of body B
    shape: np.ndarray     # (10,) N: elongation = N @ q[dofs]
    stiffness: float
    damping: float
    name: str


def _body_positions(car: CarParameters, wheel_radius: float) -> np.ndarray:
    """Centres of gravity of the 7 bodies in car coordinates (x from the car centre, z above rail)."""
    lc, lt = car.bogie_half_spacing, car.wheelbase_half
    return np.array([
        [0.0, 0.0, car.car_cg_height],
        [lc, 0.0, car.bogie_cg_height],
        [-lc, 0.0, car.bogie_cg_height],
        [lc + lt, 0.0, wheel_radius],
        [lc - lt, 0.0, wheel_radius],
        [-lc + lt, 0.0, wheel_radius],
        [-lc - lt, 0.0, wheel_radius],
    ])


def car_elements(car: CarParameters, wheel_radius: float, first_dof: int = 0) -> list[Element]:
    """Suspension elements of one car, with global DOF indices starting at ``first_dof``."""
    pos = _body_positions(car, wheel_radius)
    elements: list[Element] = []

    def add(body_a: int, body_b: int, point: np.ndarray, direction: int, k: float, c: float,
            name: str) -> None:
        if k == 0.0 and c == 0.0:
            return
        row_a = point_row(point - pos[body_a], direction, spin_free=body_a >= 3)
        row_b = point_row(point - pos[body_b], direction, spin_free=body_b >= 3)
        dofs = np.concatenate([first_dof + DOF_PER_BODY * body_a + np.arange(5),
                               first_dof + DOF_PER_BODY * body_b + np.arange(5)])
        elements.append(Element(dofs, np.concatenate([row_a, -row_b]), k, c, name))

    for bogie in (FRONT_BOGIE, REAR_BOGIE):
        xb = pos[bogie, 0]
        for side in (1.0, -1.0):
            p = np.array([xb, side * car.secondary_half_spacing, car.secondary_height])
            add(CAR_BODY, bogie, p, 2, car.secondary_kz, car.secondary_cz, "secondary_z")
            add(CAR_BODY, bogie, p, 1, car.secondary_ky, car.secondary_cy, "secondary_y")
            add(CAR_BODY, bogie, p, 0, car.secondary_kx, car.secondary_cx, "secondary_x")
            p_yd = np.array([xb, side * car.yaw_damper_half_spacing, car.secondary_height])
            add(CAR_BODY, bogie, p_yd, 0, 0.0, car.yaw_damper_c, "yaw_damper")
    for ws in WHEELSETS:
        bogie = FRONT_BOGIE if ws in (3, 4) else REAR_BOGIE
        xw = pos[ws, 0]
        for side in (1.0, -1.0):
            p = np.array([xw, side * car.primary_half_spacing, car.primary_height])
            add(bogie, ws, p, 2, car.primary_kz, car.primary_cz, "primary_z")
            add(bogie, ws, p, 1, car.primary_ky, car.primary_cy, "primary_y")
            add(bogie, ws, p, 0, car.primary_kx, car.primary_cx, "primary_x")
    return elements


def coupler_elements(train: TrainParameters) -> list[Element]:
    """Coupler spring-dampers (y and z) between consecutive cars."""
    elements = []
    cp = train.coupler
    for i in range(train.n_cars - 1):
        front, rear = train.cars[i], train.cars[i + 1]
        head_a = np.array([-front.car_length / 2, 0.0, front.coupler_height - front.car_cg_height])
        head_b = np.array([rear.car_length / 2, 0.0, rear.coupler_height - rear.car_cg_height])
        dofs = np.concatenate([DOF_PER_CAR * i + np.arange(5), DOF_PER_CAR * (i + 1) + np.arange(5)])
        for direction, k, c, name in ((1, cp.ky, cp.cy, "coupler_y"), (2, cp.kz, cp.cz, "coupler_z")):
            if k == 0.0 and c == 0.0:
                continue
            shape = np.concatenate([point_row(head_a, direction), -point_row(head_b, direction)])
            elements.append(Element(dofs, shape, k, c, f"{name}_{i}"))
    return elements


def assemble(elements: list[Element], n_dof: int, which: str) -> sp.csr_matrix:
    """Sum k N^T N (``which='k'``) or c N^T N (``'c'``) over elements into a sparse matrix."""
    rows, cols, vals = [], [], []
    for el in elements:
        coef = el.stiffness if which == "k" else el.damping
        if coef == 0.0:
            continue
        block = coef * np.outer(el.shape, el.shape)
        rr, cc = np.meshgrid(el.dofs, el.dofs, indexing="ij")
        rows.append(rr.ravel()); cols.append(cc.ravel()); vals.append(block.ravel())
    if not rows:
        return sp.csr_matrix((n_dof, n_dof))
    mat = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                        shape=(n_dof, n_dof)).tocsr()
    mat.sum_duplicates()
    mat.eliminate_zeros()
    return mat


def car_mass_vector(car: CarParameters) -> np.ndarray:
    """Diagonal mass matrix of one car (35,), seed paper eq. (10)."""
    return np.array([
        car.car_mass, car.car_mass, car.car_roll_inertia, car.car_pitch_inertia, car.car_yaw_inertia,
        car.bogie_mass, car.bogie_mass, car.bogie_roll_inertia, car.bogie_pitch_inertia, car.bogie_yaw_inertia,
        car.bogie_mass, car.bogie_mass, car.bogie_roll_inertia, car.bogie_pitch_inertia, car.bogie_yaw_inertia,
        *[car.wheelset_mass, car.wheelset_mass, car.wheelset_roll_inertia, car.wheelset_spin_inertia,
          car.wheelset_yaw_inertia] * 4,
    ], dtype=float)


@dataclass
class TrainModel:
    """Assembled train: diagonal mass, sparse K and C, gravity, wheelset layout."""

    params: TrainParameters
    mass: np.ndarray               # (n,)
    stiffness: sp.csr_matrix       # suspension + couplers
    damping: sp.csr_matrix
    coupler_stiffness: sp.csr_matrix
    gravity_force: np.ndarray      # (n,)
    wheelset_dofs: np.ndarray      # (n_ws, 5) global DOF indices of each wheelset
    wheelset_x: np.ndarray         # (n_ws,) x of each wheelset relative to the leading wheelset (<= 0)
    wheelset_car: np.ndarray       # (n_ws,) car index
    car_x: np.ndarray              # (n_cars,) car centre x relative to the leading wheelset
    static_wheel_load: np.ndarray  # (n_ws,) nominal static load per wheel from the weight distribution

    @property
    def n_dof(self) -> int:
        return self.mass.size

    @property
    def n_wheelsets(self) -> int:
        return self.wheelset_x.size

    @functools.cached_property
    def suspension_stiffness(self) -> sp.csr_matrix:
        """K without the couplers (the static solve holds each car on its own suspension):
        formed once per model, read-only."""
        return (self.stiffness - self.coupler_stiffness).tocsr()


def build_train_model(train: TrainParameters) -> TrainModel:
    """Assemble the train's matrices (block-diagonal cars plus couplers)."""
    n_cars = train.n_cars
    n = DOF_PER_CAR * n_cars
    r0 = train.contact.wheel_radius
    elements: list[Element] = []
    mass = np.zeros(n)
    gravity = np.zeros(n)
    car_centre = np.zeros(n_cars)
    for i, car in enumerate(train.cars):
        elements += car_elements(car, r0, DOF_PER_CAR * i)
        mass[DOF_PER_CAR * i:DOF_PER_CAR * (i + 1)] = car_mass_vector(car)
        if i > 0:
            car_centre[i] = car_centre[i - 1] - 0.5 * (train.cars[i - 1].car_length + car.car_length)
    gravity[Z::DOF_PER_BODY] = -GRAVITY * mass[Z::DOF_PER_BODY]
    couplers = coupler_elements(train)
    k_susp = assemble(elements + couplers, n, "k")
    c_susp = assemble(elements + couplers, n, "c")
    k_coupler = assemble(couplers, n, "k")
    ws_dofs, ws_x, ws_car, p0 = [], [], [], []
    for i, car in enumerate(train.cars):
        pos = _body_positions(car, r0)
        for ws in WHEELSETS:
            ws_dofs.append(DOF_PER_CAR * i + DOF_PER_BODY * ws + np.arange(5))
            ws_x.append(car_centre[i] + pos[ws, 0])
            ws_car.append(i)
            p0.append(car.static_wheel_load)
    ws_x = np.asarray(ws_x)
    lead = ws_x[0]
    return TrainModel(params=train, mass=mass, stiffness=k_susp, damping=c_susp,
                      coupler_stiffness=k_coupler, gravity_force=gravity,
                      wheelset_dofs=np.asarray(ws_dofs, dtype=np.int64), wheelset_x=ws_x - lead,
                      wheelset_car=np.asarray(ws_car, dtype=np.int64), car_x=car_centre - lead,
                      static_wheel_load=np.asarray(p0))


def dof_labels(n_cars: int) -> list[str]:
    """Names of all DOFs, e.g. ``car1_ws2_yaw`` (cars and bodies numbered from 1 in names)."""
    return [f"car{c + 1}_{b}_{d}" for c in range(n_cars) for b in BODY_NAMES for d in DOF_NAMES]
