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
      track_index: 0                    # the train's track on a double-track deck (0-based;
                                        #  structure.layout.tracks: 2)
      direction: 1                      # 1: the train runs +x; -1: -x (start/end_x_m defaults
                                        #  mirrored: it enters at the far end of the rails)
    irregularity:                       # ttbpipe.irregularity.track_input.build_irregularity
      source: synthetic | file | none   # default synthetic
      spectrum, seed, dx_m, file, scale, fade_in_m, channels
    second_train:                       # a second train on the other track of a double-track
      train: {...}                      #  deck, in the same run (default: the case's train)
      track_index: 1                    # default: the other track
      direction: -1                     # default: opposite to the first (the trains meet)
      speed_kmh: 300                    # default: the first train's speed
      start_x_m: null                   # its leading wheelset at t = 0 (default: as the
                                        #  first's default for its direction)
      irregularity: shared              # its track's profile: shared (the irregularity
                                        #  section's, on this track's rails) or a section
    monitors: [...]                     # structure monitors (default: the structure's default)

In memory, :func:`prepare` also takes the track input (``track``: an Irregularity, or a profile
table with chainage_m and the four channels in mm; ``second_track`` for the second train's
track) and the property factors (``factors``: {parameter: array over the carriers}) instead
of files.

Placement: a train on track k runs on rails 2k (left) and 2k + 1 (right); a train running -x
has its own axes turned by 180 degrees about z (its left wheel on the track's right rail,
lateral signs flipped: ttbpipe.simulation.loop.placed_track_kinematics); its wheelset
positions in the loop are taken along its direction of travel (x = -s). The run's length and
time step are the first train's; the second must stay on the rails for all of it. Each train
is a setup of its own (:class:`CoupledSetup`, the second in ``setup.second``) sharing the
structure, the step and the static state.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import logging
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..irregularity.track_input import Irregularity, build_irregularity
from ..structure.rail_mesh import RailMesh, no_rails, rail_inverse_masses, rail_mesh
from ..structure.static import static_solver
from ..structure.window import DEFAULT_TRACK_WINDOW_M
from ..timestepping.limits import (contact_time_step_limit, coupled_time_step_limit,
                                   resolve_time_step)
from ..vehicle.contact import ContactGeometry, build_geometry
from ..vehicle.dynamics import VehicleArrays, vehicle_arrays
from ..vehicle.kernels import RAIL_KIN_COLS
from ..vehicle.model import TrainModel, build_train_model
from ..vehicle.parameters import TrainParameters, train_from_config
from ..vehicle.curving import curve_arrays
from ..vehicle.static import solve_vehicle_static
from .loop import add_wheel_loads, placed_track_kinematics

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
    track_index: int = 0       # the train's track (rails 2k, 2k + 1)
    direction: int = 1         # 1: runs +x, -1: runs -x (its axes turned about z)
    second: Any = None         # the second train's CoupledSetup in a two-train run
    label: str = ""            # its columns' and indices' prefix ("train2_"; "" for the first)
    track_window_m: float | None = None   # approach track moving near the train (None: all)

    @property
    def n_spans(self) -> int:
        return 0 if self.structure is None else len(self.structure.spans)

    @property
    def velocity(self) -> float:
        """The train's velocity along x (m/s; negative running -x)."""
        return self.direction * self.speed

    @property
    def wheelset_x0(self) -> np.ndarray:
        """x (m) of every wheelset at t = 0, in the model's order."""
        return self.x_lead0 + self.direction * self.model.wheelset_x


@dataclass
class StaticTrain:
    """A train in the static solve: its model, contact, speed, track input, wheelset positions
    along its direction of travel (``ws_s``; x = direction s) and placement (left rail of its
    track, direction), and the curve terms (None: tangent track)."""

    model: Any
    geom: Any
    speed: float
    irregularity: Irregularity
    ws_s: np.ndarray
    rail0: int = 0
    direction: int = 1
    curve: Any = None


def _rail_kin_at(mesh, disp, train: StaticTrain) -> np.ndarray:
    rail_kin = np.zeros((train.ws_s.size, 2, RAIL_KIN_COLS))
    placed_track_kinematics(mesh, train.irregularity, disp, np.zeros_like(disp), train.ws_s,
                            0.0, rail_kin, train.rail0, train.direction)
    return rail_kin


