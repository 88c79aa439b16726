"""Coupled train-track-bridge time integration: 35-DOF cars, 3-D wheel-rail contact, structure.

One ``@njit`` loop advances the vehicle and the structure together with Zhai's explicit two-step
scheme (same dt; physics.md section 5) and computes the wheel-rail contact forces at every step
from the wheel and rail kinematics plus the track irregularities (seed paper sections 2.2.11,
eqs. 28-31). ``track: rigid`` runs the same loop on rails fixed in space (irregularities only).

Entry point: :func:`run_coupled` (case configuration dict -> time histories, summary).

Case configuration (all sections optional; SI units unless the key says otherwise)::

    train:        see ttbpipe.vehicle.parameters.train_from_config (+ speed_kmh)
    structure:    the structure owner's section (ttbpipe.structure.build_structure)
    properties:   the structure owner's random-property factors (ttbpipe.simulation.run)
    simulation:
      track: structure | rigid          # default: structure
      speed_kmh: 300                    # or train.speed_kmh
      time_step_s: 1.0e-4               # or auto (one case, not a study): the smallest of
                                        #  every stability limit (structure, coupled, contact,
                                        #  vehicle; resolve_time_step)
      check_time_step: true             # the structure's and coupled checks (the contact and
                                        #  vehicle checks always run)
      lateral_creep: semi_implicit      # or explicit: the lateral creep damper f22/V on the rail
                                        #  head, semi-implicit (no step limit; docs/performance.md)
      output_interval_s: 1.0e-3         # or output_every: n steps
      duration_s: null                  # alternative to end_x_m
      start_x_m: null                   # leading wheelset at t=0 (default: rear wheelset 5 m
                                        #  inside the rails)
      end_x_m: null                     # leading wheelset at the end (default: 5 m before the
                                        #  rails end); rigid track: start 0, end = start + length
      rigid_length_m: 200               # rigid track only: run length of the leading wheelset
      margin_m: 5
    irregularity:
      source: synthetic | file | none   # default synthetic
      spectrum: tbt3352                 # synthetic: any name of ttbpipe.irregularity.spectra
      seed: 1
      dx_m: 0.25
      file: path.parquet                # file: chainage_m + vertical_mm, alignment_mm,
                                        #  cross_level_mm, gauge_mm (x = chainage_m)
      scale: 1.0                        # multiplies all channels
      fade_in_m: 20                     # raised-cosine fade-in ahead of the leading wheelset
      channels: [vertical, alignment, cross_level, gauge]   # others set to zero
    monitors: [...]                     # structure monitors (default: the structure's default)

Time step: every stability limit is computed first (:func:`resolve_time_step`, :func:`step_limits`)
and a refused step's message proposes one that passes all of them. The loop's stops
(:data:`STATUS_MESSAGES`) raise :class:`SimulationStopped`, whose message names the likely cause
(the step, or the irregularity, or a loss of contact; :mod:`ttbpipe.simulation.diagnosis`).
Loss of wheel-rail contact is counted at every step and reported as its own index (summary
``contact_loss_*``); Q/P is defined in contact only. Nothing non-finite leaves
:func:`run_coupled` (:func:`check_finite`).

Irregularities: the four spectral channels become per-rail inputs with
:func:`ttbpipe.channels.rails_from_spectral`; each wheel reads its rail's profile at its own x.
The track is perfect behind the leading wheelset's start position and the irregularity fades in
over ``fade_in_m`` ahead of it, so the gravity-loaded static state at t = 0 is exact and every
wheel sees the same profile at the same x.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
import pandas as pd
from numba import njit

from ..channels import rails_from_spectral
from ..threads import pinned
from ..structure.kernels import (StructurePacked, _add_rail_point_force,
                                 _add_rail_point_force_at, _rail_point_kinematics_at,
                                 _structure_accelerations, _zhai_predict)
from ..vehicle.comfort import sperling_index
from ..vehicle.contact import (N_COLS, ContactGeometry, build_geometry, creep_coefficients,
                               hertz_stiffness)
from ..vehicle.kernels import N_WHEEL_OUT, _csr_matvec_sub, _train_contact_relaxed
from ..vehicle.model import (DOF_PER_CAR, PITCH, ROLL, YAW, Y, Z, TrainModel, build_train_model)
from ..vehicle.parameters import TrainParameters, train_from_config
from ..vehicle.stability import VEHICLE_SAFETY, vehicle_step_is_stable, vehicle_time_step_limit
from ..vehicle.static import StructureStatic, solve_vehicle_static

log = logging.getLogger(__name__)

#: What each stop of the loop means; the cause and remedy come from ttbpipe.simulation.diagnosis
#: (the step is not always at fault).
STATUS_MESSAGES = {
    1: "non-finite state (numerical blow-up)",
    2: "every wheel lost contact with the rail at the same step",
    3: "vehicle displacement above 0.5 m (divergence)",
}


class SimulationStopped(RuntimeError):
    """The loop stopped (status 1-3 of :data:`STATUS_MESSAGES`); the message names the likely
    cause (time step, irregularity, loss of contact) with its remedy
    (:func:`ttbpipe.simulation.diagnosis.explain`). Attributes: status, step, t_s, x_lead_m,
    cause, contact_loss (the loss-of-contact index up to the stop)."""

    def __init__(self, setup: "CoupledSetup", status: int, step: int, contact_loss: np.ndarray,
                 q: np.ndarray):
        from .diagnosis import contact_loss_stats, explain

        self.status, self.step = int(status), int(step)
        self.t_s = (step + 1) * setup.dt
        self.x_lead_m = setup.x_lead0 + setup.speed * self.t_s
        m = setup.model
        self.contact_loss = contact_loss_stats(contact_loss, setup.dt, setup.x_lead0 + m.wheelset_x,
                                               setup.speed, _wheel_labels(m))
        limits = diagnosis_limits(setup)
        self.cause, text = explain(setup.dt, limits, setup.irregularity_info, self.contact_loss,
                                   setup.irregularity_config, setup.speed,
                                   propose_auto=setup.propose_auto)
        finite = q[np.isfinite(q)]
        big = f"; largest vehicle displacement {np.abs(finite).max():.3f} m" if finite.size else ""
        super().__init__(f"coupled simulation stopped at t = {self.t_s:.4f} s (leading wheelset at "
                         f"x = {self.x_lead_m:.1f} m): {STATUS_MESSAGES[status]}{big}; {text}")


# ---------------------------------------------------------------------------------------------
# kernels
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def _irregularity_at(irr, irr_slope, x0, dx, channel, x):
    """Value and x-derivative of irregularity channel at x (linear interpolation; 0 outside)."""
    s = (x - x0) / dx
    n = irr.shape[1]
    if s < 0.0 or s >= n - 1:
        return 0.0, 0.0
    i = int(s)
    w = s - i
    return (irr[channel, i] * (1.0 - w) + irr[channel, i + 1] * w,
            irr_slope[channel, i] * (1.0 - w) + irr_slope[channel, i + 1] * w)


@njit(cache=True)
def _rail_kinematics(packed, disp, vel, ws_x, speed, head_height, irr, irr_slope, irr_x0, irr_dx,
                     rail_kin):
    """Rail-head z, dz/dt, y, dy/dt at every wheel: structure (shear centre moved to the head
    by the roll, y_head = y - h roll) plus the irregularity of that rail (dz/dt = V dz/dx)."""
    # rail geometry as scalars: passing ``packed`` per point costs ~0.3 us (docs/performance.md)
    x0, dx, n_nodes = packed.rail_x0, packed.rail_dx, packed.rail_n_nodes
    if packed.n_rails == 0:
        n_nodes = 0
    dof0 = packed.rail_dof0
    for w in range(ws_x.shape[0]):
        x = ws_x[w]
        for k in range(2):
            z, vz, y, vy, r, vr = _rail_point_kinematics_at(x0, dx, n_nodes, dof0[k], x, disp, vel)
            zi, dzi = _irregularity_at(irr, irr_slope, irr_x0, irr_dx, k, x)
            yi, dyi = _irregularity_at(irr, irr_slope, irr_x0, irr_dx, 2 + k, x)
            rail_kin[w, k, 0] = z + zi
            rail_kin[w, k, 1] = vz + speed * dzi
            rail_kin[w, k, 2] = y - head_height * r + yi
            rail_kin[w, k, 3] = vy - head_height * vr + speed * dyi


@njit(cache=True)
def _evaluate(t, q, v, a, inv_mass, k_ptr, k_idx, k_val, c_ptr, c_idx, c_val, f_const,
              ws_dofs, ws_x0, speed, table, scal, head_height, irr, irr_slope, irr_x0, irr_dx,
              packed, disp, vel, acc, nodal_force, ws_x, rail_kin, f_veh, wheel, row, tmp,
              creep_state, creep_relax):
    """Accelerations of vehicle and structure at time t for the current (q, v, disp, vel).

    ``creep_state``/``creep_relax``: semi-implicit lateral creep (vehicle.kernels).
    """
    for w in range(ws_x.shape[0]):
        ws_x[w] = ws_x0[w] + speed * t
    _rail_kinematics(packed, disp, vel, ws_x, speed, head_height, irr, irr_slope, irr_x0, irr_dx,
                     rail_kin)
    for i in range(f_veh.shape[0]):
        f_veh[i] = f_const[i]
    _train_contact_relaxed(q, v, ws_dofs, table, scal, speed, rail_kin, f_veh, wheel, row, tmp,
                           creep_state, creep_relax)
    _csr_matvec_sub(k_ptr, k_idx, k_val, q, f_veh)
    _csr_matvec_sub(c_ptr, c_idx, c_val, v, f_veh)
    for i in range(f_veh.shape[0]):
        a[i] = f_veh[i] * inv_mass[i]
    for i in range(nodal_force.shape[0]):
        nodal_force[i] = 0.0
    x0, dx, n_nodes = packed.rail_x0, packed.rail_dx, packed.rail_n_nodes
    if packed.n_rails == 0:
        n_nodes = 0
    dof0 = packed.rail_dof0
    for w in range(ws_x.shape[0]):
        for k in range(2):
            fy_rail = -wheel[w, k, 1]
            _add_rail_point_force_at(x0, dx, n_nodes, dof0[k], ws_x[w], -wheel[w, k, 2], fy_rail,
                                     -head_height * fy_rail, nodal_force)
    _structure_accelerations(packed, disp, vel, nodal_force, acc)


@njit(cache=True)
def _coupled_loop(q, v, a, a_prev, inv_mass, k_ptr, k_idx, k_val, c_ptr, c_idx, c_val, f_const,
                  ws_dofs, ws_x0, speed, table, scal, head_height,
                  irr, irr_slope, irr_x0, irr_dx,
                  packed, disp, vel, acc, acc_prev,
                  mon_ptr, mon_dof, mon_coef, mon_qty, mon_scale,
                  dt, n_steps, out_every,
                  t_out, wheel_hist, q_hist, a_hist, mon_hist, wheel_peak, h_peak, mon_peak,
                  contact_loss, creep_relax=0.0):
    """Zhai explicit integration of vehicle + structure; returns (status, step).

    Outputs every ``out_every`` steps (row 0 = t 0): wheel_hist[row, ws, side] = (F_x, F_y, F_z,
    y_rel, N) with N the Hertz normal force (> 0: in contact); q_hist/a_hist vehicle
    displacements/accelerations; mon_hist monitor values (scaled).
    Peaks over every step: wheel_peak[ws, side] = (max F_z, min F_z, max |F_y|, max |F_y|/F_z
    over the steps in contact), h_peak[ws] = max |F_y,left + F_y,right|, mon_peak[m] =
    max |monitor|. Loss of contact (N = 0) at every step, per wheel, in steps:
    contact_loss[ws, side] = (events, steps without contact, longest event, its first step,
    first step of the event under way or -1, first step of the first event or -1); step s is the
    state at t = s dt, so an event of k steps lasts k dt.
    Status 0 ok, 1 non-finite, 2 all wheels off the rail, 3 vehicle divergence.
    ``creep_relax`` > 0: semi-implicit lateral creep (its state starts from the explicit law at
    t = 0).
    """
    n_ws = ws_dofs.shape[0]
    n_v = q.shape[0]
    ws_x = np.zeros(n_ws)
    rail_kin = np.zeros((n_ws, 2, 4))
    f_veh = np.zeros(n_v)
    wheel = np.zeros((n_ws, 2, N_WHEEL_OUT))
    row = np.zeros(N_COLS)
    tmp = np.zeros(N_WHEEL_OUT)
    nodal_force = np.zeros(disp.shape[0])
    creep_state = np.zeros((n_ws, 2))
    n_mon = mon_ptr.shape[0] - 1
    _evaluate(0.0, q, v, a, inv_mass, k_ptr, k_idx, k_val, c_ptr, c_idx, c_val, f_const,
              ws_dofs, ws_x0, speed, table, scal, head_height, irr, irr_slope, irr_x0, irr_dx,
              packed, disp, vel, acc, nodal_force, ws_x, rail_kin, f_veh, wheel, row, tmp,
              creep_state, 0.0)
    out_row = 0
    for n in range(-1, n_steps):
        if n >= 0:
            psi = 0.0 if n == 0 else 0.5
            _zhai_predict(q, v, a, a_prev, dt, psi, psi)
            _zhai_predict(disp, vel, acc, acc_prev, dt, psi, psi)
            for i in range(n_v):
                a_prev[i] = a[i]
            for i in range(disp.shape[0]):
                acc_prev[i] = acc[i]
            _evaluate((n + 1) * dt, q, v, a, inv_mass, k_ptr, k_idx, k_val, c_ptr, c_idx, c_val,
                      f_const, ws_dofs, ws_x0, speed, table, scal, head_height, irr, irr_slope,
                      irr_x0, irr_dx, packed, disp, vel, acc, nodal_force, ws_x, rail_kin, f_veh,
                      wheel, row, tmp, creep_state, creep_relax)
        # peaks and loss of contact at every step
        in_contact = 0
        step = n + 1
        for w in range(n_ws):
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
                    if fz > 0.0:   # Q/P is defined in contact only
                        qp = abs(fy) / fz
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
            if abs(h) > h_peak[w]:
                h_peak[w] = abs(h)
        if in_contact == 0:
            return 2, n
        for m in range(n_mon):
            s = 0.0
            for j in range(mon_ptr[m], mon_ptr[m + 1]):
                d = mon_dof[j]
                if mon_qty[m] == 0:
                    s += mon_coef[j] * disp[d]
                elif mon_qty[m] == 1:
                    s += mon_coef[j] * vel[d]
                else:
                    s += mon_coef[j] * acc[d]
            s *= mon_scale[m]
            if abs(s) > mon_peak[m]:
                mon_peak[m] = abs(s)
            if (n + 1) % out_every == 0:
                mon_hist[out_row, m] = s
        if (n + 1) % out_every == 0:
            t_out[out_row] = (n + 1) * dt
            big = 0.0
            for i in range(n_v):
                q_hist[out_row, i] = q[i]
                a_hist[out_row, i] = a[i]
                if not np.isfinite(q[i]) or not np.isfinite(a[i]):
                    return 1, n
                if abs(q[i]) > big:
                    big = abs(q[i])
            for i in range(disp.shape[0]):
                if not np.isfinite(disp[i]):
                    return 1, n
            if big > 0.5:
                return 3, n
            for w in range(n_ws):
                for k in range(2):
                    wheel_hist[out_row, w, k, 0] = wheel[w, k, 0]
                    wheel_hist[out_row, w, k, 1] = wheel[w, k, 1]
                    wheel_hist[out_row, w, k, 2] = wheel[w, k, 2]
                    wheel_hist[out_row, w, k, 3] = wheel[w, k, 5]
                    wheel_hist[out_row, w, k, 4] = wheel[w, k, 4]
            out_row += 1
    return 0, n_steps


# ---------------------------------------------------------------------------------------------
# set-up
# ---------------------------------------------------------------------------------------------
def rigid_packed() -> StructurePacked:
    """An empty structure: rails fixed in space (``track: rigid``)."""
    i0 = np.zeros(0, dtype=np.int64)
    f0 = np.zeros(0)
    return StructurePacked(
        n_dof=0, n_diag=0, inv_mass=f0, beam_dof_a=i0, beam_dof_b=i0, beam_L=f0, beam_EIv=f0,
        beam_EIl=f0, beam_GK=f0, link_ptr=np.zeros(1, dtype=np.int64), link_dof=i0, link_coef=f0,
        link_k=f0, link_c=f0, span_dof0=i0, span_n=i0, span_mat0=i0, span_K=f0, span_C=f0,
        span_Minv=f0, span_scratch=np.zeros(1), n_rails=0, rail_x0=0.0, rail_dx=1.0,
        rail_n_nodes=0, rail_dof0=np.zeros(2, dtype=np.int64))


@dataclass
class Irregularity:
    """Per-rail irregularity inputs (m) on a uniform grid: rows z_left, z_right, y_left, y_right."""

    x0: float
    dx: float
    values: np.ndarray   # (4, n) m
    slopes: np.ndarray   # (4, n) d/dx

    @classmethod
    def none(cls) -> "Irregularity":
        return cls(0.0, 1.0, np.zeros((4, 2)), np.zeros((4, 2)))


def build_irregularity(cfg: Mapping[str, Any] | None, x_start: float, x_end: float,
                       x_fade_start: float) -> Irregularity:
    """Irregularity inputs over [x_start, x_end] from the case's ``irregularity`` section."""
    cfg = dict(cfg or {})
    source = cfg.get("source", "synthetic")
    if source == "none":
        return Irregularity.none()
    dx = float(cfg.get("dx_m", 0.25))
    if source == "synthetic":
        from ..irregularity.synthesis import synthesize_profiles
        length = x_end - x_start + 2 * dx
        prof = synthesize_profiles(cfg.get("spectrum", "tbt3352"), length, dx,
                                   seed=int(cfg.get("seed", 1)))
        chain = prof["chainage_m"].to_numpy(float) + x_start - dx
    elif source == "file":
        path = cfg.get("file")
        if not path:
            raise ValueError("irregularity.file: a Parquet/CSV path is required for source: file")
        prof = pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)
        need = ["chainage_m", "vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm"]
        missing = [c for c in need if c not in prof.columns]
        if missing:
            raise ValueError(f"{path}: missing column(s) {missing}")
        for c in need:
            bad = np.flatnonzero(~np.isfinite(prof[c].to_numpy(float)))
            if bad.size:
                raise ValueError(f"{path}: non-finite value in column {c} at row {bad[0]}")
        chain = prof["chainage_m"].to_numpy(float)
        steps = np.diff(chain)
        if np.any(steps <= 0) or np.ptp(steps) > 1e-6 * steps.mean():
            raise ValueError(f"{path}: chainage_m must be uniform and increasing")
        dx = float(steps.mean())
        if chain[0] > x_start or chain[-1] < x_end:
            raise ValueError(f"{path}: chainage {chain[0]:.1f}-{chain[-1]:.1f} m does not cover the "
                             f"wheel positions {x_start:.1f}-{x_end:.1f} m of this run")
    else:
        raise ValueError(f"irregularity.source: {source!r}; expected synthetic | file | none")
    channels = cfg.get("channels", ["vertical", "alignment", "cross_level", "gauge"])
    scale = float(cfg.get("scale", 1.0)) * 1e-3  # mm -> m
    spec = {}
    for ch in ("vertical", "alignment", "cross_level", "gauge"):
        spec[ch] = prof[f"{ch}_mm"].to_numpy(float) * scale if ch in channels else np.zeros(len(prof))
    rails = rails_from_spectral(spec["vertical"], spec["alignment"], spec["cross_level"], spec["gauge"])
    values = np.vstack([rails["z_left"], rails["z_right"], rails["y_left"], rails["y_right"]])
    fade = float(cfg.get("fade_in_m", 20.0))
    # start two grid steps ahead so that the interpolated value AND slope are exactly 0 at the
    # leading wheelset's start (central-difference slopes reach one point back)
    s = np.clip((chain - x_fade_start - 2.0 * dx) / max(fade, 1e-9), 0.0, 1.0)
    window = 0.5 - 0.5 * np.cos(np.pi * s)
    values = values * window
    slopes = np.gradient(values, dx, axis=1)
    return Irregularity(float(chain[0]), dx, np.ascontiguousarray(values), np.ascontiguousarray(slopes))


