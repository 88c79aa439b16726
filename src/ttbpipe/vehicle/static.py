"""Static (gravity-loaded) equilibrium of the train, on a rigid track or coupled to the structure.

Vehicle: Newton iterations on R(q) = f_gravity + f_contact(q) - K q = 0, with the exact nonlinear
contact law of the time loop (Hertz normal force, creep forces at zero velocities, flange) and a
finite-difference contact Jacobian (the contact force of a wheelset depends only on that
wheelset's DOFs, so 5 evaluations give the whole block-diagonal Jacobian). Wheelset spin angles
have no stiffness (held at 0); their steady spin RATES are solved instead (zero creep moment
about each axle: steady rolling). Couplers are excluded (they are made stress-free in
the static state: the time loop adds the constant preload K_coupler q_static, which is the
equivalent of adjusting the coupler heads to the static car heights).

The structure's static solve is :class:`ttbpipe.structure.static.StructureStatic`; the
train-structure fixed point between the two is the coupled set-up's
(:func:`ttbpipe.simulation.setup.static_equilibrium`).
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .kernels import RAIL_KIN_COLS, contact_forces
from .model import (BODIES_PER_CAR, CAR_BODY, DOF_PER_BODY, FRONT_BOGIE, PITCH, ROLL, Z,
                    TrainModel)

log = logging.getLogger(__name__)


def rail_following_guess(model: TrainModel, geom, rail_kin: np.ndarray) -> np.ndarray:
    """Start point of the static Newton solve: every body placed rigidly on its own rails.

    Each wheelset sits on the rail heights under it (z: mean of its two rails minus the Hertz
    static approach g P0^(2/3); roll: left-right difference over the contact spacing 2 a), each
    bogie frame on the straight line through its two wheelsets, each car body on the line
    through its two bogies (z and pitch at the body's x; ``ttbpipe.vehicle.model.point_row``:
    z_point = z + roll ry - pitch rx). Lateral DOFs start at 0.

    Why: the Hertz static approach is only ~0.09 mm at 70 kN, so a start that puts a whole car at
    its mean rail height leaves every wheel above that mean out of contact when the rail heights
    under the car differ by more than ~0.2 mm (a car straddling the junction of a slab approach,
    0.6-0.7 mm rail deflection, and the bridge, 1.1 mm). A wheelset without contact has no
    vertical support; its bogie becomes a mechanism and the Newton Jacobian is singular. From
    this start the residual is only the suspension forces of the rail-height differences within
    a bogie (k_primary x a few 0.1 mm, far below the wheel load), well inside the contact range.
    """
    q = np.zeros(model.n_dof)
    a = float(geom.contact_half_distance)
    z_rails = np.asarray(rail_kin, dtype=float)[:, :, 0]                 # (n_ws, 2) left, right
    approach = geom.hertz_g * np.asarray(model.static_wheel_load, float) ** (2.0 / 3.0)
    ws_z = z_rails.mean(axis=1) - approach
    ws_roll = (z_rails[:, 0] - z_rails[:, 1]) / (2.0 * a)
    ws_x = np.asarray(model.wheelset_x, dtype=float)
    dof0 = model.wheelset_dofs[:, 0]                 # first DOF (y) of each wheelset body
    q[dof0 + Z] = ws_z
    q[dof0 + ROLL] = ws_roll

    def line(x_a, z_a, x_b, z_b, x):
        """z and pitch at x of the straight line through (x_a, z_a), (x_b, z_b)."""
        slope = (z_a - z_b) / (x_a - x_b)
        return z_b + slope * (x - x_b), -slope   # pitch = -dz/dx (z_point = z - pitch rx)

    for c in range(model.params.n_cars):
        ws = np.flatnonzero(model.wheelset_car == c)
        if ws.size != 4:   # pragma: no cover - the model has 4 wheelsets per car
            raise ValueError(f"car {c}: expected 4 wheelsets, got {ws.size}")
        base = DOF_PER_BODY * BODIES_PER_CAR * c
        bogie_x, bogie_z = [], []
        for b, (front, rear) in enumerate(((ws[0], ws[1]), (ws[2], ws[3]))):
            xb = 0.5 * (ws_x[front] + ws_x[rear])
            zb, pitch = line(ws_x[front], ws_z[front], ws_x[rear], ws_z[rear], xb)
            o = base + DOF_PER_BODY * (FRONT_BOGIE + b)
            q[o + Z], q[o + PITCH] = zb, pitch
            q[o + ROLL] = 0.5 * (ws_roll[front] + ws_roll[rear])
            bogie_x.append(xb); bogie_z.append(zb)
        xc = 0.5 * (bogie_x[0] + bogie_x[1])
        zc, pitch = line(bogie_x[0], bogie_z[0], bogie_x[1], bogie_z[1], xc)
        o = base + DOF_PER_BODY * CAR_BODY
        q[o + Z], q[o + PITCH] = zc, pitch
        q[o + ROLL] = ws_roll[ws].mean()
    return q


def solve_vehicle_static(model: TrainModel, geom, speed: float, rail_kin: np.ndarray | None = None,
                         tol_disp: float = 1e-11, max_iter: int = 60, curve=None,
                         x_lead: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Static (steady rolling) state: vehicle DOFs q (m, rad), velocities v and the wheel table.

    ``rail_kin`` (n_ws, 2, 4 or 6): rail-head z, dz/dt, y, dy/dt (and the rail's roll and its
    rate) at each wheel (zeros: perfect rigid track). The unknowns are all DOFs except the wheelset spins, whose place is taken by the
    steady spin-rate perturbations (v at the spin DOFs): steady rolling needs the longitudinal
    creep moment about each axle to vanish (with rails deflected under load the rolling radii
    change slightly). All other velocities are 0. Raises RuntimeError naming the remedy when
    Newton does not converge.

    ``curve`` (ttbpipe.vehicle.curving.CurveArrays, active) with the lead wheelset at chainage
    ``x_lead``: the steady state on the curve there, with the track frames' loads and the
    suspension on q + q_track as in the time loop (a run that starts on a curve starts in
    equilibrium).
    """
    n = model.n_dof
    n_ws = model.n_wheelsets
    if rail_kin is None:
        rail_kin = np.zeros((n_ws, 2, RAIL_KIN_COLS))
    k_susp = model.suspension_stiffness
    spin = np.zeros(n, dtype=bool)
    spin[model.wheelset_dofs[:, PITCH]] = True
    q = rail_following_guess(model, geom, rail_kin)
    v = np.zeros(n)
    f_g = model.gravity_force
    yaw_rate = None
    if curve is not None and curve.scal[0] > 0.0:
        max_iter = max(max_iter, 200)
        from .curving import curve_frame

        q_track, v_track, f_track = np.zeros(n), np.zeros(n), np.zeros(n)
        yaw_rate = np.zeros(n_ws)
        curve_frame(curve, float(x_lead), float(speed), q_track, v_track, f_track, yaw_rate)
        f_g = f_g + f_track - k_susp @ q_track - model.damping @ v_track
    eps_q, eps_v = 1e-7, 1e-5
    step = np.full(n, np.inf)
    for it in range(max_iter):
        f_c, wheel = contact_forces(q, v, model.wheelset_dofs, geom, speed, rail_kin, yaw_rate)
        resid = f_g + f_c - k_susp @ q
        # block-diagonal contact Jacobian by finite differences, one wheelset DOF kind at a time
        # (the spin column is the derivative with respect to the spin RATE)
        # entry (d_j, d_k) of wheelset w for DOF kinds k, w, j in that order
        dofs = model.wheelset_dofs
        rows, cols, vals = [], [], []
        for k in range(5):
            dq = np.zeros(n)
            dv = np.zeros(n)
            eps = eps_v if k == PITCH else eps_q
            (dv if k == PITCH else dq)[dofs[:, k]] = eps
            f_p, _ = contact_forces(q + dq, v + dv, dofs, geom, speed, rail_kin, yaw_rate)
            f_m, _ = contact_forces(q - dq, v - dv, dofs, geom, speed, rail_kin, yaw_rate)
            df = (f_p - f_m) / (2 * eps)
            rows.append(dofs.ravel()); cols.append(np.repeat(dofs[:, k], 5))
            vals.append(df[dofs].ravel())
        jac_c = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                              shape=(n, n)).tocsr()
        jac = (k_susp - jac_c).tocsc()
        step = spla.spsolve(jac, resid)
        if not np.all(np.isfinite(step)):
            raise RuntimeError("static equilibrium: singular Jacobian (a wheel without contact or "
                               "an unsupported body); check the suspension parameters and wheel loads")
        if yaw_rate is not None:
            # on a curve the lateral equilibrium rests on creep forces that saturate: Newton
            # steps are limited to 1 mm / 1 mrad laterally and in yaw (more iterations, no
            # overshoot into the flange)
            largest = max(np.max(np.abs(step[0::DOF_PER_BODY])), np.max(np.abs(step[4::DOF_PER_BODY])))
            if largest > 1e-3:
                step = step * (1e-3 / largest)
        q[~spin] += step[~spin]
        v[spin] += step[spin]
        if np.max(np.abs(step[~spin])) < tol_disp and np.max(np.abs(step[spin])) < 1e-9:
            f_c, wheel = contact_forces(q, v, model.wheelset_dofs, geom, speed, rail_kin, yaw_rate)
            log.debug("vehicle static equilibrium in %d Newton iterations", it + 1)
            return q, wheel, v
    raise RuntimeError(f"static equilibrium: Newton did not converge in {max_iter} iterations "
                       f"(last step {np.max(np.abs(step)):.3g}); check the contact parameters "
                       "(Hertz G, wheel loads) or raise max_iter")
