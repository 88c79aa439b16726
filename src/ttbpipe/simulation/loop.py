"""The coupled train-track-bridge time loop: one numba kernel advancing train and structure.

At each step Zhai's explicit scheme (:func:`ttbpipe.timestepping.zhai.zhai_predict`, the same
dt for both) advances the vehicle and the structure; then the rail kinematics at every wheel
(the structure's rail heads, :mod:`ttbpipe.structure.rail_mesh`, plus the track irregularity,
:mod:`ttbpipe.irregularity.track_input`) go into the train's equations of motion
(:func:`ttbpipe.vehicle.dynamics.vehicle_accelerations`), whose wheel-rail forces go back onto
the rails (equal and opposite) for the structure's accelerations
(:func:`ttbpipe.structure.kernels.structure_accelerations`). The recorders take peaks at every
step and histories at output steps (:mod:`ttbpipe.simulation.recorder`,
:func:`ttbpipe.structure.monitors.record_monitors`). Seed paper sections 2.2.11, eqs. 28-31.

Stops (status): 0 ok, 1 non-finite state, 2 every wheel off the rail at one step, 3 vehicle
divergence (a displacement above 0.5 m; the wheelsets' spin angles are not displacements and are
not checked); :class:`SimulationStopped` words them with their likely
cause.
"""

from __future__ import annotations

import time
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..irregularity.track_input import irregularity_at
from ..structure.kernels import structure_accelerations
from ..structure.monitors import no_monitors, record_monitors
from ..structure.rail_mesh import add_rail_contact_load, add_rail_head_load, rail_point_kinematics
from ..timestepping.zhai import zhai_predict
from ..vehicle.dynamics import _work, vehicle_accelerations
from ..vehicle.contact import N_COLS
from ..vehicle.kernels import RAIL_KIN_COLS
from ..decimation import flush
from .recorder import (TrainRecorder, record_step_channels, record_vehicle_output,
                       record_wheel_output, record_wheel_step, train_recorder)

#: What each stop of the loop means; the cause and remedy come from ttbpipe.simulation.diagnosis
#: (the step is not always at fault).
STATUS_MESSAGES = {
    1: "non-finite state (numerical blow-up)",
    2: "every wheel lost contact with the rail at the same step",
    3: "vehicle displacement above 0.5 m (divergence)",
}

#: State of the coupled system: vehicle displacements, velocities, accelerations (this and the
#: previous step), the same for the structure, and the structure's external nodal loads.
CoupledState = namedtuple("CoupledState", ["q", "v", "a", "a_prev", "disp", "vel", "acc",
                                           "acc_prev", "nodal_force"])


@njit(cache=True)
def track_kinematics(mesh, track, disp, vel, ws_x, speed, rail_kin):
    """rail_kin[ws, side] = (z, dz/dt, y, dy/dt, theta, dtheta/dt) of the rail head under every
    wheel: the structure's (rail head moved by the roll theta) plus the irregularity of that
    rail (its time derivative is V times its slope); the roll only where ``rail_kin`` has its
    6 columns (ttbpipe.vehicle.kernels.RAIL_KIN_COLS)."""
    with_roll = rail_kin.shape[2] > 4
    h = mesh.head_height
    for w in range(ws_x.shape[0]):
        x = ws_x[w]
        for k in range(2):
            z, vz, y, vy, r, vr = rail_point_kinematics(mesh, k, x, disp, vel)
            zi, dzi = irregularity_at(track, k, x)
            yi, dyi = irregularity_at(track, 2 + k, x)
            rail_kin[w, k, 0] = z + zi
            rail_kin[w, k, 1] = vz + speed * dzi
            rail_kin[w, k, 2] = (y - h * r) + yi
            rail_kin[w, k, 3] = (vy - h * vr) + speed * dyi
            if with_roll:
                rail_kin[w, k, 4] = r
                rail_kin[w, k, 5] = vr


