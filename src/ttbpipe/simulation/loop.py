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

from ..irregularity.track_input import irregularity_at
from ..jit import kernel
from ..structure.kernels import structure_accelerations_in_place, windowed_accelerations_in_place
from ..structure.monitors import no_monitors, record_monitors
from ..structure.rail_mesh import add_rail_contact_load, add_rail_head_load, rail_point_kinematics
from ..structure.window import DOF_RANGES, clear_moving, no_window, track_window, update_window
from ..timestepping.zhai import zhai_predict, zhai_predict_ranges
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
#: previous step), the same for the structure. An evaluation clears the structure's ``acc``, adds
#: the wheel loads to it and the structure kernel turns them into accelerations in place.
CoupledState = namedtuple("CoupledState", ["q", "v", "a", "a_prev", "disp", "vel", "acc",
                                           "acc_prev"])


@kernel
def track_kinematics(mesh, track, disp, vel, ws_x, speed, rail_kin):
    """rail_kin[ws, side] = (z, dz/dt, y, dy/dt, theta, dtheta/dt) of the rail head under every
    wheel: the structure's (rail head moved by the roll theta) plus the irregularity of that
    rail (its time derivative is V times its slope); the roll only where ``rail_kin`` has its
    6 columns (ttbpipe.vehicle.kernels.RAIL_KIN_COLS). A train on rails 0, 1 running +x
    (:func:`placed_track_kinematics`)."""
    placed_track_kinematics(mesh, track, disp, vel, ws_x, speed, rail_kin, 0, 1)


@kernel(creates_arrays=False)
def placed_track_kinematics(mesh, track, disp, vel, ws_s, speed, rail_kin, rail0, direction):
    """:func:`track_kinematics` of a train on the track whose left rail is ``rail0`` (track k:
    rail 2k), running in ``direction`` +1 (+x) or -1 (-x), in the train's own axes.

    ``ws_s``: the wheelsets' positions along the train's direction of travel (x = direction s).
    A train running -x has its axes turned by 180 degrees about z (x' = -x, y' = -y, z' = z):
    its left wheel (side 0) runs on the track's right rail and its right wheel on the left
    one, lateral displacements and rolls change sign (y' = -y, theta' = -theta; y' - h theta'
    = -(y - h theta)), and a profile's time derivative at the wheel is -V times its slope.
    The irregularity ``track`` is that track's, in the structure's axes (channels z_left,
    z_right, y_left, y_right of its rails 2k, 2k + 1)."""
    with_roll = rail_kin.shape[2] > 4
    h = mesh.head_height
    for w in range(ws_s.shape[0]):
        if direction > 0:
            x = ws_s[w]
            for k in range(2):
                z, vz, y, vy, r, vr = rail_point_kinematics(mesh, rail0 + k, x, disp, vel)
                zi, dzi = irregularity_at(track, k, x)
                yi, dyi = irregularity_at(track, 2 + k, x)
                rail_kin[w, k, 0] = z + zi
                rail_kin[w, k, 1] = vz + speed * dzi
                rail_kin[w, k, 2] = (y - h * r) + yi
                rail_kin[w, k, 3] = (vy - h * vr) + speed * dyi
                if with_roll:
                    rail_kin[w, k, 4] = r
                    rail_kin[w, k, 5] = vr
        else:
            x = -ws_s[w]
            for k in range(2):
                g = 1 - k                 # the train's left wheel on the track's right rail
                z, vz, y, vy, r, vr = rail_point_kinematics(mesh, rail0 + g, x, disp, vel)
                zi, dzi = irregularity_at(track, g, x)
                yi, dyi = irregularity_at(track, 2 + g, x)
                rail_kin[w, k, 0] = z + zi
                rail_kin[w, k, 1] = vz - speed * dzi
                rail_kin[w, k, 2] = -((y - h * r) + yi)
                rail_kin[w, k, 3] = -((vy - h * vr) - speed * dyi)
                if with_roll:
                    rail_kin[w, k, 4] = -r
                    rail_kin[w, k, 5] = -vr


