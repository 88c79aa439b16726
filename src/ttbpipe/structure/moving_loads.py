"""Moving point loads on the structure (validation without a vehicle) and the run driver.

Loads enter the rails through the Hermite shape functions of the element they are in
(:func:`ttbpipe.structure.rail_mesh.add_rail_point_load`), exactly as the vehicle's contact
forces do; the time loop (:func:`_moving_load_loop`) uses the same Zhai step
(:mod:`ttbpipe.timestepping.zhai`), the same monitor recorder
(:func:`ttbpipe.structure.monitors.record_monitors`) and the same anti-alias decimation of the
histories (:mod:`ttbpipe.decimation`) as the coupled loop. For girder-only validation models (``layout.bridge_track: none``) the loads act on the
girder axis through the span's reduced basis instead (``loads.target: girder``).

Sign convention: forces in the structure's axes (z up, y left); a wheel pressing on the rail is
``Fz_N < 0``. ``axle_train.wheel_load_N`` is given as a positive magnitude and applied downwards;
``axle_train.train: NAME`` takes the axles and their loads from the train library
(:mod:`ttbpipe.trains`, e.g. ``HSLM-A1``), half of each axle load on each rail.

Double-track decks (``structure.layout.tracks: 2``): a load's ``rail`` is 0..3 (track k has
rails 2k, 2k + 1); an axle train runs on ``track`` k in ``direction`` +1 (+x) or -1 (-x: its
axles trail at x_front + d and it moves at -V); ``loads.axle_trains`` lists several trains
(two trains meeting on the bridge).
"""

from __future__ import annotations

import logging
import time
from collections import namedtuple
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..decimation import decimator, flush, push
from ..jit import kernel
from ..timestepping.limits import check_time_step, stable_time_step
from ..timestepping.zhai import zhai_predict
from .kernels import structure_accelerations, structure_accelerations_in_place
from .monitors import compile_monitors, default_monitors, record_monitors
from .rail_mesh import add_rail_point_load, rail_mesh

log = logging.getLogger(__name__)


@dataclass
class LoadSet:
    """Moving loads as arrays (n loads): rail, x at t=0, speed, constant and harmonic forces."""

    rail: np.ndarray
    x0: np.ndarray
    speed: np.ndarray
    F0: np.ndarray      # (n, 3): Fz, Fy, Mx
    F1: np.ndarray      # (n, 3): harmonic amplitudes
    freq: np.ndarray
    phase: np.ndarray
    target: str = "rail"
    track: np.ndarray | None = None   # track of each load (girder target: its offset); None: 0

    @property
    def n(self) -> int:
        return self.rail.size


def axle_offsets(train: Mapping[str, Any]) -> np.ndarray:
    """Axle distances behind the first axle (m) from ``axle_positions_m`` or a car layout.

    Car layout (each car: two bogies at +- bogie_centre_distance/2 about the car centre, two axles
    per bogie at +- wheelbase/2): ``cars``, ``car_length_m``, ``bogie_centre_distance_m``,
    ``wheelbase_m``. Default: CRH-type 25 m cars, 17.5 m bogie centres, 2.5 m wheelbase
    (physics.md section 6: 17.375 m; rounded to the car layout).
    """
    if "axle_positions_m" in train:
        pos = np.asarray(train["axle_positions_m"], dtype=float)
    else:
        cars = int(train.get("cars", 1))
        Lc = float(train.get("car_length_m", 25.0))
        bc = float(train.get("bogie_centre_distance_m", 17.375))
        wb = float(train.get("wheelbase_m", 2.5))
        local = np.array([-bc / 2 - wb / 2, -bc / 2 + wb / 2, bc / 2 - wb / 2, bc / 2 + wb / 2])
        pos = np.concatenate([c * Lc + Lc / 2 + local for c in range(cars)])
    pos = np.sort(pos - pos.min())
    return pos