def contact_time_step_limit(model: TrainModel, geom: ContactGeometry, speed: float,
                            rail_inv_mass_z: float = 0.0, rail_inv_mass_y: float = 0.0) -> dict:
    """Largest stable Zhai step from the wheel-rail contact (safety 0.9; omega dt <= 2 undamped,
    c dt / m <= 2 for a stiff damper, physics.md section 5).

    * Hertz mode: linearised stiffness k_H = 1.5 P^(1/3)/G at twice the largest static wheel load
      (dynamic peaks) between half a wheelset and the rail node under it:
      omega = sqrt(k_H (1/m_w + 1/m_r,z)) (rigid track: 1/m_r = 0).
    * Creep damping: the creep forces are viscous in the sliding velocities, with c = f11/V per
      wheel on the spin (lever r0: c_spin = 2 f11 r0^2/V on the spin inertia), c = f22/V per
      wheel laterally between the wheelset and the rail head (effective inverse mass of the head
      1/m_y + h^2/I_roll). At low speed these become the stiffest "modes" of the system.
    ``rail_inv_mass_*``: largest inverse mass of a rail node (z) and of the rail head (y).
    """
    p_max = 2.0 * float(model.static_wheel_load.max())
    k_h = hertz_stiffness(p_max, geom.hertz_g)
    m_w = 0.5 * min(c.wheelset_mass for c in model.params.cars)
    omega = np.sqrt(k_h * (1.0 / m_w + rail_inv_mass_z))
    dt_hertz = 0.9 * 2.0 / omega
    f11, f22, _, _ = creep_coefficients(geom, p_max)
    spin_inertia = min(c_.wheelset_spin_inertia for c_ in model.params.cars)
    dt_spin = 0.9 * 2.0 * spin_inertia / (2 * f11 * geom.wheel_radius ** 2 / speed)
    # lateral: wheelset (two wheels, mass 2 m_w) against the rail head of one wheel
    inv_lat = max(1.0 / (2 * m_w) * 2.0, rail_inv_mass_y + 1.0 / (2 * m_w))
    dt_lat = 0.9 * 2.0 / (f22 / speed * inv_lat)
    return {"dt_s": float(min(dt_hertz, dt_spin, dt_lat)), "dt_hertz_s": float(dt_hertz),
            "omega_hertz_rad_s": float(omega),
            "dt_creep_spin_s": float(dt_spin), "dt_creep_lateral_s": float(dt_lat),
            "hertz_stiffness_N_m": float(k_h),
            "lateral_creep_inverse_mass_1_kg": float(inv_lat)}