def _vehicle_static(mesh, disp, train: StaticTrain):
    rail_kin = _rail_kin_at(mesh, disp, train)
    return solve_vehicle_static(train.model, train.geom, train.speed, rail_kin,
                                curve=train.curve, x_lead=float(train.ws_s[0]))


def static_equilibrium_trains(trains: list[StaticTrain], mesh, structure_static,
                              tol_load: float = 1e-3, max_iter: int = 30):
    """Trains + structure static state: fixed point between each train's vehicle Newton solve
    and the structure's linear static solve under all their wheel loads (the rails are ~100x
    stiffer than the primary suspension, so it converges in a few iterations; it stops when no
    wheel load changes by more than ``tol_load`` N). Returns ([(q, wheel, v) per train], disp,
    iterations); v is zero except the wheelsets' steady spin rates."""
    n_s = 0 if structure_static is None else int(structure_static.n)
    disp = np.zeros(n_s)
    prev = None
    for it in range(1, max_iter + 1):
        states = [_vehicle_static(mesh, disp, tr) for tr in trains]
        if structure_static is None:
            return states, disp, it
        force = np.zeros(n_s)
        for tr, (_, wheel, _) in zip(trains, states):
            # as the loop (ttbpipe.simulation.loop)
            add_wheel_loads(mesh, wheel, tr.ws_s, tr.rail0, tr.direction,
                            tr.geom.zones is not None, force)
        disp = structure_static.solve(force)
        loads = np.concatenate([wheel[:, :, 2].ravel() for _, wheel, _ in states])
        if prev is not None and np.max(np.abs(loads - prev)) < tol_load:
            return [_vehicle_static(mesh, disp, tr) for tr in trains], disp, it
        prev = loads
    raise RuntimeError(f"train-structure static equilibrium did not converge in {max_iter} "
                       "iterations; check the structure supports and the suspension stiffness")


def static_equilibrium(model, geom, speed, mesh, structure_static, irr, ws_x,
                       tol_load: float = 1e-3, max_iter: int = 30, curve=None):
    """Train + structure static state of one train on rails 0, 1 running +x
    (:func:`static_equilibrium_trains`). Returns (q, v, disp, wheel, iterations). ``curve``:
    the track layout's terms (ttbpipe.vehicle.curving), the steady state on the curve at the
    train's start."""
    states, disp, it = static_equilibrium_trains(
        [StaticTrain(model, geom, speed, irr, np.asarray(ws_x, float), curve=curve)], mesh,
        structure_static, tol_load, max_iter)
    q, wheel, v = states[0]
    return q, v, disp, wheel, it


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


def _kept_per_process(table: dict[str, Any], kept: int, key_data: Any, build) -> Any:
    """``build()`` once per process and configuration ``key_data`` (its canonical JSON is the
    key of ``table``); the last ``kept`` results are kept, so that a batch alternating between
    two stays cached. Configuration that is not plain JSON data is built and not kept."""
    try:
        key = json.dumps(key_data, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError):
        return build()
    if key not in table:
        value = build()
        while len(table) >= kept:
            table.pop(next(iter(table)))
        table[key] = value
    return table[key]


#: The last nominal structures built in this process, by their configuration
#: (:func:`_nominal_structure`).
_NOMINAL_STRUCTURES: dict[str, Any] = {}
_NOMINAL_STRUCTURES_KEPT = 2


def _nominal_structure(config: Mapping[str, Any], layout: Any):
    """The structure of a ``structure:`` section and a layout, without random properties:
    built once per process and configuration. Samples that share it (every scenario without
    property fields) share one model, and with it its matrices, stability analysis and static
    factorisation (:meth:`ttbpipe.structure.StructureModel.derived`): a model depends on its
    configuration alone and is not changed after assembly, so a shared model gives the results
    of a fresh one bit for bit (tests/test_structure_reuse.py)."""
    from ..structure import build_structure
    from ..vehicle.curving import cant_knots, plan_knots

    # a copy of the configuration: a caller editing its dict later does not change the model
    return _kept_per_process(
        _NOMINAL_STRUCTURES, _NOMINAL_STRUCTURES_KEPT, [config, layout],
        lambda: build_structure(copy.deepcopy(dict(config)), cant=cant_knots(layout),
                                plan=plan_knots(layout)))


