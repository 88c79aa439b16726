"""Numba kernels of the train's contact forces, shared by the static solver and the time loop.

Layout conventions: see :mod:`ttbpipe.vehicle.model` (DOFs) and :mod:`ttbpipe.vehicle.contact`
(geometry table, contact kinematics). Rail kinematics per wheel are packed as
``rail_kin[ws, side, 0:6] = (z, dz/dt, y, dy/dt, theta, dtheta/dt)`` of the rail head at the
contact (structure plus irregularity; theta the rail's roll, used by the two-point contact; an
array of 4 columns means no roll), side 0 = left rail (+y), 1 = right rail. Per-wheel results are
``wheel[ws, side, 0:8] = (F_x, F_y, F_z, M_spin, N, y_rel, penetration, M_rail)`` (force of the
rail on the wheel, track axes; M_rail the moment of the wheel's vertical forces about the rail's
shear-centre line, two-point contact only, 0 otherwise).
"""

from __future__ import annotations

import numpy as np

from .contact import N_COLS, N_POINT_OUT, N_PTS_COLS, _wheel_contact, _wheel_contact_points
from ..jit import kernel

N_WHEEL_OUT = 8
#: Columns of ``rail_kin`` per wheel (ttbpipe.simulation.loop.track_kinematics).
RAIL_KIN_COLS = 6


@kernel(creates_arrays=False)
def csr_matvec_sub(indptr, indices, data, x, out):
    """out -= A x for a CSR matrix A.

    The indices are taken unsigned: numba then drops its negative-index wrap-around test on
    every access made with them (as in the structure's element loops)."""
    for i in range(indptr.shape[0] - 1):
        s = 0.0
        for j in range(np.uint64(indptr[i]), np.uint64(indptr[i + 1])):
            s += data[j] * x[np.uint64(indices[j])]
        out[i] -= s


@kernel
def _train_contact(q, v, ws_dofs, table, scal, zones, speed, rail_kin, force, wheel, row, tmp,
                   frame_yaw_rate):
    """Add the contact generalised forces of every wheel to ``force`` and fill ``wheel``
    (explicit creep law; see :func:`train_contact`)."""
    n_pts = max(zones.shape[0], 1)
    creep_state = np.zeros((ws_dofs.shape[0], 2, n_pts))
    train_contact(q, v, ws_dofs, (table, scal, zones), speed, rail_kin, force, wheel,
                  (row, tmp, creep_state, np.zeros((n_pts, N_PTS_COLS))), 0.0, frame_yaw_rate)


@kernel(creates_arrays=False)
def train_contact(q, v, ws_dofs, geometry, speed, rail_kin, force, wheel, scratch, creep_relax,
                  frame_yaw_rate):
    """Add the contact generalised forces of every wheel to ``force`` and fill ``wheel``.

    ``geometry`` = (table, scalars, zones) of the contact (ttbpipe.vehicle.contact; ``zones``
    with no zone: one point per wheel, :func:`ttbpipe.vehicle.contact._wheel_contact`; else
    the two-point contact of :func:`ttbpipe.vehicle.contact._wheel_contact_points`);
    ``scratch`` = (row, tmp, creep_state, pts): a geometry-table row, the wheel's output row
    (:data:`ttbpipe.vehicle.contact.N_POINT_OUT`), ``creep_state[ws, side, point]``, the
    semi-implicit lateral creepage of the previous step, updated in place, and the two-point
    kernel's scratch; ``creep_relax`` = m_eff^-1 dt / V (0: explicit law). ``frame_yaw_rate[ws]``: the yaw rate of
    the wheelset's track frame, V kappa on a curve (ttbpipe.vehicle.curving), added to the
    wheelset's own yaw rate in the longitudinal and spin creepages.

    A contact at (0, s a0, -r) from the wheelset centre with force (F_x, F_y, F_z) and spin moment
    M about the normal gives: y += F_y, z += F_z, roll += s a0 F_z + r F_y, pitch (spin)
    += -r F_x, yaw += -s a0 F_x + M cos(delta) (r x F, small angles; the contact kernels
    return these moments). The rolling radius r and contact angle come from the geometry table
    at the wheel's relative lateral position; with two-point contact each point acts at its own
    (0, s a_k, -r_k).
    """
    table, scal, zones = geometry
    row, tmp, creep_state, pts = scratch
    n_ws = ws_dofs.shape[0]
    two_point = zones.shape[0] > 0
    with_roll = rail_kin.shape[2] > 4
    for w in range(n_ws):
        iy = ws_dofs[w, 0]
        iz = ws_dofs[w, 1]
        ir = ws_dofs[w, 2]
        ip = ws_dofs[w, 3]
        iw = ws_dofs[w, 4]
        for k in range(2):
            side = 1.0 if k == 0 else -1.0
            if two_point:
                roll = rail_kin[w, k, 4] if with_roll else 0.0
                vroll = rail_kin[w, k, 5] if with_roll else 0.0
                _wheel_contact_points(
                    side, zones, scal, speed,
                    (q[iy], q[iz], q[ir], q[iw], v[iy], v[iz], v[ir], v[ip],
                     v[iw] + frame_yaw_rate[w]),
                    (rail_kin[w, k, 0], rail_kin[w, k, 2], rail_kin[w, k, 1], rail_kin[w, k, 3],
                     roll, vroll),
                    pts, tmp, creep_state[w, k], creep_relax)
            else:
                creep_state[w, k, 0] = _wheel_contact(
                    side, table, scal, speed,
                    (q[iy], q[iz], q[ir], q[iw], v[iy], v[iz], v[ir], v[ip],
                     v[iw] + frame_yaw_rate[w]),
                    (rail_kin[w, k, 0], rail_kin[w, k, 2], rail_kin[w, k, 1], rail_kin[w, k, 3]),
                    row, tmp, creep_state[w, k, 0], creep_relax)
            # both kernels give the forces and the generalised moments (N_POINT_OUT)
            force[iy] += tmp[1]
            force[iz] += tmp[2]
            force[ir] += tmp[7]
            force[ip] += tmp[8]
            force[iw] += tmp[9]
            for c in range(7):
                wheel[w, k, c] = tmp[c]
            wheel[w, k, 7] = tmp[10]


def contact_forces(q, v, ws_dofs, geom, speed, rail_kin, frame_yaw_rate=None):
    """Python wrapper: (generalised force vector, wheel table) for the whole train;
    ``frame_yaw_rate[ws]``: the track frames' yaw rates on a curve (None: tangent track)."""
    force = np.zeros(q.size)
    wheel = np.zeros((ws_dofs.shape[0], 2, N_WHEEL_OUT))
    if frame_yaw_rate is None:
        frame_yaw_rate = np.zeros(ws_dofs.shape[0])
    _train_contact(q, v, ws_dofs, geom.table, geom.scalars(), geom.zone_array(), float(speed),
                   rail_kin, force, wheel, np.zeros(N_COLS), np.zeros(N_POINT_OUT),
                   np.asarray(frame_yaw_rate, dtype=float))
    return force, wheel
