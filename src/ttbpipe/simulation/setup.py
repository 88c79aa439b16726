"""Set-up of a coupled run: case configuration -> train, contact, structure, track input, step,
static state (:func:`prepare`).

Case configuration (all sections optional; SI units unless the key says otherwise; schema:
``schemas/simulation.schema.json``)::

    train:        ttbpipe.vehicle.parameters.train_from_config (+ speed_kmh)
    structure:    the track-bridge structure (ttbpipe.structure.build_structure)
    properties:   random per-element property factors (ttbpipe.structure.random_properties)
    simulation:
      track: structure | rigid          # default: structure
      speed_kmh: 300                    # or train.speed_kmh
      time_step_s: 1.0e-4               # or auto (one case, not a study): the smallest of
                                        #  every stability limit (ttbpipe.timestepping.limits)
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
    irregularity:                       # ttbpipe.irregularity.track_input.build_irregularity
      source: synthetic | file | none   # default synthetic
      spectrum, seed, dx_m, file, scale, fade_in_m, channels
    monitors: [...]                     # structure monitors (default: the structure's default)

In memory, :func:`prepare` also takes the track input (``track``: an Irregularity, or a profile
table with chainage_m and the four channels in mm) and the property factors (``factors``:
{parameter: array over the carriers}) instead of files.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..irregularity.track_input import Irregularity, build_irregularity
from ..structure.rail_mesh import (RailMesh, add_rail_contact_load, add_rail_head_load, no_rails,
                                   rail_inverse_masses, rail_mesh)
from ..structure.static import StructureStatic
from ..timestepping.limits import (contact_time_step_limit, coupled_time_step_limit,
                                   resolve_time_step)
from ..vehicle.contact import ContactGeometry, build_geometry
from ..vehicle.dynamics import VehicleArrays, vehicle_arrays
from ..vehicle.kernels import RAIL_KIN_COLS
from ..vehicle.model import TrainModel, build_train_model
from ..vehicle.parameters import TrainParameters, train_from_config
from ..vehicle.curving import curve_arrays
from ..vehicle.static import solve_vehicle_static
from .loop import track_kinematics

log = logging.getLogger(__name__)


def wheel_labels(model: TrainModel) -> list[str]:
    """``car<c>_ws<j>`` of every wheelset, in the model's order."""
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
    structure: Any             # ttbpipe.structure.StructureModel, None on rigid track
    packed: Any                # the structure's packed arrays (an empty structure when rigid)
    mesh: RailMesh
    monitors: Any              # ttbpipe.structure.monitors.MonitorSet or None
    vehicle: VehicleArrays
    q0: np.ndarray
    v0: np.ndarray             # zero except the steady spin-rate perturbations
    disp0: np.ndarray
    static_wheel: np.ndarray   # (n_ws, 2, 7) contact table of the static state
    dt_limits: dict
    static_iterations: int
    creep_relax: float = 0.0   # semi-implicit lateral creep: m_eff^-1 dt / V (0: explicit)
    irregularity_info: dict = field(default_factory=dict)   # diagnosis.irregularity_indicators
    irregularity_config: dict = field(default_factory=dict)  # the case's irregularity section
    propose_auto: bool = False  # messages may offer time_step_s: auto (prepare)

    @property
    def n_spans(self) -> int:
        return 0 if self.structure is None else len(self.structure.spans)


def _rail_kin_at(mesh, disp, ws_x, irr: Irregularity) -> np.ndarray:
    rail_kin = np.zeros((ws_x.size, 2, RAIL_KIN_COLS))
    track_kinematics(mesh, irr, disp, np.zeros_like(disp), ws_x, 0.0, rail_kin)
    return rail_kin