@njit(cache=True)
def _evaluate(t, state, vehicle, work, packed, mesh, track, speed, creep_relax, ws_x, rail_kin):
    """Accelerations of train and structure at time t for the current displacements and
    velocities (``work.wheel``: the wheel table of this evaluation)."""
    for w in range(ws_x.shape[0]):
        ws_x[w] = vehicle.ws_x0[w] + speed * t
    track_kinematics(mesh, track, state.disp, state.vel, ws_x, speed, rail_kin)
    vehicle_accelerations(vehicle, work, state.q, state.v, rail_kin, speed, creep_relax, state.a,
                          ws_x[0])
    nodal_force = state.nodal_force
    for i in range(nodal_force.shape[0]):
        nodal_force[i] = 0.0
    wheel = work.wheel
    two_point = vehicle.zones.shape[0] > 0
    for w in range(ws_x.shape[0]):
        for k in range(2):
            # the rail carries the opposite of the force of the rail on the wheel (with
            # two-point contact also the opposite of its vertical forces' moment about the
            # rail's shear centre: they act off the rail's axis)
            if two_point:
                add_rail_contact_load(mesh, k, ws_x[w], -wheel[w, k, 2], -wheel[w, k, 1],
                                      -wheel[w, k, 7], nodal_force)
            else:
                add_rail_head_load(mesh, k, ws_x[w], -wheel[w, k, 2], -wheel[w, k, 1],
                                   nodal_force)
    structure_accelerations(packed, state.disp, state.vel, nodal_force, state.acc)


@njit(cache=True)
def _coupled_loop(state, vehicle, packed, mesh, track, monitors, train, speed, dt, n_steps,
                  out_every, creep_relax):
    """Zhai explicit integration of train + structure; returns (status, step).

    Output every ``out_every`` steps (row 0 = t 0) into ``train`` (ttbpipe.simulation.recorder):
    sampled states, and the anti-alias decimated histories of the monitors, wheel forces and
    vehicle DOFs, fed at every step; peaks and contact loss at every step. ``creep_relax`` > 0: semi-implicit
    lateral creep (its state starts from the explicit law at t = 0).
    """
    n_ws = vehicle.ws_dofs.shape[0]
    ws_x = np.zeros(n_ws)
    rail_kin = np.zeros((n_ws, 2, RAIL_KIN_COLS))
    work = _work(state.q.shape[0], n_ws, N_COLS, max(vehicle.zones.shape[0], 1))
    q, v, a, a_prev = state.q, state.v, state.a, state.a_prev
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    _evaluate(0.0, state, vehicle, work, packed, mesh, track, speed, 0.0, ws_x, rail_kin)
    out_row = 0
    for n in range(-1, n_steps):
        if n >= 0:
            psi = 0.0 if n == 0 else 0.5
            zhai_predict(q, v, a, a_prev, dt, psi, psi)
            zhai_predict(disp, vel, acc, acc_prev, dt, psi, psi)
            for i in range(q.shape[0]):
                a_prev[i] = a[i]
            for i in range(disp.shape[0]):
                acc_prev[i] = acc[i]
            _evaluate((n + 1) * dt, state, vehicle, work, packed, mesh, track, speed,
                      creep_relax, ws_x, rail_kin)
        step = n + 1
        if record_wheel_step(train, work.wheel, step) == 0:
            return 2, n
        record_monitors(monitors, disp, vel, acc)
        record_step_channels(train, monitors.current, work.wheel, q, a)
        if step % out_every == 0:
            finite, big = record_vehicle_output(train, out_row, step * dt, q, a)
            if not finite:
                return 1, n
            for i in range(disp.shape[0]):
                if not np.isfinite(disp[i]):
                    return 1, n
            if big > 0.5:
                return 3, n
            record_wheel_output(train, out_row, work.wheel)
            out_row += 1
    flush(train.dec)
    return 0, n_steps