def coupled_time_step_limit(structure, limits: Mapping[str, Any], safety: float = 0.9) -> dict:
    """Zhai step limit of the structure with the Hertz contact springs (physics.md section 5).

    The structure's check (K, M of the structure alone) and the contact check (Hertz spring
    between half a wheelset and a rail node, rail node otherwise free) each miss the other's
    stiffness: the rail node under a wheel carries both. In mass-normalised coordinates the
    coupled stiffness is the sum of the two, so by Weyl's inequality (Horn & Johnson, Matrix
    Analysis, thm 4.3.1) omega_coupled^2 <= omega_structure^2 + omega_hertz^2; the limit is
    Omega_crit(zeta of the structure's top mode) / that omega, times ``safety``. Both omegas come
    from the model actually integrated (factored rail masses and stiffnesses).
    Returns dt_structure_s (safety 0.9, as stable_time_step), dt_structure_limit_s (safety 1),
    dt_coupled_s (with ``safety``: the ``auto`` step and the step :func:`prepare` enforces, as
    the contact check does), dt_coupled_limit_s (safety 1), omega_structure_rad_s.
    Measured (case 2, C1 sample 32, rail mass factor 0.63): dt_coupled_limit_s 1.228e-4 s,
    dt_coupled_s 1.105e-4 s; the run is stable at 1.2e-4 s and diverges at 1.22e-4 s (t = 1.36 s),
    1.23e-4 (0.94 s), 1.25e-4 s (0.65 s): the linear bound with k_H at twice the static load
    needs the 0.9 margin (dynamic wheel loads stiffen the Hertz spring, k ~ P^(1/3)).
    """
    from ..structure.integrator import stable_time_step, zhai_critical_omega_dt
    info = stable_time_step(structure, safety=1.0)
    w_s = float(info["omega_max_rad_s"])
    w_c = float(np.hypot(w_s, float(limits["omega_hertz_rad_s"])))
    crit = zhai_critical_omega_dt(round(max(float(info["zeta"]), 0.0), 6))
    return {"dt_structure_s": 0.9 * float(info["dt_limit_s"]),
            "dt_structure_limit_s": float(info["dt_limit_s"]),
            "structure_frequency_hz": float(info["frequency_hz"]),
            "structure_zeta": float(info["zeta"]),
            "omega_structure_rad_s": w_s, "dt_coupled_s": float(safety * crit / w_c),
            "dt_coupled_limit_s": float(crit / w_c)}