def static_equilibrium(model, geom, speed, mesh, structure_static, irr, ws_x,
                       tol_load: float = 1e-3, max_iter: int = 30, curve=None):
    """Train + structure static state: fixed point between the vehicle Newton solve and the
    structure's linear static solve (the rails are ~100x stiffer than the primary suspension, so
    it converges in a few iterations; it stops when the wheel loads change by less than
    ``tol_load`` N). Returns (q, v, disp, wheel, iterations); v is zero except the wheelsets'
    steady spin rates. ``curve``: the track layout's terms (ttbpipe.vehicle.curving), the
    steady state on the curve at the train's start."""
    n_s = 0 if structure_static is None else int(structure_static.n)
    disp = np.zeros(n_s)
    prev = None
    for it in range(1, max_iter + 1):
        rail_kin = _rail_kin_at(mesh, disp, ws_x, irr)
        q, wheel, v = solve_vehicle_static(model, geom, speed, rail_kin, curve=curve,
                                           x_lead=float(ws_x[0]))
        if structure_static is None:
            return q, v, disp, wheel, it
        force = np.zeros(n_s)
        for w in range(ws_x.size):
            for k in range(2):
                if geom.zones is not None:       # as the loop (ttbpipe.simulation.loop)
                    add_rail_contact_load(mesh, k, ws_x[w], -wheel[w, k, 2], -wheel[w, k, 1],
                                          -wheel[w, k, 7], force)
                else:
                    add_rail_head_load(mesh, k, ws_x[w], -wheel[w, k, 2], -wheel[w, k, 1],
                                       force)
        disp = structure_static.solve(force)
        loads = wheel[:, :, 2]
        if prev is not None and np.max(np.abs(loads - prev)) < tol_load:
            rail_kin = _rail_kin_at(mesh, disp, ws_x, irr)
            q, wheel, v = solve_vehicle_static(model, geom, speed, rail_kin, curve=curve,
                                           x_lead=float(ws_x[0]))
            return q, v, disp, wheel, it
        prev = loads
    raise RuntimeError(f"train-structure static equilibrium did not converge in {max_iter} "
                       "iterations; check the structure supports and the suspension stiffness")


def rigid_packed():
    """An empty structure: rails fixed in space (``track: rigid``)."""
    from ..structure.kernels import StructurePacked

    i0 = np.zeros(0, dtype=np.int64)
    f0 = np.zeros(0)
    return StructurePacked(
        n_dof=0, n_diag=0, inv_mass=f0, beam_dof_a=i0, beam_dof_b=i0, beam_L=f0, beam_EIv=f0,
        beam_EIl=f0, beam_GK=f0, link_ptr=np.zeros(1, dtype=np.int64), link_dof=i0, link_coef=f0,
        link_k=f0, link_c=f0, span_dof0=i0, span_n=i0, span_mat0=i0, span_K=f0, span_C=f0,
        span_Minv=f0, span_scratch=np.zeros(1), n_rails=0, rail_x0=0.0, rail_dx=1.0,
        rail_n_nodes=0, rail_dof0=np.zeros(2, dtype=np.int64))


def _structure(case: Mapping[str, Any], factors: Mapping[str, np.ndarray] | None):
    from ..structure import apply_factors, build_structure
    from ..structure.random_properties import property_factors
    from ..vehicle.curving import cant_knots

    layout = (case.get("simulation") or {}).get("layout")
    structure = build_structure(case.get("structure") or {}, cant=cant_knots(layout))
    if factors is None:
        factors = property_factors(case.get("properties"), structure)
    if factors:
        structure = apply_factors(structure, dict(factors))
    return structure