def axle_train_loads(train: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(axle distances behind the first axle (m), wheel load per rail (N, magnitude)).

    ``train: NAME`` takes both from the train library (:func:`ttbpipe.trains.get_train`; each
    axle load is shared equally by the two wheels); otherwise the axles come from
    :func:`axle_offsets` and every wheel carries ``wheel_load_N``.
    """
    if "train" in train:
        from ..trains import get_train

        clash = sorted(set(train) & {"wheel_load_N", "axle_positions_m", "cars", "car_length_m",
                                     "bogie_centre_distance_m", "wheelbase_m"})
        if clash:
            raise ValueError(f"loads.axle_train: train {train['train']!r} gives the axles and "
                             f"loads; remove {', '.join(clash)}")
        try:
            named = get_train(str(train["train"]))
        except ValueError as err:
            raise ValueError(f"loads.axle_train.train: {err}") from None
        return np.asarray(named.positions_m, float), np.asarray(named.axle_loads_N) / 2.0
    if "wheel_load_N" not in train:
        raise ValueError("loads.axle_train: give wheel_load_N (with axle_positions_m or a car "
                         "layout) or a library train (train: NAME)")
    offsets = axle_offsets(train)
    return offsets, np.full(offsets.size, float(train["wheel_load_N"]))


def build_loads(loads_cfg: Mapping[str, Any], model) -> LoadSet:
    """LoadSet from the ``loads:`` section of a case config (``axle_train`` and/or a list of
    ``axle_trains``; a point load's ``speed_kmh`` < 0 moves it towards -x)."""
    speed_default = float(loads_cfg.get("speed_kmh", 0.0)) / 3.6
    n_rails = 2 * model.n_tracks
    rows = []
    for i, p in enumerate(loads_cfg.get("point_loads") or []):
        where = f"loads.point_loads[{i}]"
        rail = int(p.get("rail", 0))
        if not 0 <= rail < n_rails:
            raise ValueError(f"{where}.rail: {rail}; expected 0 (left) or 1 (right)"
                             + (f", 2k or 2k + 1 on track k < {n_rails // 2}"
                                if n_rails > 2 else ""))
        h = p.get("harmonic") or {}
        rows.append((rail, float(p.get("x0_m", 0.0)),
                     float(p["speed_kmh"]) / 3.6 if "speed_kmh" in p else speed_default,
                     [float(p.get("Fz_N", 0.0)), float(p.get("Fy_N", 0.0)),
                      float(p.get("Mx_Nm", 0.0))],
                     [float(h.get("Fz_amplitude_N", 0.0)), float(h.get("Fy_amplitude_N", 0.0)),
                      float(h.get("Mx_amplitude_Nm", 0.0))],
                     float(h.get("frequency_hz", 0.0)), float(h.get("phase_rad", 0.0))))
    trains = [("loads.axle_train", loads_cfg["axle_train"])] if loads_cfg.get("axle_train") \
        else []
    trains += [(f"loads.axle_trains[{i}]", t)
               for i, t in enumerate(loads_cfg.get("axle_trains") or [])]
    for where, train in trains:
        offsets, wheel_loads = axle_train_loads(train)
        x_front = float(train.get("front_x0_m", 0.0))
        v = float(train["speed_kmh"]) / 3.6 if "speed_kmh" in train else speed_default
        track = int(train.get("track", 0))
        if not 0 <= track < model.n_tracks:
            raise ValueError(f"{where}.track: {track}; the structure has {model.n_tracks} "
                             "track(s), 0-based")
        direction = int(train.get("direction", 1))
        if direction not in (1, -1):
            raise ValueError(f"{where}.direction: {direction}; expected 1 (+x) or -1 (-x)")
        for d, P in zip(offsets, wheel_loads):
            for rail in (2 * track, 2 * track + 1):
                rows.append((rail, x_front - direction * d, direction * v, [-P, 0.0, 0.0],
                             [0.0, 0.0, 0.0], 0.0, 0.0))
    if not rows:
        raise ValueError("loads: no loads; give loads.point_loads and/or loads.axle_train")
    target = loads_cfg.get("target", "rail" if model.packed.n_rails else "girder")
    if target not in ("rail", "girder"):
        raise ValueError(f"loads.target: {target!r}; expected rail | girder")
    if target == "rail" and model.packed.n_rails == 0:
        raise ValueError("loads.target: rail, but the structure has no track "
                         "(layout.bridge_track: none); use target: girder")
    rail = np.array([r[0] for r in rows], np.int64)
    return LoadSet(rail=rail,
                   x0=np.array([r[1] for r in rows]), speed=np.array([r[2] for r in rows]),
                   F0=np.array([r[3] for r in rows]), F1=np.array([r[4] for r in rows]),
                   freq=np.array([r[5] for r in rows]), phase=np.array([r[6] for r in rows]),
                   target=target, track=rail // 2)


def girder_force_table(model, loads: LoadSet, dt: float, n_steps: int):
    """(dofs, table (n_steps+1, n)) of generalised girder forces of loads acting on the girder.

    The load's rail is ignored: it acts on its track's centre line, e = ``girder.track_offset_m``
    (or that track's ``track_offsets_m``) to the left of the girder axis, so Fz adds the torque
    e Fz to Mx (paper eq. 24). A load on the common end of two spans acts on the first.
    Vectorised over the steps: each load's span rows at all its positions
    (``SpanReduction.rows_at_many``).
    """
    spans = model.spans
    track = np.zeros(loads.n, np.int64) if loads.track is None else loads.track
    off = model.dof_info["span_dof0"]
    dofs = np.concatenate([np.arange(o, o + s.n) for o, s in zip(off, spans)]).astype(np.int64)
    table = np.zeros((n_steps + 1, dofs.size))
    col0 = np.cumsum([0] + [s.n for s in spans])
    t = np.arange(n_steps + 1) * dt
    for i in range(loads.n):
        e_track = float(model.layout.track_offsets_m[track[i]])
        x = loads.x0[i] + loads.speed[i] * t
        F = loads.F0[i][None, :] + loads.F1[i][None, :] * np.sin(
            2 * np.pi * loads.freq[i] * t + loads.phase[i])[:, None]
        taken = np.zeros(t.size, dtype=bool)
        for s, red in enumerate(spans):
            on = ~taken & (x >= red.start_m) & (x <= red.start_m + red.length_m)
            steps = np.flatnonzero(on)
            if steps.size == 0:
                continue
            taken |= on
            rz, ry, rr = red.rows_at_many(x[steps])
            fz, fy, mx = F[steps, 0:1], F[steps, 1:2], F[steps, 2:3]
            table[steps, col0[s]:col0[s + 1]] += rz * fz + ry * fy + rr * (mx + e_track * fz)
    return dofs, table


def default_duration(model, loads: LoadSet) -> float:
    """Time until the last load has left the structure at the end it runs to (or 1 s for
    static loads)."""
    x_end = model.layout.total_m
    moving = loads.speed != 0
    if not np.any(moving):
        return 1.0
    v = loads.speed[moving]
    return float(np.max(np.where(v > 0, x_end - loads.x0[moving], -loads.x0[moving]) / v))


#: The loads as the loop reads them: rail, x at t = 0, speed, constant (Fz, Fy, Mx) and harmonic
#: amplitudes, frequency, phase (arrays over the loads); plus generalised forces table[step, j]
#: added to DOF dofs[j] (loads on the girder coordinates of girder-only validation models).
LoadArrays = namedtuple("LoadArrays", ["rail", "x0", "speed", "F0", "F1", "freq", "phase",
                                       "extra_dofs", "extra_table"])
#: Structure state of a time loop: displacements, velocities, accelerations (this and the last
#: step). A step clears ``acc``, adds its loads to it and the structure kernel turns them into
#: accelerations in place (:func:`ttbpipe.structure.kernels.structure_accelerations_in_place`).
StructureState = namedtuple("StructureState", ["disp", "vel", "acc", "acc_prev"])


@kernel(creates_arrays=False)
def _moving_load_loop(packed, mesh, loads, state, rec, dec, dt, n_steps, blowup_m):
    """Zhai time loop with moving point loads on the rails; records the monitors at every step
    into the anti-alias decimator ``dec`` (its rows: t = k out_every dt).

    Load i: rail loads.rail[i], position x = x0[i] + speed[i] t, forces (Fz, Fy, Mx) = F0[i] +
    F1[i] sin(2 pi freq[i] t + phase[i]). Returns the step at which a displacement monitor or a
    diagonal-mass DOF exceeded ``blowup_m`` or became NaN (-1 if none).
    """
    n_loads = loads.rail.shape[0]
    n_extra = loads.extra_dofs.shape[0]
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    for step in range(n_steps + 1):
        t = step * dt
        if step > 0:
            psi = 0.0 if step == 1 else 0.5
            zhai_predict(disp, vel, acc, acc_prev, dt, psi, psi)
        for i in range(acc.shape[0]):
            acc[i] = 0.0
        for i in range(n_loads):
            x = loads.x0[i] + loads.speed[i] * t
            s = np.sin(2.0 * np.pi * loads.freq[i] * t + loads.phase[i])
            add_rail_point_load(mesh, loads.rail[i], x,
                                loads.F0[i, 0] + loads.F1[i, 0] * s,
                                loads.F0[i, 1] + loads.F1[i, 1] * s,
                                loads.F0[i, 2] + loads.F1[i, 2] * s, acc)
        if n_extra > 0:
            for j in range(n_extra):
                acc[loads.extra_dofs[j]] += loads.extra_table[step, j]
        structure_accelerations_in_place(packed, disp, vel, acc)
        largest = record_monitors(rec, disp, vel, acc)
        push(dec, rec.current)
        if not largest < blowup_m:
            return step
        if step % 1000 == 0:
            for i in range(packed.n_diag):
                if not (abs(disp[i]) < blowup_m):
                    return step
    flush(dec)
    return -1


def simulate(model, loads: LoadSet, dt: float, duration: float, monitor_specs=None,
             output_every: int = 1, check_dt: bool = True, blowup_m: float = 1.0):
    """Run the moving-load case; returns (DataFrame of monitors with time_s, info dict).

    Raises FloatingPointError naming the remedy on blow-up (NaN or a displacement > blowup_m).
    """
    if dt <= 0 or duration <= 0:
        raise ValueError(f"time step {dt} s and duration {duration} s must be > 0")
    info: dict[str, Any] = {}
    if check_dt:
        info["stability"] = check_time_step(model, dt)
    specs = default_monitors(model) if monitor_specs is None else monitor_specs
    mons = compile_monitors(model, specs)
    n_steps = int(round(duration / dt))
    output_every = max(1, int(output_every))
    n_out = n_steps // output_every + 1
    rec = mons.recorder()
    dec = decimator(mons.n, n_out, output_every)
    n = model.n_dof
    state = StructureState(*(np.zeros(n) for _ in range(4)))
    if loads.target == "girder":
        extra_dofs, extra = girder_force_table(model, loads, dt, n_steps)
        empty = np.zeros(0)
        arrays = LoadArrays(np.zeros(0, np.int64), empty, empty, np.zeros((0, 3)),
                            np.zeros((0, 3)), empty, empty, extra_dofs, extra)
    else:
        arrays = LoadArrays(loads.rail, loads.x0, loads.speed, loads.F0, loads.F1, loads.freq,
                            loads.phase, np.zeros(0, np.int64), np.zeros((1, 0)))
    t0 = time.perf_counter()
    c0 = time.process_time()
    status = _moving_load_loop(model.packed, rail_mesh(model.packed, model.rail_head_height_m),
                               arrays, state, rec, dec, float(dt), n_steps, float(blowup_m))
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    if status >= 0:
        raise FloatingPointError(
            f"structure response blew up (NaN or |u| > {blowup_m} m) at t={status * dt:.4g} s; "
            f"reduce simulation.time_step_s (now {dt:g} s; stable limit "
            f"{stable_time_step(model)['dt_limit_s']:.3g} s) or check the loads' magnitudes")
    info.update(n_dof=n, n_steps=n_steps, dt_s=dt, wall_s=wall, cpu_s=cpu,
                wall_s_per_simulated_s=wall / (n_steps * dt),
                cpu_s_per_simulated_s=cpu / (n_steps * dt))
    log.info("simulated %.3f s (%d steps of %.3g s, %d DOF) in %.2f s wall (%.2f s per "
             "simulated s)", n_steps * dt, n_steps, dt, n, wall, info["wall_s_per_simulated_s"])
    t_out = (np.arange(n_out) * output_every) * dt
    df = pd.DataFrame(np.column_stack([t_out, dec.out]), columns=["time_s"] + mons.names)
    info["final_state"] = (state.disp, state.vel, state.acc)
    return df, info


def static_initial_acceleration(model, nodal_force: np.ndarray) -> np.ndarray:
    """M^-1 f at rest (helper for callers writing their own loop)."""
    acc = np.zeros(model.n_dof)
    z = np.zeros(model.n_dof)
    structure_accelerations(model.packed, z, z, nodal_force, acc)
    return acc
