"""Zhai step limit of the vehicle's own modes: suspension plus linearised wheel-rail contact.

The contact limit (:func:`ttbpipe.timestepping.limits.contact_time_step_limit`) bounds the Hertz
mode of half a wheelset and the creep dampers one at a time; it misses the suspension. A light
body on stiff springs or strong dampers (bogie pitch inertia 1 kg m^2 with the default primary
dampers: c/I = 2.5e5 1/s; primary vertical stiffness 5e8 N/m on top of the Hertz springs) has
modes that diverge at steps both checks accept. This module builds the linear system the loop
integrates explicitly, per car, with the rail fixed, and finds the largest stable Zhai step of
it with :func:`ttbpipe.timestepping.zhai.zhai_critical_time_step` (spectral radius of the
one-step amplification matrix <= 1; validated in tests against the closed form of one damped
oscillator and against runs of the diverging cars).

Linear system of one car (35 DOF; ttbpipe.vehicle.model), symmetric parts only:

* M, K, C of the suspension: the car's diagonal blocks of the train's matrices, so a coupler
  acts as if the neighbouring car were fixed (couplers are soft: 5e5 N/m on a 44 t body);
* Hertz springs to the fixed rail, one per wheel, k_H = 1.5 P^(1/3)/G at P = ``load_factor``
  times the car's static wheel load (2, as the contact limit: dynamic peaks stiffen the spring),
  on the contact's vertical displacement z + s a0 roll (cos delta taken as 1: stiffer);
* the flange spring k_f on y + r0 roll, one flange per wheelset (active when flanging);
* the creep forces the loop treats explicitly, as dampers (Kalker's linear law at the same load;
  the Shen-Hedrick-Elkins saturation only lowers them): longitudinal f11/V on the contact point's
  longitudinal velocity s a0 yaw' + r0 spin', spin f33 cos^2(delta)/V on yaw', and, with
  ``lateral_creep: explicit`` only, lateral f22/V on the lateral sliding velocity
  cos(delta) (y' + r0 roll') + sin(delta) (s z' + a0 roll'). The semi-implicit lateral creep
  (default) is unconditionally stable for its damper and is left out.

Left out on purpose: the non-symmetric creep terms (f22 yaw, the conicity term of xi_x, the skew
f23 coupling) and the gravitational stiffness of the contact angle. They are low-frequency
(hunting, kinematic coupling), physical rather than numerical instabilities, and with them the
exact solution itself may grow, which a numerical-stability criterion must not count.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from .contact import ContactGeometry, creep_coefficients, hertz_stiffness
from .model import DOF_PER_BODY, DOF_PER_CAR, PITCH, ROLL, WHEELSETS, YAW, Y, Z, TrainModel, dof_labels

log = logging.getLogger(__name__)

#: Safety factor on the vehicle limit (as the contact and coupled limits: the linearisation at
#: twice the static load is not an upper bound of the dynamic Hertz stiffness).
VEHICLE_SAFETY = 0.9

_CACHE: dict[tuple, dict] = {}


def linearised_car(model: TrainModel, geom: ContactGeometry, car: int, speed: float,
                   lateral_creep: str = "semi_implicit", load_factor: float = 2.0
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(mass (35,), K (35, 35), C (35, 35)) of car ``car`` on a fixed rail (module docstring)."""
    dofs = DOF_PER_CAR * car + np.arange(DOF_PER_CAR)
    mass = model.mass[dofs].copy()
    k = model.stiffness[dofs][:, dofs].toarray()
    c = model.damping[dofs][:, dofs].toarray()
    params = model.params.cars[car]
    load = load_factor * params.static_wheel_load
    k_h = hertz_stiffness(load, geom.hertz_g)
    f11, f22, _f23, f33 = creep_coefficients(geom, load)
    tab = geom.table[geom.table.shape[0] // 2]
    cos_d, sin_d = np.cos(tab[3]), np.sin(tab[3])
    a0, r0 = geom.contact_half_distance, geom.wheel_radius
    for ws in WHEELSETS:
        b = DOF_PER_BODY * ws
        iy, iz, ir, ip, iw = b + Y, b + Z, b + ROLL, b + PITCH, b + YAW
        flange = np.zeros(DOF_PER_CAR)
        flange[iy], flange[ir] = 1.0, r0
        k += geom.flange_stiffness * np.outer(flange, flange)
        for side in (1.0, -1.0):
            vert = np.zeros(DOF_PER_CAR)
            vert[iz], vert[ir] = 1.0, side * a0
            k += k_h * np.outer(vert, vert)
            lon = np.zeros(DOF_PER_CAR)
            lon[ip], lon[iw] = r0, side * a0
            c += f11 / speed * np.outer(lon, lon)
            c[iw, iw] += f33 * cos_d * cos_d / speed
            if lateral_creep == "explicit":
                lat = np.zeros(DOF_PER_CAR)
                lat[iy], lat[iz], lat[ir] = cos_d, side * sin_d, r0 * cos_d + a0 * sin_d
                c += f22 / speed * np.outer(lat, lat)
    return mass, k, c


def vehicle_time_step_limit(model: TrainModel, geom: ContactGeometry, speed: float,
                            lateral_creep: str = "semi_implicit") -> dict:
    """Largest stable Zhai step of every car's linear system (module docstring).

    Returns dt_vehicle_limit_s (spectral radius <= 1), dt_vehicle_s (times
    :data:`VEHICLE_SAFETY`, the step :func:`ttbpipe.simulation.setup.prepare` enforces) and
    vehicle_mode, the DOF dominating the first mode to diverge (e.g. ``car1_bogie1_pitch``).
    Cached per (train parameters, speed, lateral creep law): every sample of a study shares it.
    """
    key = (repr(model.params), float(speed), str(lateral_creep))
    if key in _CACHE:
        return dict(_CACHE[key])
    from ..timestepping.zhai import zhai_critical_time_step

    t0 = time.perf_counter()
    labels = dof_labels(model.params.n_cars)
    blocks: dict[bytes, dict] = {}
    best = None
    n_eval = 0
    for car in range(model.params.n_cars):
        mass, k, c = linearised_car(model, geom, car, speed, lateral_creep)
        tag = mass.tobytes() + k.tobytes() + c.tobytes()
        if tag not in blocks:
            blocks[tag] = zhai_critical_time_step(1.0 / mass, k, c)
            n_eval += blocks[tag]["evaluations"]
        res = blocks[tag]
        if best is None or res["dt_limit_s"] < best[0]:
            best = (res["dt_limit_s"], labels[DOF_PER_CAR * car + res["mode_dof"]])
    out = {"dt_vehicle_limit_s": float(best[0]), "dt_vehicle_s": float(VEHICLE_SAFETY * best[0]),
           "vehicle_mode": best[1]}
    log.debug("vehicle step limit %.3g s (%s): %d distinct cars, %d eigenvalue problems, "
              "%.0f ms", best[0], best[1], len(blocks), n_eval, 1e3 * (time.perf_counter() - t0))
    _CACHE[key] = out
    return dict(out)


def vehicle_step_is_stable(model: TrainModel, geom: ContactGeometry, speed: float, dt: float,
                           lateral_creep: str = "semi_implicit") -> bool:
    """One spectral-radius check of every distinct car at step ``dt`` (no bisection; cached
    like :func:`vehicle_time_step_limit`)."""
    from ..timestepping.zhai import SPECTRAL_RADIUS_TOL, zhai_spectral_radius

    key = ("step", repr(model.params), float(speed), str(lateral_creep), float(dt))
    if key in _CACHE:
        return bool(_CACHE[key])
    seen = set()
    for car in range(model.params.n_cars):
        mass, k, c = linearised_car(model, geom, car, speed, lateral_creep)
        tag = mass.tobytes() + k.tobytes() + c.tobytes()
        if tag in seen:
            continue
        seen.add(tag)
        if zhai_spectral_radius(1.0 / mass, k, c, dt) > 1.0 + SPECTRAL_RADIUS_TOL:
            _CACHE[key] = False
            return False
    _CACHE[key] = True
    return True