def floor_significant(x: float, digits: int = 2) -> float:
    """x rounded DOWN to ``digits`` significant digits; the printed value ``f'{r:.{digits}g}'``
    parses back to a number <= x (a proposed step must pass the limit it was derived from)."""
    if not np.isfinite(x) or x <= 0:
        return float(x)
    e = int(np.floor(np.log10(x))) - (digits - 1)
    m = int(np.floor(x / 10.0 ** e * (1.0 - 1e-12)))
    while m > 0 and float(f"{m}e{e}") > x:
        m -= 1
    return float(f"{m}e{e}")


#: Names of the stability limits in messages and in the summary's ``dt_limits``.
LIMIT_NAMES = {"structure": "structure", "coupled": "coupled rail-contact",
               "hertz": "Hertz contact", "creep_spin": "creep spin",
               "creep_lateral": "creep lateral", "vehicle": "vehicle suspension"}


def step_limits(limits: Mapping[str, Any]) -> dict[str, float]:
    """Every stability limit of a case that applies (s, safety factors included), by
    :data:`LIMIT_NAMES` key: a step at or below their minimum passes every check of
    :func:`prepare`. Structure and coupled limits only when they were computed (a structure,
    and ``check_time_step`` or ``auto``); creep lateral only with ``lateral_creep: explicit``."""
    out = {}
    if "dt_structure_s" in limits:
        out["structure"] = float(limits["dt_structure_s"])
        out["coupled"] = float(limits["dt_coupled_s"])
    if "dt_hertz_s" in limits:   # absent only in a summary that was not made by prepare()
        out["hertz"] = float(limits["dt_hertz_s"])
        out["creep_spin"] = float(limits["dt_creep_spin_s"])
    if limits.get("lateral_creep") == "explicit":
        out["creep_lateral"] = float(limits["dt_creep_lateral_s"])
    if "dt_vehicle_s" in limits:
        out["vehicle"] = float(limits["dt_vehicle_s"])
    return out


def proposed_time_step(limits: Mapping[str, Any]) -> float:
    """The step a message proposes: min of :func:`step_limits` rounded down to 2 digits."""
    return floor_significant(min(step_limits(limits).values()), 2)


def _limit_list(limits: Mapping[str, Any]) -> str:
    lims = step_limits(limits)
    text = ", ".join(f"{LIMIT_NAMES[k]} {v:.3g} s" for k, v in sorted(lims.items(), key=lambda kv: kv[1]))
    if "structure" not in lims:
        text += ("; rigid track: no structure limit" if limits.get("track") == "rigid" else
                 "; structure and coupled limits not computed: simulation.check_time_step false")
    return text


def time_step_remedy(limits: Mapping[str, Any], propose_auto: bool) -> str:
    """'set simulation.time_step_s <= N ...': N passes every limit (rounded down, 2 digits)."""
    text = (f"set simulation.time_step_s <= {proposed_time_step(limits):.2g}, which passes every "
            f"stability limit of this case ({_limit_list(limits)})")
    if propose_auto:
        return text + ", or time_step_s: auto (the smallest of these limits)"
    return (text + "; in a study every sample uses this one step, and random properties move the "
            "structure and coupled limits from sample to sample: leave a margin below this "
            "sample's limits")