@dataclass
class RawResult:
    """Records of a run (before the table is built)."""

    train: TrainRecorder
    monitors: object           # ttbpipe.structure.monitors.MonitorRecorder
    wall_s: float
    final: CoupledState | None = None   # the state after the last step (a run continues from it)

    @property
    def time(self) -> np.ndarray:
        """Output times (s)."""
        return self.train.t_out

    @property
    def wheel(self) -> np.ndarray:
        """wheel[row, ws, side] = (F_x, F_y, F_z, y_rel, N) at the output steps."""
        return self.train.wheel_hist

    @property
    def q(self) -> np.ndarray:
        """Vehicle displacements at the output steps."""
        return self.train.q_hist

    @property
    def a(self) -> np.ndarray:
        """Vehicle accelerations at the output steps."""
        return self.train.a_hist

    @property
    def wheel_peak(self) -> np.ndarray:
        """wheel_peak[ws, side] = (max F_z, min F_z, max |F_y|, max Q/P in contact)."""
        return self.train.wheel_peak


class SimulationStopped(RuntimeError):
    """The loop stopped (status 1-3 of :data:`STATUS_MESSAGES`); the message names the likely
    cause (time step, irregularity, loss of contact) with its remedy
    (:func:`ttbpipe.simulation.diagnosis.explain`). Attributes: status, step, t_s, x_lead_m,
    cause, contact_loss (the loss-of-contact index up to the stop)."""

    def __init__(self, setup, status: int, step: int, contact_loss: np.ndarray, q: np.ndarray):
        from .diagnosis import contact_loss_stats, explain
        from .setup import diagnosis_limits, wheel_labels

        self.status, self.step = int(status), int(step)
        self.t_s = (step + 1) * setup.dt
        self.x_lead_m = setup.x_lead0 + setup.speed * self.t_s
        m = setup.model
        self.contact_loss = contact_loss_stats(contact_loss, setup.dt, setup.x_lead0 + m.wheelset_x,
                                               setup.speed, wheel_labels(m))
        self.cause, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info,
                                   self.contact_loss, setup.irregularity_config, setup.speed,
                                   propose_auto=setup.propose_auto)
        finite = q[np.isfinite(q)]
        big = f"; largest vehicle displacement {np.abs(finite).max():.3f} m" if finite.size else ""
        super().__init__(f"coupled simulation stopped at t = {self.t_s:.4f} s (leading wheelset at "
                         f"x = {self.x_lead_m:.1f} m): {STATUS_MESSAGES[status]}{big}; {text}")


def history_dofs(model) -> tuple[np.ndarray, np.ndarray]:
    """Vehicle DOFs whose anti-aliased histories a run keeps: the accelerations of every car
    body's vertical, lateral, pitch and yaw DOFs (car-body floor accelerations) and every
    wheelset's lateral displacement."""
    from ..vehicle.model import DOF_PER_CAR, PITCH, YAW, Y, Z

    acc = [DOF_PER_CAR * c + d for c in range(model.params.n_cars) for d in (Z, Y, PITCH, YAW)]
    return np.array(acc, dtype=np.int64), np.asarray(model.wheelset_dofs[:, 0], dtype=np.int64)


def integrate(setup) -> RawResult:
    """Run the loop for a prepared case (:func:`ttbpipe.simulation.setup.prepare`); raises
    :class:`SimulationStopped` with the likely cause when it stops."""
    m = setup.model
    n_v = m.n_dof
    n_out = setup.n_steps // setup.out_every + 1
    n_s = setup.disp0.shape[0]
    state = CoupledState(setup.q0.copy(), setup.v0.copy(), np.zeros(n_v), np.zeros(n_v),
                         setup.disp0.copy(), np.zeros(n_s), np.zeros(n_s), np.zeros(n_s),
                         np.zeros(n_s))
    monitors = setup.monitors.recorder() if setup.monitors is not None else no_monitors()
    train = train_recorder(n_out, m.n_wheelsets, n_v, monitors.qty.shape[0], setup.out_every,
                           *history_dofs(m), spin_dofs=m.wheelset_dofs[:, 3])
    t0 = time.perf_counter()
    status, step = _coupled_loop(state, setup.vehicle, setup.packed, setup.mesh,
                                 setup.irregularity, monitors, train, setup.speed, setup.dt,
                                 setup.n_steps, setup.out_every, setup.creep_relax)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SimulationStopped(setup, status, step, train.contact_loss, state.q)
    return RawResult(train, monitors, wall, state)