@kernel(creates_arrays=False)
def add_wheel_loads(mesh, wheel, ws_s, rail0, direction, two_point, nodal_force):
    """Add to ``nodal_force`` the loads of a train's wheels on its rails: the opposite of the
    force of the rail on each wheel (``wheel``: the contact table in the train's axes), with
    two-point contact also the opposite of its vertical forces' moment about the rail's shear
    centre (they act off the rail's axis). Placement as :func:`placed_track_kinematics`: a
    train running -x loads the track's right rail with its left wheel, and its lateral forces
    and moments change sign in the structure's axes."""
    for w in range(ws_s.shape[0]):
        if direction > 0:
            x = ws_s[w]
            for k in range(2):
                if two_point:
                    add_rail_contact_load(mesh, rail0 + k, x, -wheel[w, k, 2], -wheel[w, k, 1],
                                          -wheel[w, k, 7], nodal_force)
                else:
                    add_rail_head_load(mesh, rail0 + k, x, -wheel[w, k, 2], -wheel[w, k, 1],
                                       nodal_force)
        else:
            x = -ws_s[w]
            for k in range(2):
                if two_point:
                    add_rail_contact_load(mesh, rail0 + 1 - k, x, -wheel[w, k, 2],
                                          wheel[w, k, 1], wheel[w, k, 7], nodal_force)
                else:
                    add_rail_head_load(mesh, rail0 + 1 - k, x, -wheel[w, k, 2], wheel[w, k, 1],
                                       nodal_force)


#: A train as the loops run it: its arrays (ttbpipe.vehicle.dynamics.VehicleArrays,
#: wheelset positions ``ws_x0`` along its direction of travel), its track's irregularity, its
#: speed and semi-implicit creep factor, and where it runs: the left rail of its track (track k:
#: 2k) and its direction (+1: +x, -1: -x; :func:`placed_track_kinematics`).
PlacedTrain = namedtuple("PlacedTrain", ["vehicle", "track", "speed", "creep_relax", "rail0",
                                         "direction"])


@kernel(creates_arrays=False)
def _train_loads(t, state, placed, work, mesh, ws_s, rail_kin, creep_scale):
    """One train at time t: its rail kinematics, accelerations (``state.a``) and wheel table
    (``work.wheel``); adds its wheel loads to ``state.acc`` (the structure's loads, turned into
    accelerations in place by the structure kernel). ``creep_scale``: 0.0 at the evaluation at
    t = 0 (explicit creep law, as :func:`_coupled_loop`), 1.0 after it.

    A float rather than a bool: numba compiles a separate copy of every caller for each
    literal True and False (measured: the loop's first compilation took 11 s longer)."""
    vehicle = placed.vehicle
    for w in range(ws_s.shape[0]):
        ws_s[w] = vehicle.ws_x0[w] + placed.speed * t
    placed_track_kinematics(mesh, placed.track, state.disp, state.vel, ws_s, placed.speed,
                            rail_kin, placed.rail0, placed.direction)
    vehicle_accelerations(vehicle, work, state.q, state.v, rail_kin, placed.speed,
                          creep_scale * placed.creep_relax, state.a, ws_s[0])
    add_wheel_loads(mesh, work.wheel, ws_s, placed.rail0, placed.direction,
                    vehicle.zones.shape[0] > 0, state.acc)


@kernel(creates_arrays=False)
def _move_window(t, state, placed, window):
    """The track window (:mod:`ttbpipe.structure.window`) over the train's wheelsets at time t."""
    if window.n_segments == 0:
        return
    x_low = np.inf
    x_high = -np.inf
    for w in range(placed.vehicle.ws_x0.shape[0]):
        x = placed.direction * (placed.vehicle.ws_x0[w] + placed.speed * t)
        x_low = min(x_low, x)
        x_high = max(x_high, x)
    update_window(window, x_low, x_high, state.vel, state.acc, state.acc_prev)