def _violation_text(key: str, dt: float, limits: Mapping[str, Any]) -> str:
    """What a violated limit is and what moves it (the old per-check messages)."""
    if key == "structure":
        return (f"the Zhai stability limit {limits['dt_structure_limit_s']:.3g} s of this structure "
                f"(mode at {limits['structure_frequency_hz']:.0f} Hz, damping ratio "
                f"{limits['structure_zeta']:.3f}; structure.rail.rotary_inertia_scaling or a coarser "
                "structure.slab.element_length_m raises it, docs/structure.md)")
    if key == "coupled":
        return (f"the coupled rail-contact stability limit {limits['dt_coupled_s']:.3g} s (safety 0.9) "
                f"of this structure (highest structural mode "
                f"{limits['omega_structure_rad_s'] / (2 * np.pi):.0f} Hz plus the Hertz contact mode "
                f"{limits['omega_hertz_rad_s'] / (2 * np.pi):.0f} Hz on the lightest rail node; with "
                "random rail properties a light or stiff rail element lowers it)")
    if key == "contact":
        return (f"the wheel-rail contact stability limit {limits['dt_s']:.3g} s (Hertz "
                f"{limits['dt_hertz_s']:.3g} s, creep {limits['dt_creep_spin_s']:.3g} s spin, "
                f"{limits['dt_creep_lateral_s']:.3g} s lateral, {limits['lateral_creep']}; creep "
                "damping grows as 1/V: low speeds need smaller steps; simulation.lateral_creep: "
                "semi_implicit removes the lateral creep limit)")
    return (f"the vehicle suspension stability limit {limits['dt_vehicle_s']:.3g} s (safety "
            f"{VEHICLE_SAFETY}; Zhai amplification of the linearised car on a fixed rail, first mode "
            f"to diverge: {limits['vehicle_mode']}: a light body on stiff springs or strong dampers; "
            "check the train parameters, vehicle/stability.py)")


def resolve_time_step(sim: Mapping[str, Any], model: TrainModel, geom: ContactGeometry,
                      speed: float, structure, limits: dict, *, propose_auto: bool = False
                      ) -> float:
    """The step of a case from ``simulation.time_step_s`` after every stability check.

    ``limits`` (the contact limits) is completed in place with the vehicle limit
    (:func:`ttbpipe.vehicle.stability.vehicle_time_step_limit`) and, on a structure with
    ``check_time_step`` (default) or ``auto``, the structure and coupled limits
    (:func:`coupled_time_step_limit`). ``auto`` is the smallest of them (:func:`step_limits`).
    A number is refused when it exceeds the structure's limit, the coupled limit, the contact
    limit (``dt_s``) or the vehicle limit (also checked directly at dt / safety: one spectral
    radius per car); the message names every violated limit and proposes a step that passes
    all of them (:func:`time_step_remedy`), with ``auto`` only if ``propose_auto``.
    """
    dt_setting = sim.get("time_step_s", 1.0e-4)
    check = sim.get("check_time_step", True)
    lateral_creep = limits["lateral_creep"]
    limits["track"] = "rigid" if structure is None else "structure"
    limits.update(vehicle_time_step_limit(model, geom, speed, lateral_creep))
    if structure is not None and (dt_setting == "auto" or check):
        # on the model actually integrated (random-property factors applied above)
        limits.update(coupled_time_step_limit(structure, limits))
    if dt_setting == "auto":
        dt = min(step_limits(limits).values())
        log.info("time_step_s auto: %.3g s (%s)", dt, _limit_list(limits))
        return float(dt)
    dt = float(dt_setting)
    if not dt > 0:
        raise ValueError(f"simulation.time_step_s must be positive, got {dt_setting!r}")
    violated = []
    if structure is not None and check:
        if dt > limits["dt_structure_limit_s"]:
            violated.append("structure")
        if dt > limits["dt_coupled_s"] * (1 + 1e-9):
            violated.append("coupled")
    if dt > limits["dt_s"]:
        violated.append("contact")
    if dt > limits["dt_vehicle_s"] * (1 + 1e-9) or not vehicle_step_is_stable(
            model, geom, speed, dt / VEHICLE_SAFETY, lateral_creep):
        violated.append("vehicle")
    if violated:
        raise ValueError(f"simulation.time_step_s={dt:g} s exceeds "
                         + " and ".join(_violation_text(k, dt, limits) for k in violated)
                         + "; " + time_step_remedy(limits, propose_auto))
    return dt


def rail_inverse_masses(packed, head_height: float) -> tuple[float, float]:
    """Largest inverse mass of a rail node vertically and of the rail head laterally
    (1/m_y + h^2/I_roll), from the structure's lumped inverse masses."""
    inv = np.asarray(packed.inv_mass)
    z_max, y_max = 0.0, 0.0
    for r in range(int(packed.n_rails)):
        base = int(packed.rail_dof0[r]) + 5 * np.arange(int(packed.rail_n_nodes))
        z_max = max(z_max, float(inv[base].max()))
        y_max = max(y_max, float((inv[base + 2] + head_height ** 2 * inv[base + 4]).max()))
    return z_max, y_max


def _wheel_labels(model: TrainModel) -> list[str]:
    labels = []
    for w in range(model.n_wheelsets):
        c = int(model.wheelset_car[w])
        j = w - int(np.flatnonzero(model.wheelset_car == c)[0]) + 1
        labels.append(f"car{c + 1}_ws{j}")
    return labels


@dataclass
class CoupledSetup:
    """Everything the loop needs, built from a case configuration (exposed for tests)."""

    train: TrainParameters
    model: TrainModel
    geom: ContactGeometry
    speed: float
    dt: float
    n_steps: int
    out_every: int
    x_lead0: float
    irregularity: Irregularity
    structure: Any
    packed: StructurePacked
    head_height: float
    monitors: Any
    q0: np.ndarray
    v0: np.ndarray             # zero except the steady spin-rate perturbations
    disp0: np.ndarray
    f_const: np.ndarray
    static_wheel: np.ndarray   # (n_ws, 2, 7) contact table of the static state
    dt_limits: dict
    static_iterations: int
    creep_relax: float = 0.0   # semi-implicit lateral creep: m_eff^-1 dt / V (0: explicit)
    irregularity_info: dict = field(default_factory=dict)   # diagnosis.irregularity_indicators
    irregularity_config: dict = field(default_factory=dict)  # the case's irregularity section
    propose_auto: bool = False  # messages may offer time_step_s: auto (prepare)


def _rail_kin_at(packed, disp, ws_x, head_height, irr: Irregularity) -> np.ndarray:
    rail_kin = np.zeros((ws_x.size, 2, 4))
    _rail_kinematics(packed, disp, np.zeros_like(disp), ws_x, 0.0, head_height,
                     irr.values, irr.slopes, irr.x0, irr.dx, rail_kin)
    return rail_kin


