"""What the coupled loop records of the train: peaks and contact loss at every step, histories at
output steps.

The structure's monitors are recorded by the recorder the structure's own loops use
(:func:`ttbpipe.structure.monitors.record_monitors`); this module adds the train:

* at every step: per wheel the largest and smallest vertical force F_z, the largest |F_y|, the
  largest Q/P = |F_y|/F_z over the steps in contact (Q/P is defined in contact only), per
  wheelset the largest |F_y,left + F_y,right| (H), and the loss of wheel-rail contact (normal
  force N = 0): events, steps without contact, the longest event and where it started;
* at every step, into an anti-alias decimator (:mod:`ttbpipe.decimation`) with the structure's
  monitors: the wheel forces (F_x, F_y, F_z) and the vehicle accelerations and displacements the
  results need (car bodies, wheelsets), so their histories are valid to the output Nyquist
  frequency;
* at output steps, sampled as they are: the wheel table (F_x, F_y, F_z, y_rel, N; N tells the
  contact state) and the vehicle's displacements and accelerations (the raw states).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..decimation import push
from ..jit import kernel

#: Train records of a run with ``n_out`` output rows (see :func:`train_recorder`):
#: t_out[row]; wheel_hist[row, ws, side] = (F_x, F_y, F_z, y_rel, N) sampled; q_hist, a_hist[row,
#: dof] sampled; wheel_peak[ws, side] = (max F_z, min F_z, max |F_y|, max Q/P in contact);
#: h_peak[ws]; contact_loss[ws, side] = (events, steps without contact, longest event, its first
#: step, first step of the event under way or -1, first step of the first event or -1), in steps
#: (step s is the state at t = s dt, so an event of k steps lasts k dt); the channels decimated
#: with an anti-alias filter: the monitors, then F_x, F_y, F_z of every wheel, then the
#: accelerations of ``acc_dofs`` and the displacements of ``disp_dofs`` (``values``: the current
#: step's, ``dec``: the decimator and its output rows).
#: ``displacement_dofs``: 1 for the vehicle DOFs whose size the loop's divergence check watches,
#: 0 for the wheelsets' spin angles (their "pitch" DOF: a rotation on top of the rolling, on
#: which no force depends and which drifts whenever the mean rolling radius differs from r0,
#: e.g. on a hunting limit cycle or in a curve).
TrainRecorder = namedtuple("TrainRecorder", ["t_out", "wheel_hist", "q_hist", "a_hist",
                                             "wheel_peak", "h_peak", "contact_loss", "acc_dofs",
                                             "disp_dofs", "values", "dec", "displacement_dofs"])

#: Columns of wheel_hist.
WHEEL_HISTORY_COLUMNS = ("F_x", "F_y", "F_z", "y_rel", "N")
#: Decimated wheel-force channels per wheel (indices into the wheel table).
WHEEL_FORCE_CHANNELS = (0, 1, 2)


def train_recorder(n_out: int, n_wheelsets: int, n_dof: int, n_monitors: int, out_every: int,
                   acc_dofs: np.ndarray, disp_dofs: np.ndarray,
                   spin_dofs: np.ndarray | None = None) -> TrainRecorder:
    """Empty records (peaks at their neutral values, no contact loss); ``spin_dofs``: the
    wheelsets' spin-angle DOFs, left out of the divergence check."""
    from ..decimation import decimator

    wheel_peak = np.zeros((n_wheelsets, 2, 4))
    wheel_peak[:, :, 1] = np.inf
    contact_loss = np.zeros((n_wheelsets, 2, 6), dtype=np.int64)
    contact_loss[:, :, 3:] = -1
    acc_dofs = np.asarray(acc_dofs, dtype=np.int64)
    disp_dofs = np.asarray(disp_dofs, dtype=np.int64)
    n_channels = (n_monitors + 2 * n_wheelsets * len(WHEEL_FORCE_CHANNELS) + acc_dofs.size
                  + disp_dofs.size)
    displacement_dofs = np.ones(n_dof, dtype=np.int64)
    if spin_dofs is not None:
        displacement_dofs[np.asarray(spin_dofs, dtype=np.int64)] = 0
    return TrainRecorder(np.zeros(n_out), np.zeros((n_out, n_wheelsets, 2, 5)),
                         np.zeros((n_out, n_dof)), np.zeros((n_out, n_dof)), wheel_peak,
                         np.zeros(n_wheelsets), contact_loss, acc_dofs, disp_dofs,
                         np.zeros(n_channels), decimator(n_channels, n_out, out_every),
                         displacement_dofs)


def decimated(rec: TrainRecorder, n_monitors: int) -> dict[str, np.ndarray]:
    """The anti-aliased histories of a run: {"monitors": (n_out, n_monitors), "wheel":
    (n_out, n_ws, 2, 3) F_x, F_y, F_z, "acc": (n_out, len(acc_dofs)), "disp": ...}."""
    out = rec.dec.out
    n_ws = rec.wheel_peak.shape[0]
    a = n_monitors
    b = a + 2 * n_ws * len(WHEEL_FORCE_CHANNELS)
    c = b + rec.acc_dofs.size
    return {"monitors": out[:, :a], "wheel": out[:, a:b].reshape(out.shape[0], n_ws, 2, -1),
            "acc": out[:, b:c], "disp": out[:, c:]}


