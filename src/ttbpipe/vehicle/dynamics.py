"""The train's equations of motion as a time loop evaluates them: rail kinematics in, wheel forces
and vehicle accelerations out.

M a = f_const + f_contact(q, v, rail) - K q - C v, with M diagonal (35 DOF per car,
:mod:`ttbpipe.vehicle.model`), K and C the suspension and coupler matrices (CSR), f_const the
gravity loads plus the coupler preload of the static state, and f_contact the wheel-rail contact
forces of every wheel (:func:`ttbpipe.vehicle.kernels.train_contact`). A loop hands over the rail
kinematics at every wheel, ``rail_kin[ws, side] = (z, dz/dt, y, dy/dt, theta, dtheta/dt)`` of the rail head
(structure plus irregularity), and gets back the accelerations and the wheel table
``wheel[ws, side] = (F_x, F_y, F_z, M_spin, N, y_rel, penetration, M_rail)`` (forces of the rail
on the wheel, track axes; M_rail: two-point contact's vertical forces' moment about the rail's
shear centre, ttbpipe.vehicle.kernels), whose negatives it applies to the rails.

:class:`VehicleArrays` groups what the kernel needs; :func:`vehicle_arrays` builds it from a
:class:`~ttbpipe.vehicle.model.TrainModel`.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .curving import curve_frame
from .contact import N_POINT_OUT, N_PTS_COLS
from ..jit import kernel
from .kernels import N_WHEEL_OUT, csr_matvec_sub, train_contact

#: The train for a time loop: diagonal inverse mass, suspension stiffness and damping (CSR
#: pointer, column, value), constant loads, the wheelsets' DOFs (ws, (y, z, roll, spin, yaw)) and
#: their x at t = 0, the contact geometry table, scalars and two-point zone tables
#: (ttbpipe.vehicle.contact; no zone: one point per wheel), and the curve terms (ttbpipe.vehicle.curving.CurveArrays; inactive on tangent track).
VehicleArrays = namedtuple("VehicleArrays", [
    "inv_mass", "k_ptr", "k_idx", "k_val", "c_ptr", "c_idx", "c_val", "f_const", "ws_dofs",
    "ws_x0", "table", "scal", "zones", "curve"])

#: Work arrays of :func:`vehicle_accelerations`: the generalised force, the wheel table, the
#: contact kernel's scratch rows, the semi-implicit lateral creep state per wheel, and the curve
#: terms' frames (pose, rate, loads per DOF; each wheelset's frame yaw rate) with the suspension's
#: effective displacements and velocities (q + q_track, v + v_track).
VehicleWork = namedtuple("VehicleWork", ["force", "wheel", "row", "tmp", "creep_state", "q_track",
                                         "v_track", "f_track", "ws_yaw_rate", "q_eff", "v_eff",
                                         "pts"])


@kernel
def _work(n_dof, n_ws, n_cols, n_pts):
    """Fresh :class:`VehicleWork` (numba: the time loops build theirs inside the kernel);
    ``n_pts``: contact points per wheel (1, or the number of two-point zones)."""
    return VehicleWork(np.zeros(n_dof), np.zeros((n_ws, 2, N_WHEEL_OUT)), np.zeros(n_cols),
                       np.zeros(N_POINT_OUT), np.zeros((n_ws, 2, n_pts)), np.zeros(n_dof),
                       np.zeros(n_dof), np.zeros(n_dof), np.zeros(n_ws), np.zeros(n_dof),
                       np.zeros(n_dof), np.zeros((n_pts, N_PTS_COLS)))


def vehicle_arrays(model, geom, f_const: np.ndarray, x_lead0: float,
                   curve=None) -> VehicleArrays:
    """:class:`VehicleArrays` of a train model, its contact geometry and constant loads, with
    the leading wheelset at ``x_lead0`` at t = 0, on the track layout's ``curve``
    (:class:`ttbpipe.vehicle.curving.CurveArrays`; None: tangent track)."""
    from .curving import no_curve

    k, c = model.stiffness, model.damping
    return VehicleArrays(
        1.0 / model.mass, k.indptr.astype(np.int64), k.indices.astype(np.int64), k.data,
        c.indptr.astype(np.int64), c.indices.astype(np.int64), c.data,
        np.asarray(f_const, dtype=float), model.wheelset_dofs,
        x_lead0 + np.asarray(model.wheelset_x, dtype=float), geom.table, geom.scalars(),
        geom.zone_array(), no_curve(model) if curve is None else curve)


def vehicle_work(vehicle: VehicleArrays) -> VehicleWork:
    """Fresh work arrays for :func:`vehicle_accelerations`."""
    from .contact import N_COLS

    return _work(vehicle.inv_mass.shape[0], vehicle.ws_dofs.shape[0], N_COLS,
                 max(vehicle.zones.shape[0], 1))


@kernel(creates_arrays=False)
def vehicle_accelerations(vehicle, work, q, v, rail_kin, speed, creep_relax, a, x_lead):
    """a = M^-1 (f_const + f_contact - K q - C v); ``work.wheel`` holds the wheel table.

    ``creep_relax`` = m_eff^-1 dt / V of the semi-implicit lateral creep (0: the explicit law),
    whose state ``work.creep_state`` is updated in place (ttbpipe.vehicle.contact). On a curve
    (``vehicle.curve`` active; the lead wheelset at chainage ``x_lead``) the track frames'
    loads are added and the suspension acts on q + q_track, v + v_track
    (ttbpipe.vehicle.curving).
    """
    f = work.force
    for i in range(f.shape[0]):
        f[i] = vehicle.f_const[i]
    q_s, v_s = q, v
    if vehicle.curve.scal[0] > 0.0:
        curve_frame(vehicle.curve, x_lead, speed, work.q_track, work.v_track, work.f_track,
                    work.ws_yaw_rate)
        for i in range(f.shape[0]):
            f[i] += work.f_track[i]
            work.q_eff[i] = q[i] + work.q_track[i]
            work.v_eff[i] = v[i] + work.v_track[i]
        q_s, v_s = work.q_eff, work.v_eff
    train_contact(q, v, vehicle.ws_dofs, (vehicle.table, vehicle.scal, vehicle.zones), speed,
                  rail_kin, f, work.wheel, (work.row, work.tmp, work.creep_state, work.pts),
                  creep_relax, work.ws_yaw_rate)
    csr_matvec_sub(vehicle.k_ptr, vehicle.k_idx, vehicle.k_val, q_s, f)
    csr_matvec_sub(vehicle.c_ptr, vehicle.c_idx, vehicle.c_val, v_s, f)
    for i in range(f.shape[0]):
        a[i] = f[i] * vehicle.inv_mass[i]