@kernel(creates_arrays=False)
def _evaluate(t, state, placed, work, packed, window, mesh, ws_x, rail_kin, creep_scale):
    """Accelerations of train and structure at time t for the current displacements and
    velocities (``work.wheel``: the wheel table of this evaluation; :func:`_train_loads`), the
    track outside ``window`` frozen."""
    acc = state.acc
    clear_moving(window, acc)
    _move_window(t, state, placed, window)
    _train_loads(t, state, placed, work, mesh, ws_x, rail_kin, creep_scale)
    windowed_accelerations_in_place(packed, window, state.disp, state.vel, acc)


@kernel(creates_arrays=False)
def _advance(u, v, a, a_prev, dt, psi):
    """Zhai's predictor for one system (displacements and velocities at the new step from this
    and the previous step's accelerations; :func:`ttbpipe.timestepping.zhai.zhai_predict`),
    then this step's accelerations become the previous ones."""
    zhai_predict(u, v, a, a_prev, dt, psi, psi)


@kernel(creates_arrays=False)
def _advance_moving(window, u, v, a, a_prev, dt, psi):
    """:func:`_advance` for the structure's DOFs that move in ``window`` (the frozen ones keep
    zero velocity and accelerations, which the update would leave as they are). The whole
    track takes the plain update: through the ranges' one row the step measured 2 % longer."""
    if window.n_segments == 0:
        zhai_predict(u, v, a, a_prev, dt, psi, psi)
    else:
        zhai_predict_ranges(u, v, a, a_prev, dt, psi, psi, window.dof_ranges,
                            window.n_ranges[DOF_RANGES])


@kernel
def _coupled_loop(state, placed, packed, window, mesh, monitors, train, dt, n_steps, out_every):
    """Zhai explicit integration of train + structure; returns (status, step).

    ``window``: the approach track that moves (:mod:`ttbpipe.structure.window`; ``no_window``:
    all of it).

    ``placed``: the train, its track input, speed, creep factor and placement
    (:data:`PlacedTrain`). Output every ``out_every`` steps (row 0 = t 0) into ``train``
    (ttbpipe.simulation.recorder): sampled states, and the anti-alias decimated histories of the
    monitors, wheel forces and vehicle DOFs, fed at every step; peaks and contact loss at every
    step. ``placed.creep_relax`` > 0: semi-implicit lateral creep (its state starts from the
    explicit law at t = 0).
    """
    vehicle = placed.vehicle
    n_ws = vehicle.ws_dofs.shape[0]
    ws_x = np.zeros(n_ws)
    rail_kin = np.zeros((n_ws, 2, RAIL_KIN_COLS))
    work = _work(state.q.shape[0], n_ws, N_COLS, max(vehicle.zones.shape[0], 1))
    q, v, a, a_prev = state.q, state.v, state.a, state.a_prev
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    _evaluate(0.0, state, placed, work, packed, window, mesh, ws_x, rail_kin, 0.0)
    out_row = np.int64(0)   # not a literal 0: numba would compile the recorders for it too
    for n in range(-1, n_steps):
        if n >= 0:
            psi = 0.0 if n == 0 else 0.5
            _advance(q, v, a, a_prev, dt, psi)
            _advance_moving(window, disp, vel, acc, acc_prev, dt, psi)
            _evaluate((n + 1) * dt, state, placed, work, packed, window, mesh, ws_x, rail_kin,
                      1.0)
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


@kernel(creates_arrays=False)
def _evaluate_pair(t, state, state_b, placed, placed_b, work, work_b, packed, mesh, scratch,
                   creep_scale):
    """Accelerations of two trains and the structure at time t (``state_b`` shares the
    structure's arrays with ``state``); ``scratch`` = (ws_s, rail_kin) of each train."""
    acc = state.acc
    for i in range(acc.shape[0]):
        acc[i] = 0.0
    ws_s, rail_kin, ws_s_b, rail_kin_b = scratch
    _train_loads(t, state, placed, work, mesh, ws_s, rail_kin, creep_scale)
    _train_loads(t, state_b, placed_b, work_b, mesh, ws_s_b, rail_kin_b, creep_scale)
    structure_accelerations_in_place(packed, state.disp, state.vel, acc)