def static_equilibrium(model, geom, speed, packed, structure_static, head_height, irr, ws_x,
                       tol_load: float = 1e-3, max_iter: int = 30):
    """Train + structure static state: fixed point between the vehicle Newton solve and the
    structure's linear static solve. Returns (q, v, disp, wheel, iterations); v is zero except
    the wheelsets' steady spin rates."""
    n_s = int(packed.n_dof)
    disp = np.zeros(n_s)
    prev = None
    for it in range(1, max_iter + 1):
        rail_kin = _rail_kin_at(packed, disp, ws_x, head_height, irr)
        q, wheel, v = solve_vehicle_static(model, geom, speed, rail_kin)
        if structure_static is None:
            return q, v, disp, wheel, it
        force = np.zeros(n_s)
        for w in range(ws_x.size):
            for k in range(2):
                fy_rail = -wheel[w, k, 1]
                _add_rail_point_force(packed, k, ws_x[w], -wheel[w, k, 2], fy_rail,
                                      -head_height * fy_rail, force)
        disp = structure_static.solve(force)
        loads = wheel[:, :, 2]
        if prev is not None and np.max(np.abs(loads - prev)) < tol_load:
            rail_kin = _rail_kin_at(packed, disp, ws_x, head_height, irr)
            q, wheel, v = solve_vehicle_static(model, geom, speed, rail_kin)
            return q, v, disp, wheel, it
        prev = loads
    raise RuntimeError(f"train-structure static equilibrium did not converge in {max_iter} "
                       "iterations; check the structure supports and the suspension stiffness")


def prepare(case: Mapping[str, Any], *, propose_auto: bool = False) -> CoupledSetup:
    """Build the train, contact, structure, irregularity and the static state of a case.

    ``propose_auto``: a refused time step's message may offer ``time_step_s: auto`` besides the
    concrete step (``ttbpipe simulate``, one case). Off by default: in a study every sample must
    use the same step (one time grid), so ``auto``, which takes each sample's own limit, is
    not a remedy there. ``auto`` itself is accepted either way (see :func:`resolve_time_step`).
    """
    case = dict(case or {})
    sim = dict(case.get("simulation") or {})
    train_cfg = dict(case.get("train") or {})
    speed_kmh = sim.get("speed_kmh", train_cfg.get("speed_kmh"))
    if speed_kmh is None:
        raise ValueError("simulation.speed_kmh (or train.speed_kmh) is required")
    speed = float(speed_kmh) / 3.6
    if speed <= 0:
        raise ValueError(f"simulation.speed_kmh must be positive, got {speed_kmh}")
    train = train_from_config(train_cfg)
    model = build_train_model(train)
    geom = build_geometry(train.contact)
    track = sim.get("track", "structure")
    margin = float(sim.get("margin_m", 5.0))
    train_len = -float(model.wheelset_x.min())
    if track == "rigid":
        structure, packed = None, rigid_packed()
        head_height = train.contact.rail_head_height
        x_lead0 = float(sim.get("start_x_m") or 0.0)
        x_end = float(sim.get("end_x_m") or (x_lead0 + float(sim.get("rigid_length_m", 200.0))))
        rail_inv = (0.0, 0.0)
        monitors = None
    elif track == "structure":
        from ..structure import build_structure
        from ..structure.monitors import compile_monitors, default_monitors
        from ..structure import apply_factors
        from .run import property_factors  # structure owner's random-property factors
        structure = build_structure(case.get("structure") or {})
        factors = property_factors(case.get("properties"), structure)
        if factors:
            structure = apply_factors(structure, factors)
        packed = structure.packed
        head_height = structure.rail_head_height_m
        x_min, x_max = structure.rail_x_range
        x_lead0 = float(sim["start_x_m"]) if sim.get("start_x_m") is not None else x_min + margin + train_len
        x_end = float(sim["end_x_m"]) if sim.get("end_x_m") is not None else x_max - margin
        if x_lead0 - train_len < x_min or x_end > x_max:
            raise ValueError(
                f"the train ({train_len:.1f} m between end wheelsets) must stay on the modelled rails "
                f"[{x_min:.1f}, {x_max:.1f}] m but runs with its leading wheelset from {x_lead0:.1f} "
                f"to {x_end:.1f} m; lengthen the structure's approaches or set simulation.start_x_m/end_x_m")
        rail_inv = rail_inverse_masses(packed, head_height)
        specs = case.get("monitors") or default_monitors(structure)
        monitors = compile_monitors(structure, specs)
    else:
        raise ValueError(f"simulation.track: {track!r}; expected structure | rigid")
    if sim.get("duration_s") is not None:
        x_end = x_lead0 + speed * float(sim["duration_s"])
        if structure is not None and x_end > structure.rail_x_range[1]:
            raise ValueError(f"simulation.duration_s={sim['duration_s']} s takes the leading wheelset "
                             f"to x = {x_end:.1f} m, beyond the rails; shorten it")
    if x_end <= x_lead0:
        raise ValueError(f"simulation: end_x_m {x_end} must exceed start_x_m {x_lead0}")
    limits = contact_time_step_limit(model, geom, speed, *rail_inv)
    lateral_creep = sim.get("lateral_creep", "semi_implicit")
    if lateral_creep not in ("semi_implicit", "explicit"):
        raise ValueError(f"simulation.lateral_creep: {lateral_creep!r}; expected semi_implicit | "
                         "explicit")
    limits["lateral_creep"] = lateral_creep
    if lateral_creep == "semi_implicit":
        # the lateral creep damper is integrated semi-implicitly (unconditionally stable;
        # docs/performance.md): only the Hertz and spin limits bound the step
        limits["dt_s"] = float(min(limits["dt_hertz_s"], limits["dt_creep_spin_s"]))
    dt = resolve_time_step(sim, model, geom, speed, structure, limits, propose_auto=propose_auto)
    if sim.get("output_every") is not None:
        out_every = int(sim["output_every"])
    else:
        out_every = max(1, int(round(float(sim.get("output_interval_s", 1.0e-3)) / dt)))
    duration = (x_end - x_lead0) / speed
    n_steps = int(np.ceil(duration / dt / out_every)) * out_every
    irr = build_irregularity(case.get("irregularity"), x_lead0 - train_len - 1.0,
                             x_end + speed * dt * out_every + 1.0, x_lead0)
    ws_x = x_lead0 + model.wheelset_x
    sstatic = StructureStatic(structure) if structure is not None else None
    q0, v0, disp0, wheel0, iters = static_equilibrium(model, geom, speed, packed, sstatic, head_height,
                                                  irr, ws_x)
    f_const = model.gravity_force + model.coupler_stiffness @ q0
    creep_relax = (limits["lateral_creep_inverse_mass_1_kg"] * dt / speed
                   if lateral_creep == "semi_implicit" else 0.0)
    from .diagnosis import PLAUSIBLE_D1_PEAK_MM, irregularity_indicators
    irr_info = irregularity_indicators(irr, speed, model)
    if (irr_info["contact_demand_ratio"] > 1.0 or max(irr_info["peak_vertical_d1_mm"],
                                                      irr_info["peak_lateral_d1_mm"]) > PLAUSIBLE_D1_PEAK_MM):
        log.warning("irregularity: peak %.1f mm vertical, %.1f mm lateral in 3-25 m (plausible at "
                    "most %.0f mm); its curvature asks for %.1f times the wheel acceleration "
                    "contact can give at %.0f km/h: expect loss of wheel-rail contact",
                    irr_info["peak_vertical_d1_mm"], irr_info["peak_lateral_d1_mm"],
                    PLAUSIBLE_D1_PEAK_MM, irr_info["contact_demand_ratio"], speed * 3.6)
    return CoupledSetup(train=train, model=model, geom=geom, speed=speed, dt=dt, n_steps=n_steps,
                        out_every=out_every, x_lead0=x_lead0, irregularity=irr, structure=structure,
                        packed=packed, head_height=head_height, monitors=monitors, q0=q0, v0=v0,
                        disp0=disp0, f_const=f_const, static_wheel=wheel0, dt_limits=limits,
                        static_iterations=iters, creep_relax=creep_relax,
                        irregularity_info=irr_info,
                        irregularity_config=dict(case.get("irregularity") or {}),
                        propose_auto=propose_auto)