#: The last trains built in this process, by their configuration (:func:`_train_model`).
_TRAINS: dict[str, tuple[TrainParameters, TrainModel]] = {}
_TRAINS_KEPT = 2


def _train_model(config: Mapping[str, Any]) -> tuple[TrainParameters, TrainModel]:
    """A ``train:`` section's parameters and assembled model, built once per process and
    configuration: every sample of a study runs the same train, and assembling its suspension
    matrices element by element took about a tenth of a sample's work outside the time loop.
    The model is not changed after assembly (its arrays are read, never written), so a shared
    one gives the results of a fresh one bit for bit (tests/test_structure_reuse.py)."""
    def build() -> tuple[TrainParameters, TrainModel]:
        params = train_from_config(dict(config))
        return params, build_train_model(params)

    return _kept_per_process(_TRAINS, _TRAINS_KEPT, config, build)


def nominal_structure(case: Mapping[str, Any]):
    """The structure a case runs on before random properties: its ``structure:`` section on
    its ``simulation.layout`` (the cant and the curvature in plan of its curves), shared within
    a process (:func:`_nominal_structure`). Monitors placed from it (the deck under a curved
    track) sit where the run's structure has them."""
    layout = (case.get("simulation") or {}).get("layout")
    return _nominal_structure(case.get("structure") or {}, layout)


def _structure(case: Mapping[str, Any], factors: Mapping[str, np.ndarray] | None):
    from ..structure import apply_factors
    from ..structure.random_properties import property_factors

    structure = nominal_structure(case)
    if factors is None:
        factors = property_factors(case.get("properties"), structure)
    if factors:
        structure = apply_factors(structure, dict(factors))
    return structure


def _run_span(sim: Mapping[str, Any], structure, train_len: float, margin: float,
              direction: int, where: str = "simulation") -> tuple[float, float]:
    """(leading wheelset at t = 0, at the end) of a train on the structure's rails: the
    section's ``start_x_m`` / ``end_x_m``, by default the whole train inside the rails
    ``margin`` from the end it enters at and the leading wheelset ``margin`` before the other."""
    x_min, x_max = structure.rail_x_range
    start, end = sim.get("start_x_m"), sim.get("end_x_m")
    if direction > 0:
        x_lead0 = float(start) if start is not None else x_min + margin + train_len
        x_end = float(end) if end is not None else x_max - margin
        outside = x_lead0 - train_len < x_min or x_end > x_max
    else:
        x_lead0 = float(start) if start is not None else x_max - margin - train_len
        x_end = float(end) if end is not None else x_min + margin
        outside = x_lead0 + train_len > x_max or x_end < x_min
    if outside:
        raise ValueError(
            f"the train ({train_len:.1f} m between end wheelsets) must stay on the modelled rails "
            f"[{x_min:.1f}, {x_max:.1f}] m but runs with its leading wheelset from {x_lead0:.1f} "
            f"to {x_end:.1f} m; lengthen the structure's approaches or set {where}.start_x_m/end_x_m")
    return x_lead0, x_end


def _placement(sim: Mapping[str, Any], where: str, default_track: int = 0,
               default_direction: int = 1) -> tuple[int, int]:
    track_index = int(sim.get("track_index", default_track))
    direction = int(sim.get("direction", default_direction))
    if direction not in (1, -1):
        raise ValueError(f"{where}.direction: {direction}; expected 1 (+x) or -1 (-x)")
    return track_index, direction


def _wheel_range(x_lead0: float, x_end: float, train_len: float, direction: int,
                 reach: float) -> tuple[float, float]:
    """Chainage range the wheels of a train cover in a run (``reach``: the distance past the
    end the output rows reach), 1 m margins."""
    if direction > 0:
        return x_lead0 - train_len - 1.0, x_end + reach + 1.0
    return x_end - reach - 1.0, x_lead0 + train_len + 1.0


def _track_window_m(sim: Mapping[str, Any], second_cfg) -> float | None:
    """``simulation.track_window_m`` (:mod:`ttbpipe.structure.window`); a two-train run moves
    the whole track (its loop takes no window)."""
    margin = sim.get("track_window_m", DEFAULT_TRACK_WINDOW_M)
    if margin is None:
        return None
    if second_cfg is not None:
        log.warning("simulation.track_window_m: %s m not applied: a two-train run moves the "
                    "whole track", margin)
        return None
    return float(margin)