@kernel
def _coupled_loop_pair(state, state_b, placed, placed_b, packed, mesh, monitors, recorders,
                       dt, n_steps, out_every):
    """:func:`_coupled_loop` with two trains on the structure (the two blocks of one
    block-diagonal vehicle system, each with its own speed, track and direction; Zhai's
    scheme on each train's and the structure's states at the same dt). ``recorders``: the two
    trains' recorders (the first also takes the monitors' decimated histories). Returns
    (status, step, which train stopped it: 0, 1, or -1 for the structure)."""
    train, train_b = recorders
    n_ws = placed.vehicle.ws_dofs.shape[0]
    n_ws_b = placed_b.vehicle.ws_dofs.shape[0]
    scratch = (np.zeros(n_ws), np.zeros((n_ws, 2, RAIL_KIN_COLS)), np.zeros(n_ws_b),
               np.zeros((n_ws_b, 2, RAIL_KIN_COLS)))
    work = _work(state.q.shape[0], n_ws, N_COLS, max(placed.vehicle.zones.shape[0], 1))
    work_b = _work(state_b.q.shape[0], n_ws_b, N_COLS, max(placed_b.vehicle.zones.shape[0], 1))
    no_values = np.zeros(0)
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    _evaluate_pair(0.0, state, state_b, placed, placed_b, work, work_b, packed, mesh, scratch,
                   0.0)
    out_row = np.int64(0)   # not a literal 0: numba would compile the recorders for it too
    for n in range(-1, n_steps):
        if n >= 0:
            psi = 0.0 if n == 0 else 0.5
            for st in (state, state_b):
                _advance(st.q, st.v, st.a, st.a_prev, dt, psi)
            _advance(disp, vel, acc, acc_prev, dt, psi)
            _evaluate_pair((n + 1) * dt, state, state_b, placed, placed_b, work, work_b, packed,
                           mesh, scratch, 1.0)
        step = n + 1
        if record_wheel_step(train, work.wheel, step) == 0:
            return 2, n, 0
        if record_wheel_step(train_b, work_b.wheel, step) == 0:
            return 2, n, 1
        record_monitors(monitors, disp, vel, acc)
        record_step_channels(train, monitors.current, work.wheel, state.q, state.a)
        record_step_channels(train_b, no_values, work_b.wheel, state_b.q, state_b.a)
        if step % out_every == 0:
            finite, big = record_vehicle_output(train, out_row, step * dt, state.q, state.a)
            finite_b, big_b = record_vehicle_output(train_b, out_row, step * dt, state_b.q,
                                                    state_b.a)
            if not finite:
                return 1, n, 0
            if not finite_b:
                return 1, n, 1
            for i in range(disp.shape[0]):
                if not np.isfinite(disp[i]):
                    return 1, n, -1
            if big > 0.5:
                return 3, n, 0
            if big_b > 0.5:
                return 3, n, 1
            record_wheel_output(train, out_row, work.wheel)
            record_wheel_output(train_b, out_row, work_b.wheel)
            out_row += 1
    flush(train.dec)
    flush(train_b.dec)
    return 0, n_steps, -1


@dataclass
class RawResult:
    """Records of a run (before the table is built); ``second``: the second train's records
    in a two-train run (its ``final`` state in ``final_second``)."""

    train: TrainRecorder
    monitors: object           # ttbpipe.structure.monitors.MonitorRecorder
    wall_s: float
    final: CoupledState | None = None   # the state after the last step (a run continues from it)
    second: TrainRecorder | None = None
    final_second: CoupledState | None = None

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
        self.x_lead_m = setup.x_lead0 + setup.velocity * self.t_s
        m = setup.model
        self.contact_loss = contact_loss_stats(contact_loss, setup.dt, setup.wheelset_x0,
                                               setup.velocity, wheel_labels(m))
        self.cause, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info,
                                   self.contact_loss, setup.irregularity_config, setup.speed,
                                   propose_auto=setup.propose_auto)
        finite = q[np.isfinite(q)]
        big = f"; largest vehicle displacement {np.abs(finite).max():.3f} m" if finite.size else ""
        which = f"{setup.label.rstrip('_')}: " if setup.label else ""
        super().__init__(f"{which}coupled simulation stopped at t = {self.t_s:.4f} s (leading wheelset at "
                         f"x = {self.x_lead_m:.1f} m): {STATUS_MESSAGES[status]}{big}; {text}")