@dataclass
class RawResult:
    """Arrays returned by the loop (before the table is built)."""

    time: np.ndarray
    wheel: np.ndarray      # (n_out, n_ws, 2, 5): F_x, F_y, F_z, y_rel, N (normal force)
    q: np.ndarray
    a: np.ndarray
    monitors: np.ndarray
    wheel_peak: np.ndarray
    h_peak: np.ndarray
    monitor_peak: np.ndarray
    wall_s: float
    contact_loss: np.ndarray | None = None   # (n_ws, 2, 6) int64 steps, see _coupled_loop


def integrate(setup: CoupledSetup) -> RawResult:
    """Run the njit loop for a prepared case; raises RuntimeError with the remedy on trouble."""
    m = setup.model
    n_v = m.n_dof
    n_out = setup.n_steps // setup.out_every + 1
    q = setup.q0.copy()
    v = setup.v0.copy()
    a = np.zeros(n_v)
    a_prev = np.zeros(n_v)
    disp = setup.disp0.copy()
    vel = np.zeros_like(disp)
    acc = np.zeros_like(disp)
    acc_prev = np.zeros_like(disp)
    k, c = m.stiffness, m.damping
    if setup.monitors is not None:
        mon = setup.monitors
        mon_ptr, mon_dof, mon_coef, mon_qty, mon_scale = mon.ptr, mon.dof, mon.coef, mon.qty, mon.scale
    else:
        mon_ptr, mon_dof, mon_coef = np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)
        mon_qty, mon_scale = np.zeros(0, np.int64), np.zeros(0)
    n_mon = mon_ptr.size - 1
    t_out = np.zeros(n_out)
    wheel_hist = np.zeros((n_out, m.n_wheelsets, 2, 5))
    q_hist = np.zeros((n_out, n_v))
    a_hist = np.zeros((n_out, n_v))
    mon_hist = np.zeros((n_out, n_mon))
    wheel_peak = np.zeros((m.n_wheelsets, 2, 4))
    wheel_peak[:, :, 1] = np.inf
    h_peak = np.zeros(m.n_wheelsets)
    mon_peak = np.zeros(n_mon)
    contact_loss = np.zeros((m.n_wheelsets, 2, 6), dtype=np.int64)
    contact_loss[:, :, 3:] = -1
    ws_x0 = setup.x_lead0 + m.wheelset_x
    irr = setup.irregularity
    t0 = time.perf_counter()
    status, step = _coupled_loop(
        q, v, a, a_prev, 1.0 / m.mass, k.indptr.astype(np.int64), k.indices.astype(np.int64), k.data,
        c.indptr.astype(np.int64), c.indices.astype(np.int64), c.data, setup.f_const,
        m.wheelset_dofs, ws_x0, setup.speed, setup.geom.table, setup.geom.scalars(),
        setup.head_height, irr.values, irr.slopes, irr.x0, irr.dx,
        setup.packed, disp, vel, acc, acc_prev,
        mon_ptr, mon_dof, mon_coef, mon_qty, mon_scale,
        setup.dt, setup.n_steps, setup.out_every,
        t_out, wheel_hist, q_hist, a_hist, mon_hist, wheel_peak, h_peak, mon_peak,
        contact_loss, setup.creep_relax)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SimulationStopped(setup, status, step, contact_loss, q)
    return RawResult(t_out, wheel_hist, q_hist, a_hist, mon_hist, wheel_peak, h_peak, mon_peak,
                     wall, contact_loss)


# ---------------------------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------------------------
CARBODY_POINTS = ("front", "centre", "rear")


def carbody_accelerations(setup: CoupledSetup, a_hist: np.ndarray) -> dict[str, np.ndarray]:
    """Car-body floor accelerations (vertical, lateral) above the bogie pivots and at the centre.

    At a point x_p from the car centre (rigid body, small rotations): a_z = z'' - x_p pitch'',
    a_y = y'' + x_p yaw'' (model.point_row), at the car's centre-of-gravity height.
    """
    out = {}
    for ci, car in enumerate(setup.train.cars):
        base = DOF_PER_CAR * ci
        for name, xp in zip(CARBODY_POINTS, (car.bogie_half_spacing, 0.0, -car.bogie_half_spacing)):
            out[f"car{ci + 1}_body_{name}_az_m_s2"] = a_hist[:, base + Z] - xp * a_hist[:, base + PITCH]
            out[f"car{ci + 1}_body_{name}_ay_m_s2"] = a_hist[:, base + Y] + xp * a_hist[:, base + YAW]
    return out


def results_table(setup: CoupledSetup, raw: RawResult) -> pd.DataFrame:
    """Time histories: wheel forces, contact flag, Q/P, unloading, H, car-body accelerations,
    monitors.

    ``<wheel>_in_contact`` (int8, 1/0): normal force N > 0 and P > 0 at that output step. Q/P is
    defined in contact only: |Q|/P there and 0 where the wheel is off the rail (a lifted wheel
    with a flange force would give |Q|/0); the unloading (P0 - P)/P0 is 1 there. The loss of
    contact itself is its own index (summary ``contact_loss_*``).
    """
    m = setup.model
    labels = _wheel_labels(m)
    p0 = setup.static_wheel[:, :, 2]
    cols: dict[str, np.ndarray] = {"time_s": raw.time,
                                   "x_lead_m": setup.x_lead0 + setup.speed * raw.time}
    for w, lab in enumerate(labels):
        for k, side in enumerate(("left", "right")):
            p = raw.wheel[:, w, k, 2]
            qf = raw.wheel[:, w, k, 1]
            contact = (raw.wheel[:, w, k, 4] > 0.0) & (p > 0.0)
            cols[f"{lab}_{side}_P_N"] = p
            cols[f"{lab}_{side}_Q_N"] = qf
            cols[f"{lab}_{side}_in_contact"] = contact.astype(np.int8)
            cols[f"{lab}_{side}_QP"] = np.where(contact, np.abs(qf) / np.where(contact, p, 1.0), 0.0)
            cols[f"{lab}_{side}_unloading"] = (p0[w, k] - p) / p0[w, k]
        cols[f"{lab}_H_N"] = raw.wheel[:, w, 0, 1] + raw.wheel[:, w, 1, 1]
        cols[f"{lab}_y_mm"] = 1e3 * raw.q[:, m.wheelset_dofs[w, Y]]
    cols.update(carbody_accelerations(setup, raw.a))
    if setup.monitors is not None:
        for i, name in enumerate(setup.monitors.names):
            cols[name] = raw.monitors[:, i]
    return pd.DataFrame(cols)