@kernel(creates_arrays=False)
def record_step_channels(rec, monitor_values, wheel, q, a):
    """Push this step's decimated channels (monitors, wheel forces, vehicle DOFs)."""
    values = rec.values
    i = 0
    for m in range(monitor_values.shape[0]):
        values[i] = monitor_values[m]
        i += 1
    for w in range(wheel.shape[0]):
        for k in range(2):
            for c in range(3):
                values[i] = wheel[w, k, c]
                i += 1
    for j in range(rec.acc_dofs.shape[0]):
        values[i] = a[rec.acc_dofs[j]]
        i += 1
    for j in range(rec.disp_dofs.shape[0]):
        values[i] = q[rec.disp_dofs[j]]
        i += 1
    push(rec.dec, values)


@kernel
def derailment_coefficient(lateral_force, vertical_force, in_contact):
    """Q/P = |lateral| / vertical wheel-rail force, defined in contact only (0 off the rail: a
    lifted wheel with a flange force would give |Q|/0); the one formula of the loop's peaks and
    the time-history table."""
    if in_contact and vertical_force > 0.0:
        return abs(lateral_force) / vertical_force
    return 0.0


@kernel
def derailment_coefficients(lateral_force, vertical_force, in_contact):
    """:func:`derailment_coefficient` over arrays (the table's Q/P columns)."""
    out = np.zeros(lateral_force.shape[0])
    for i in range(out.shape[0]):
        out[i] = derailment_coefficient(lateral_force[i], vertical_force[i], in_contact[i])
    return out


@kernel(creates_arrays=False)
def record_wheel_step(rec, wheel, step):
    """Peaks and contact loss of one step (module docstring); returns the number of wheels in
    contact."""
    wheel_peak, contact_loss = rec.wheel_peak, rec.contact_loss
    in_contact = 0
    for w in range(wheel.shape[0]):
        h = 0.0
        for k in range(2):
            fz = wheel[w, k, 2]
            fy = wheel[w, k, 1]
            h += fy
            if fz > wheel_peak[w, k, 0]:
                wheel_peak[w, k, 0] = fz
            if fz < wheel_peak[w, k, 1]:
                wheel_peak[w, k, 1] = fz
            if abs(fy) > wheel_peak[w, k, 2]:
                wheel_peak[w, k, 2] = abs(fy)
            if wheel[w, k, 4] > 0.0:
                in_contact += 1
                contact_loss[w, k, 4] = -1
                qp = derailment_coefficient(fy, fz, np.bool_(True))
                if qp > wheel_peak[w, k, 3]:
                    wheel_peak[w, k, 3] = qp
            else:
                if contact_loss[w, k, 4] < 0:
                    contact_loss[w, k, 0] += 1
                    contact_loss[w, k, 4] = step
                    if contact_loss[w, k, 5] < 0:
                        contact_loss[w, k, 5] = step
                contact_loss[w, k, 1] += 1
                run = step - contact_loss[w, k, 4] + 1
                if run > contact_loss[w, k, 2]:
                    contact_loss[w, k, 2] = run
                    contact_loss[w, k, 3] = contact_loss[w, k, 4]
        if abs(h) > rec.h_peak[w]:
            rec.h_peak[w] = abs(h)
    return in_contact


@kernel(creates_arrays=False)
def record_vehicle_output(rec, row, t, q, a):
    """The vehicle's displacements and accelerations of one output step; returns (finite, the
    largest |displacement| over ``rec.displacement_dofs``), for the loop's divergence checks."""
    rec.t_out[row] = t
    big = 0.0
    for i in range(q.shape[0]):
        rec.q_hist[row, i] = q[i]
        rec.a_hist[row, i] = a[i]
        if not np.isfinite(q[i]) or not np.isfinite(a[i]):
            return False, big
        if rec.displacement_dofs[i] != 0 and abs(q[i]) > big:
            big = abs(q[i])
    return True, big


@kernel(creates_arrays=False)
def record_wheel_output(rec, row, wheel):
    """The wheel forces of one output step (:data:`WHEEL_HISTORY_COLUMNS`)."""
    for w in range(wheel.shape[0]):
        for k in range(2):
            rec.wheel_hist[row, w, k, 0] = wheel[w, k, 0]
            rec.wheel_hist[row, w, k, 1] = wheel[w, k, 1]
            rec.wheel_hist[row, w, k, 2] = wheel[w, k, 2]
            rec.wheel_hist[row, w, k, 3] = wheel[w, k, 5]
            rec.wheel_hist[row, w, k, 4] = wheel[w, k, 4]