def history_dofs(model) -> tuple[np.ndarray, np.ndarray]:
    """Vehicle DOFs whose anti-aliased histories a run keeps: the accelerations of every car
    body's vertical, lateral, pitch and yaw DOFs (car-body floor accelerations) and every
    wheelset's lateral displacement."""
    from ..vehicle.model import DOF_PER_CAR, PITCH, YAW, Y, Z

    acc = [DOF_PER_CAR * c + d for c in range(model.params.n_cars) for d in (Z, Y, PITCH, YAW)]
    return np.array(acc, dtype=np.int64), np.asarray(model.wheelset_dofs[:, 0], dtype=np.int64)


def _recorder(setup, n_monitors: int) -> TrainRecorder:
    m = setup.model
    return train_recorder(setup.n_steps // setup.out_every + 1, m.n_wheelsets, m.n_dof,
                          n_monitors, setup.out_every, *history_dofs(m),
                          spin_dofs=m.wheelset_dofs[:, 3])


def _placed(setup) -> PlacedTrain:
    return PlacedTrain(setup.vehicle, setup.irregularity, float(setup.speed),
                       float(setup.creep_relax), 2 * int(setup.track_index),
                       int(setup.direction))


def _window(setup, monitors):
    """A fresh track window of a run (``simulation.track_window_m``; its monitored DOFs always
    move), or none."""
    if setup.structure is None or setup.track_window_m is None:
        return no_window(setup.packed)
    return track_window(setup.structure, setup.track_window_m, keep_dofs=monitors.dof)


def _integrate_pair(setup) -> RawResult:
    """:func:`integrate` of a two-train run (``setup.second``)."""
    second = setup.second
    n_s = setup.disp0.shape[0]
    structure = (setup.disp0.copy(), np.zeros(n_s), np.zeros(n_s), np.zeros(n_s))
    states = []
    for s in (setup, second):
        n_v = s.model.n_dof
        states.append(CoupledState(s.q0.copy(), s.v0.copy(), np.zeros(n_v), np.zeros(n_v),
                                   *structure))
    monitors = setup.monitors.recorder()
    recorders = (_recorder(setup, monitors.qty.shape[0]), _recorder(second, 0))
    t0 = time.perf_counter()
    status, step, which = _coupled_loop_pair(states[0], states[1], _placed(setup),
                                             _placed(second), setup.packed, setup.mesh,
                                             monitors, recorders, setup.dt, setup.n_steps,
                                             setup.out_every)
    wall = time.perf_counter() - t0
    if status != 0:
        culprit = second if which == 1 else setup
        raise SimulationStopped(culprit, status, step, recorders[max(which, 0)].contact_loss,
                                states[max(which, 0)].q)
    return RawResult(recorders[0], monitors, wall, states[0], recorders[1], states[1])


def integrate(setup) -> RawResult:
    """Run the loop for a prepared case (:func:`ttbpipe.simulation.setup.prepare`); raises
    :class:`SimulationStopped` with the likely cause when it stops. A case with a second
    train (``setup.second``) runs both in one loop (:func:`_coupled_loop_pair`)."""
    if getattr(setup, "second", None) is not None:
        return _integrate_pair(setup)
    n_v = setup.model.n_dof
    n_s = setup.disp0.shape[0]
    state = CoupledState(setup.q0.copy(), setup.v0.copy(), np.zeros(n_v), np.zeros(n_v),
                         setup.disp0.copy(), np.zeros(n_s), np.zeros(n_s), np.zeros(n_s))
    monitors = setup.monitors.recorder() if setup.monitors is not None else no_monitors()
    train = _recorder(setup, monitors.qty.shape[0])
    t0 = time.perf_counter()
    status, step = _coupled_loop(state, _placed(setup), setup.packed, _window(setup, monitors),
                                 setup.mesh, monitors, train, setup.dt, setup.n_steps,
                                 setup.out_every)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SimulationStopped(setup, status, step, train.contact_loss, state.q)
    return RawResult(train, monitors, wall, state)