def summarise(setup: CoupledSetup, raw: RawResult, table: pd.DataFrame) -> dict:
    """Peak values (every step) and Sperling indices per car."""
    m = setup.model
    labels = _wheel_labels(m)
    p0 = setup.static_wheel[:, :, 2]
    peak = raw.wheel_peak
    unloading = (p0 - peak[:, :, 1]) / p0
    dt_out = setup.dt * setup.out_every
    summary: dict[str, Any] = {
        "speed_kmh": setup.speed * 3.6, "time_step_s": setup.dt, "n_steps": setup.n_steps,
        "simulated_s": setup.n_steps * setup.dt, "wall_s": raw.wall_s,
        "wall_s_per_simulated_s": raw.wall_s / (setup.n_steps * setup.dt),
        "dt_limits": setup.dt_limits, "static_iterations": setup.static_iterations,
        "static_wheel_load_N": {lab: p0[w].tolist() for w, lab in enumerate(labels)},
        "max_wheel_load_N": float(peak[:, :, 0].max()),
        "min_wheel_load_N": float(peak[:, :, 1].min()),
        "max_lateral_wheel_force_N": float(peak[:, :, 2].max()),
        "max_derailment_coefficient": float(peak[:, :, 3].max()),
        "max_wheel_unloading": float(unloading.max()),
        "max_wheelset_lateral_force_N": float(raw.h_peak.max()),
        "contact": setup.geom.description,
        "irregularity": dict(setup.irregularity_info),
    }
    if raw.contact_loss is not None:
        from .diagnosis import contact_loss_stats
        summary.update(contact_loss_stats(raw.contact_loss, setup.dt, setup.x_lead0 + m.wheelset_x,
                                          setup.speed, labels))
    if setup.monitors is not None:
        summary["monitor_peaks"] = {name: float(raw.monitor_peak[i])
                                    for i, name in enumerate(setup.monitors.names)}
    sperling = {}
    record_s = len(table) * dt_out
    if record_s < 5.0:
        log.warning("Sperling indices from a %.2f s record (shorter than the 5 s window of the "
                    "standard): each evaluated as one window", record_s)
    summary["sperling_record_s"] = record_s
    for ci in range(setup.train.n_cars):
        for direction, key in (("vertical", "az"), ("lateral", "ay")):
            vals = [sperling_index(table[f"car{ci + 1}_body_{p}_{key}_m_s2"].to_numpy(), dt_out,
                                   direction, quiet=True)[0] for p in CARBODY_POINTS]
            sperling[f"car{ci + 1}_{direction}"] = float(max(vals))
    summary["sperling"] = sperling
    summary["max_carbody_vertical_acc_m_s2"] = float(max(
        np.abs(table[c]).max() for c in table.columns if c.endswith("_az_m_s2")))
    summary["max_carbody_lateral_acc_m_s2"] = float(max(
        np.abs(table[c]).max() for c in table.columns if c.endswith("_ay_m_s2")))
    return summary


def diagnosis_limits(setup: CoupledSetup) -> dict:
    """The setup's dt_limits, with the structure and coupled limits computed now if the case
    skipped them (``check_time_step: false``): a diagnosis weighs the step against all."""
    limits = dict(setup.dt_limits)
    if setup.structure is not None and "dt_structure_s" not in limits:
        limits.update(coupled_time_step_limit(setup.structure, limits))
    return limits


def _nonfinite_entries(summary: Mapping[str, Any], prefix: str = "") -> list[str]:
    bad = []
    for key, value in summary.items():
        if isinstance(value, Mapping):
            bad += _nonfinite_entries(value, f"{prefix}{key}.")
        elif isinstance(value, (float, np.floating)) and not np.isfinite(value):
            bad.append(f"{prefix}{key}")
    return bad


def check_finite(setup: CoupledSetup, raw: RawResult, table: pd.DataFrame, summary: dict) -> None:
    """Raise ValueError naming the column(s) and summary key(s) with a non-finite value and the
    likely cause (:func:`ttbpipe.simulation.diagnosis.explain`): nothing non-finite reaches a
    results table."""
    values = table.to_numpy(dtype=float)
    bad_rows = ~np.isfinite(values)
    columns = [c for c, b in zip(table.columns, bad_rows.any(axis=0)) if b]
    keys = _nonfinite_entries(summary)
    if not columns and not keys:
        return
    from .diagnosis import explain
    where = ""
    if columns:
        row = int(np.flatnonzero(bad_rows.any(axis=1))[0])
        where = (f" (first at t = {table['time_s'].iloc[row]:.4f} s, leading wheelset at x = "
                 f"{table['x_lead_m'].iloc[row]:.1f} m)")
    loss = {k: v for k, v in summary.items() if k.startswith("contact_loss")}
    _, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info, loss,
                      setup.irregularity_config, setup.speed, propose_auto=setup.propose_auto)
    raise ValueError(f"non-finite values in the coupled run's results: column(s) {columns[:8]}"
                     f"{' ...' if len(columns) > 8 else ''} ({len(columns)} in all){where}, "
                     f"summary key(s) {keys}; the loop only stops on a non-finite vehicle or "
                     f"structure state, so this is a defect of the post-processing or of an "
                     f"input; {text}")


@pinned
def run_coupled(case_config: Mapping[str, Any], *, propose_auto: bool = False
                ) -> tuple[pd.DataFrame, dict]:
    """Run one coupled case: (time-history table, summary dict). See the module docstring.

    Raises :class:`SimulationStopped` (a RuntimeError) when the loop stops, with the likely
    cause, and ValueError for a refused time step (``propose_auto``: see :func:`prepare`) or a
    non-finite result (:func:`check_finite`). A run in which wheels lose contact completes: the
    loss is reported (summary ``contact_loss_*``, a warning with its likely cause).
    """
    setup = prepare(case_config, propose_auto=propose_auto)
    log.info("coupled run: %d cars, %.1f km/h, dt %.2e s, %d steps, track %s", setup.train.n_cars,
             setup.speed * 3.6, setup.dt, setup.n_steps,
             "rigid" if setup.structure is None else f"{setup.packed.n_dof} structural DOF")
    raw = integrate(setup)
    table = results_table(setup, raw)
    summary = summarise(setup, raw, table)
    check_finite(setup, raw, table, summary)
    if summary["contact_loss_count"] > 0:
        from .diagnosis import explain
        _, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info,
                          summary, setup.irregularity_config, setup.speed,
                          propose_auto=propose_auto, stopped=False)
        log.warning("wheel-rail contact lost %d times on %d wheel(s), longest %.1f ms: %s",
                    summary["contact_loss_count"], summary["contact_loss_wheels"],
                    1e3 * summary["contact_loss_max_s"], text)
    log.info("coupled run done: %.1f s wall, %.2f s per simulated s", raw.wall_s,
             summary["wall_s_per_simulated_s"])
    return table, summary