def prepare(case: Mapping[str, Any], *, track: Irregularity | pd.DataFrame | None = None,
            factors: Mapping[str, np.ndarray] | None = None,
            propose_auto: bool = False) -> CoupledSetup:
    """Build the train, contact, structure, track input and the static state of a case.

    ``track``: the track input in memory (an :class:`Irregularity`, used as it is, or a profile
    table, faded in like a file's), instead of the case's ``irregularity`` source; ``factors``:
    the structure's property factors in memory, instead of its ``properties`` section.
    ``propose_auto``: a refused time step's message may offer ``time_step_s: auto`` besides the
    concrete step (``ttbpipe simulate``, one case). Off by default: in a study every sample must
    use the same step (one time grid), so ``auto``, which takes each sample's own limit, is
    not a remedy there. ``auto`` itself is accepted either way (ttbpipe.timestepping.limits).
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
    track_kind = sim.get("track", "structure")
    margin = float(sim.get("margin_m", 5.0))
    train_len = -float(model.wheelset_x.min())
    if track_kind == "rigid":
        structure, packed = None, rigid_packed()
        mesh = no_rails(train.contact.rail_head_height)
        x_lead0 = float(sim.get("start_x_m") or 0.0)
        x_end = float(sim.get("end_x_m") or (x_lead0 + float(sim.get("rigid_length_m", 200.0))))
        monitors = None
    elif track_kind == "structure":
        from ..structure.monitors import compile_monitors, default_monitors

        structure = _structure(case, factors)
        packed = structure.packed
        mesh = rail_mesh(packed, structure.rail_head_height_m)
        x_min, x_max = structure.rail_x_range
        x_lead0 = float(sim["start_x_m"]) if sim.get("start_x_m") is not None else x_min + margin + train_len
        x_end = float(sim["end_x_m"]) if sim.get("end_x_m") is not None else x_max - margin
        if x_lead0 - train_len < x_min or x_end > x_max:
            raise ValueError(
                f"the train ({train_len:.1f} m between end wheelsets) must stay on the modelled rails "
                f"[{x_min:.1f}, {x_max:.1f}] m but runs with its leading wheelset from {x_lead0:.1f} "
                f"to {x_end:.1f} m; lengthen the structure's approaches or set simulation.start_x_m/end_x_m")
        monitors = compile_monitors(structure, case.get("monitors") or default_monitors(structure))
    else:
        raise ValueError(f"simulation.track: {track_kind!r}; expected structure | rigid")
    if geom.zones is not None:
        # two-point contact: the vertical loads' lever about the rail's shear centre uses the
        # structure's head height, as the lateral force's (ttbpipe.structure.rail_mesh)
        import dataclasses

        geom = dataclasses.replace(geom, rail_head_height=float(mesh.head_height))
    if sim.get("duration_s") is not None:
        x_end = x_lead0 + speed * float(sim["duration_s"])
        if structure is not None and x_end > structure.rail_x_range[1]:
            raise ValueError(f"simulation.duration_s={sim['duration_s']} s takes the leading wheelset "
                             f"to x = {x_end:.1f} m, beyond the rails; shorten it")
    if x_end <= x_lead0:
        raise ValueError(f"simulation: end_x_m {x_end} must exceed start_x_m {x_lead0}")
    limits = contact_time_step_limit(model, geom, speed, *rail_inverse_masses(mesh, packed.inv_mass))
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
    if isinstance(track, Irregularity):
        irr = track
    else:
        irr = build_irregularity(case.get("irregularity"), x_lead0 - train_len - 1.0,
                                 x_end + speed * dt * out_every + 1.0, x_lead0, profile=track)
    ws_x = x_lead0 + model.wheelset_x
    sstatic = StructureStatic(structure) if structure is not None else None
    curve = curve_arrays(model, sim.get("layout"))
    q0, v0, disp0, wheel0, iters = static_equilibrium(model, geom, speed, mesh, sstatic, irr, ws_x,
                                                      curve=curve)
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
                        packed=packed, mesh=mesh, monitors=monitors,
                        vehicle=vehicle_arrays(model, geom, f_const, x_lead0, curve), q0=q0, v0=v0,
                        disp0=disp0, static_wheel=wheel0, dt_limits=limits,
                        static_iterations=iters, creep_relax=creep_relax,
                        irregularity_info=irr_info,
                        irregularity_config=dict(case.get("irregularity") or {}),
                        propose_auto=propose_auto)


def diagnosis_limits(setup: CoupledSetup) -> dict:
    """The setup's dt_limits, with the structure and coupled limits computed now if the case
    skipped them (``check_time_step: false``): a diagnosis weighs the step against all."""
    limits = dict(setup.dt_limits)
    if setup.structure is not None and "dt_structure_s" not in limits:
        limits.update(coupled_time_step_limit(setup.structure, limits))
    return limits