def _time_step(sim, model, geom, speed, structure, mesh, packed, propose_auto):
    """(dt, limits) of one train on the structure (every stability limit, resolve_time_step)."""
    limits = contact_time_step_limit(model, geom, speed,
                                     *rail_inverse_masses(mesh, packed.inv_mass))
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
    return dt, limits


def _warn_irregularity(irr_info: dict, speed: float, label: str = "") -> None:
    from .diagnosis import PLAUSIBLE_D1_PEAK_MM
    if (irr_info["contact_demand_ratio"] > 1.0 or max(irr_info["peak_vertical_d1_mm"],
                                                      irr_info["peak_lateral_d1_mm"]) > PLAUSIBLE_D1_PEAK_MM):
        log.warning("%sirregularity: peak %.1f mm vertical, %.1f mm lateral in 3-25 m (plausible at "
                    "most %.0f mm); its curvature asks for %.1f times the wheel acceleration "
                    "contact can give at %.0f km/h: expect loss of wheel-rail contact", label,
                    irr_info["peak_vertical_d1_mm"], irr_info["peak_lateral_d1_mm"],
                    PLAUSIBLE_D1_PEAK_MM, irr_info["contact_demand_ratio"], speed * 3.6)


def prepare(case: Mapping[str, Any], *, track: Irregularity | pd.DataFrame | None = None,
            factors: Mapping[str, np.ndarray] | None = None,
            propose_auto: bool = False,
            second_track: Irregularity | pd.DataFrame | None = None) -> CoupledSetup:
    """Build the train, contact, structure, track input and the static state of a case.

    ``track``: the track input in memory (an :class:`Irregularity`, used as it is, or a profile
    table, faded in like a file's), instead of the case's ``irregularity`` source; ``factors``:
    the structure's property factors in memory, instead of its ``properties`` section.
    ``propose_auto``: a refused time step's message may offer ``time_step_s: auto`` besides the
    concrete step (``ttbpipe simulate``, one case). Off by default: in a study every sample must
    use the same step (one time grid), so ``auto``, which takes each sample's own limit, is
    not a remedy there. ``auto`` itself is accepted either way (ttbpipe.timestepping.limits).
    ``second_track``: the track input of the second train's track (``second_train``; default:
    from its ``irregularity`` entry, ``shared``: ``track`` again).
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
    train, model = _train_model(train_cfg)
    geom = build_geometry(train.contact)
    track_kind = sim.get("track", "structure")
    margin = float(sim.get("margin_m", 5.0))
    train_len = -float(model.wheelset_x.min())
    track_index, direction = _placement(sim, "simulation")
    second_cfg = case.get("second_train")
    curve = curve_arrays(model, sim.get("layout"), direction)
    if track_kind == "rigid":
        if track_index != 0 or direction != 1 or second_cfg is not None:
            raise ValueError("simulation.track: rigid has one track run +x by one train; "
                             "track_index, direction and second_train need the structure")
        structure, packed = None, rigid_packed()
        mesh = no_rails(train.contact.rail_head_height)
        x_lead0 = float(sim.get("start_x_m") or 0.0)
        x_end = float(sim.get("end_x_m") or (x_lead0 + float(sim.get("rigid_length_m", 200.0))))
        monitors = None
    elif track_kind == "structure":
        from ..structure.monitors import compile_monitors, default_monitors

        structure = _structure(case, factors)
        if not 0 <= track_index < structure.n_tracks:
            raise ValueError(f"simulation.track_index: {track_index}; the structure has "
                             f"{structure.n_tracks} track(s) (structure.layout.tracks), 0-based")
        packed = structure.packed
        mesh = rail_mesh(packed, structure.rail_head_height_m)
        x_lead0, x_end = _run_span(sim, structure, train_len, margin, direction)
        specs = case.get("monitors") or default_monitors(structure)
        try:   # compiled once per model and list (samples sharing a structure share its rows)
            key = ("monitors", json.dumps(specs, sort_keys=True, allow_nan=False))
        except (TypeError, ValueError):      # not plain data: compiled for this run alone
            key = None
        monitors = (compile_monitors(structure, specs) if key is None else
                    structure.derived(key, lambda: compile_monitors(structure, specs)))
    else:
        raise ValueError(f"simulation.track: {track_kind!r}; expected structure | rigid")
    if geom.zones is not None:
        # two-point contact: the vertical loads' lever about the rail's shear centre uses the
        # structure's head height, as the lateral force's (ttbpipe.structure.rail_mesh)
        geom = dataclasses.replace(geom, rail_head_height=float(mesh.head_height))
    if sim.get("duration_s") is not None:
        x_end = x_lead0 + direction * speed * float(sim["duration_s"])
        if structure is not None and not (structure.rail_x_range[0] <= x_end
                                          <= structure.rail_x_range[1]):
            raise ValueError(f"simulation.duration_s={sim['duration_s']} s takes the leading wheelset "
                             f"to x = {x_end:.1f} m, beyond the rails; shorten it")
    if direction * (x_end - x_lead0) <= 0:
        raise ValueError(f"simulation: end_x_m {x_end} must be beyond start_x_m {x_lead0} in "
                         "the direction of travel")
    dt, limits = _time_step(sim, model, geom, speed, structure, mesh, packed, propose_auto)
    second = None
    if second_cfg is not None:
        second = _second_train(dict(second_cfg), structure, train_cfg, speed, track_index,
                               direction, margin)
        second["geom"] = dataclasses.replace(second["geom"], rail_head_height=float(
            mesh.head_height)) if second["geom"].zones is not None else second["geom"]
        dt2, second["limits"] = _time_step(sim, second["model"], second["geom"],
                                           second["speed"], structure, mesh, packed,
                                           propose_auto)
        dt = min(dt, dt2)
    if sim.get("output_every") is not None:
        out_every = int(sim["output_every"])
    else:
        out_every = max(1, int(round(float(sim.get("output_interval_s", 1.0e-3)) / dt)))
    duration = direction * (x_end - x_lead0) / speed
    n_steps = int(np.ceil(duration / dt / out_every)) * out_every
    irr_cfg = case.get("irregularity")
    lo, hi = _wheel_range(x_lead0, x_end, train_len, direction, speed * dt * out_every)
    if second is not None:
        second["x_end"] = second["x_lead0"] + second["direction"] * second["speed"] * n_steps * dt
        _check_on_rails(second, structure)
        lo2, hi2 = _wheel_range(second["x_lead0"], second["x_end"], second["train_len"],
                                second["direction"], second["speed"] * dt * out_every)
        lo, hi = min(lo, lo2), max(hi, hi2)
    if isinstance(track, Irregularity):
        irr = track
    else:
        irr = build_irregularity(irr_cfg, lo, hi, x_lead0, profile=track, direction=direction)
    trains = [StaticTrain(model, geom, speed, irr, direction * x_lead0 + model.wheelset_x,
                          2 * track_index, direction, curve)]
    if second is not None:
        shared = second["irregularity"] == "shared"
        source = track if second_track is None and shared else second_track
        if isinstance(source, Irregularity):
            second["irr"] = source
        else:
            second["irr"] = build_irregularity(irr_cfg if shared else second["irregularity"],
                                               lo, hi, second["x_lead0"], profile=source,
                                               direction=second["direction"])
        # both tracks of a double-track deck take the layout's radius and cant (each track's
        # own radius differs by half the spacing: 2.5 m in 4000 m, 0.06 % of V^2/R)
        trains.append(StaticTrain(second["model"], second["geom"], second["speed"],
                                  second["irr"], second["direction"] * second["x_lead0"]
                                  + second["model"].wheelset_x, 2 * second["track_index"],
                                  second["direction"],
                                  curve_arrays(second["model"], sim.get("layout"),
                                               second["direction"])))
    sstatic = static_solver(structure) if structure is not None else None
    states, disp0, iters = static_equilibrium_trains(trains, mesh, sstatic)
    common = dict(dt=dt, n_steps=n_steps, out_every=out_every, structure=structure,
                  packed=packed, mesh=mesh, monitors=monitors, disp0=disp0,
                  static_iterations=iters, propose_auto=propose_auto,
                  track_window_m=_track_window_m(sim, second_cfg))

    def train_setup(tr, state, train_params, limits, x0, track_i, irr_config, label):
        from .diagnosis import irregularity_indicators

        q0, wheel0, v0 = state
        f_const = tr.model.gravity_force + tr.model.coupler_stiffness @ q0
        creep_relax = (limits["lateral_creep_inverse_mass_1_kg"] * dt / tr.speed
                       if limits["lateral_creep"] == "semi_implicit" else 0.0)
        irr_info = irregularity_indicators(tr.irregularity, tr.speed, tr.model)
        _warn_irregularity(irr_info, tr.speed, label)
        return CoupledSetup(
            train=train_params, model=tr.model, geom=tr.geom, speed=tr.speed, x_lead0=x0,
            irregularity=tr.irregularity,
            vehicle=vehicle_arrays(tr.model, tr.geom, f_const, tr.direction * x0, tr.curve),
            q0=q0, v0=v0, static_wheel=wheel0, dt_limits=limits, creep_relax=creep_relax,
            irregularity_info=irr_info, irregularity_config=dict(irr_config or {}),
            track_index=track_i, direction=tr.direction, label=label, **common)

    setup = train_setup(trains[0], states[0], train, limits, x_lead0, track_index, irr_cfg, "")
    if second is not None:
        irr2 = irr_cfg if second["irregularity"] == "shared" else second["irregularity"]
        setup.second = train_setup(trains[1], states[1], second["train"], second["limits"],
                                   second["x_lead0"], second["track_index"], irr2, "train2_")
        setup.second.monitors = None          # the structure's monitors are the first's
    return setup


def _second_train(cfg: dict, structure, train_cfg: dict, speed: float, track_index: int,
                  direction: int, margin: float) -> dict:
    """The ``second_train`` section resolved: its train, model, contact, speed, placement and
    start (its end follows from the run's duration, :func:`prepare`)."""
    where = "second_train"
    if structure is None or structure.n_tracks < 2:
        raise ValueError(f"{where}: a second train needs a double-track deck "
                         "(structure.layout.tracks: 2)")
    unknown = sorted(set(cfg) - {"train", "track_index", "direction", "speed_kmh", "start_x_m",
                                  "irregularity"})
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}")
    t_index, t_dir = _placement(cfg, where, default_track=1 - track_index,
                                default_direction=-direction)
    if not 0 <= t_index < structure.n_tracks or t_index == track_index:
        raise ValueError(f"{where}.track_index: {t_index}; it runs on the other track "
                         f"({1 - track_index}) of the double-track deck")
    tcfg = dict(cfg.get("train") or train_cfg)
    v_kmh = cfg.get("speed_kmh", speed * 3.6)
    if not float(v_kmh) > 0:
        raise ValueError(f"{where}.speed_kmh must be positive, got {v_kmh}")
    params, model = _train_model(tcfg)
    train_len = -float(model.wheelset_x.min())
    x_lead0, _ = _run_span({"start_x_m": cfg.get("start_x_m")}, structure, train_len, margin,
                           t_dir, where)
    irregularity = cfg.get("irregularity", "shared")
    if not (irregularity == "shared" or isinstance(irregularity, Mapping)):
        raise ValueError(f"{where}.irregularity: shared or an irregularity section, got "
                         f"{irregularity!r}")
    return {"train": params, "model": model, "geom": build_geometry(params.contact),
            "speed": float(v_kmh) / 3.6, "track_index": t_index, "direction": t_dir,
            "x_lead0": x_lead0, "train_len": train_len, "irregularity": irregularity}


def _check_on_rails(second: dict, structure) -> None:
    x_min, x_max = structure.rail_x_range
    x0, x1, d, length = (second["x_lead0"], second["x_end"], second["direction"],
                         second["train_len"])
    rear0 = x0 - d * length
    if not all(x_min <= x <= x_max for x in (x0, x1, rear0)):
        raise ValueError(f"second_train: its leading wheelset runs from {x0:.1f} to {x1:.1f} m "
                         f"during the run, its rear starts at {rear0:.1f} m, but the rails are "
                         f"[{x_min:.1f}, {x_max:.1f}] m; move second_train.start_x_m, lower its "
                         "speed or lengthen the approaches")



def diagnosis_limits(setup: CoupledSetup) -> dict:
    """The setup's dt_limits, with the structure and coupled limits computed now if the case
    skipped them (``check_time_step: false``): a diagnosis weighs the step against all."""
    limits = dict(setup.dt_limits)
    if setup.structure is not None and "dt_structure_s" not in limits:
        limits.update(coupled_time_step_limit(setup.structure, limits))
    return limits
