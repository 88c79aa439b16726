"""EN 1991-2 dynamic analysis of a simply supported span under moving axle loads.

The span model (:func:`span_model`) is the study's girder (its E, I, mass, torsion, damping
rule, track offset) as one simply supported span on point supports (``bearing.rigid``), without
the track's stiffness, with the track's mass (slab and rails per metre) added to the girder's:
the model of EN 1991-2 6.4.6 for a moving-load analysis. Damping: EN 1991-2 Table 6.6 by span
and construction, plus eq. 6.13's additional damping for spans below 30 m when
``additional_damping`` is on (6.4.6.3.1(3): moving loads carry no vehicle-bridge interaction).

Each train (ttbpipe.trains library) crosses the span at every speed of the sweep as constant
moving axle loads on the track's centre line (:func:`ttbpipe.structure.moving_loads.simulate`,
the same explicit loop and recorder as every ttbpipe run). Per speed the run gives:

* the peak deck acceleration at the track (3/8, 1/2, 5/8 of the span and the quarter points),
  filtered as EN 1990 A2.4.4.2.1 prescribes (frequencies up to max(30 Hz, 1.5 n0, n3):
  :func:`ttbpipe.assessment.en1990.deck_filter`), and its raw value;
* the peak midspan deflection and the peak end rotation (the girder's slope at the supports);
* the static deflection under the same train (the largest midspan deflection of the train
  standing anywhere on the span, from the span's own static solve) and the dynamic
  amplification y_dyn / y_stat.
"""

from __future__ import annotations

import copy
import logging
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..assessment.en1990 import band_cutoff_hz, deck_filter
from ..stats.limits import DECK_VERTICAL_ACC_M_S2
from ..structure import build_structure
from ..structure import properties as structure_properties
from ..structure.moving_loads import build_loads, simulate
from ..structure.static import static_solver
from ..trains import get_train

log = logging.getLogger(__name__)

__all__ = ["SpanModel", "span_model", "sweep_train", "track_mass_per_m", "MONITOR_POSITIONS"]

#: Deck points (fractions of the span) whose peak acceleration enters the envelope.
MONITOR_POSITIONS = (0.25, 0.375, 0.5, 0.625, 0.75)
#: Free vibration after the last axle has left the span (s): the peak of a resonant train can
#: come just after it.
FREE_VIBRATION_S = 0.5
#: Largest time step of the sweep (s): 20 samples per period at 100 Hz, above the acceleration
#: band of every span EN 1991-2 covers (max(30 Hz, 1.5 n0, n3)).
MAX_TIME_STEP_S = 5.0e-4


def track_mass_per_m(structure: Mapping[str, Any]) -> float:
    """Mass of the track on the deck per metre (kg/m): the slab (density x width x thickness)
    and both rails; 0 without a track (``layout.bridge_track: none``)."""
    cfg = structure_properties.resolve(structure)
    if cfg["layout"]["bridge_track"] == "none":
        return 0.0
    slab, rail = cfg["slab"], cfg["rail"]
    slab_mass = (float(slab["density_kg_m3"]) * float(slab["width_m"])
                 * float(slab["thickness_m"])) if cfg["layout"]["bridge_track"] == "slab" else 0.0
    return slab_mass + 2.0 * float(rail["mass_kg_m"])


@dataclass
class SpanModel:
    """A simply supported span ready for moving-load runs."""

    span_m: float
    model: Any
    n0_hz: float
    n3_hz: float
    torsion_hz: float
    damping_ratio: float
    mass_kg_m: float
    track_offset_m: float
    track_type: str               # ballasted | ballastless (EN 1990 A2.4.4.2.1)

    @property
    def acceleration_limit_m_s2(self) -> float:
        return float(DECK_VERTICAL_ACC_M_S2[self.track_type])

    @property
    def band_hz(self) -> float:
        return band_cutoff_hz(self.n0_hz, self.n3_hz)


def span_model(structure: Mapping[str, Any] | None, span_m: float, *,
               additional_damping: bool = False) -> SpanModel:
    """The study's girder as one simply supported span of ``span_m`` (module docstring)."""
    cfg = structure_properties.resolve(structure)
    girder = copy.deepcopy(cfg["girder"])
    track_mass = track_mass_per_m(structure)
    girder["mass_kg_m"] = float(girder["mass_kg_m"]) + track_mass
    girder["additional_damping"] = bool(additional_damping)
    model = build_structure({"layout": {"approach_length_m": 0.0, "spans_m": [float(span_m)],
                                        "bridge_track": "none"},
                             "girder": girder, "bearing": {"rigid": True}})
    red = model.spans[0]
    vertical, _, torsion = red.mode_frequencies_hz
    if vertical.size < 3:
        raise ValueError(f"span {span_m:g} m: fewer than three vertical modes below "
                         f"girder.max_mode_frequency_hz = {girder['max_mode_frequency_hz']:g} Hz;"
                         " EN 1990 A2.4.4.2.1 needs n3: raise the cut-off")
    bridge_track = cfg["layout"]["bridge_track"]
    track_type = "ballasted" if bridge_track == "ballasted" else "ballastless"
    return SpanModel(span_m=float(span_m), model=model, n0_hz=float(vertical[0]),
                     n3_hz=float(vertical[2]), torsion_hz=float(torsion[0]),
                     damping_ratio=float(red.damping_ratio), mass_kg_m=float(girder["mass_kg_m"]),
                     track_offset_m=float(girder["track_offset_m"]), track_type=track_type)


def _monitor_specs(span: SpanModel) -> list[dict]:
    specs = [{"name": f"deck_{round(1000 * f):04d}", "kind": "girder", "span": 0,
              "position": f, "lateral_offset_m": span.track_offset_m, "directions": ["z"],
              "quantities": ["displacement", "acceleration"]} for f in MONITOR_POSITIONS]
    specs += [{"name": f"end_{e}", "kind": "girder", "span": 0, "position": p,
               "directions": ["slope"], "quantities": ["displacement"]}
              for e, p in (("a", 0.0), ("b", 1.0))]
    return specs


def static_midspan_deflection_m(span: SpanModel, train_name: str, step_m: float = 0.25) -> float:
    """Largest midspan deflection (m, downward positive) of the train standing on the span:
    the span's static solve for unit loads at the grid positions, combined over the axles."""
    model = span.model
    red = model.spans[0]
    o = model.dof_info["span_dof0"][0]
    static = static_solver(model)
    mid_row = red.rows_at(0.5 * span.span_m)[0]
    xs = np.arange(0.0, span.span_m + 1e-9, step_m)
    influence = np.empty(xs.size)              # midspan deflection per downward unit load
    for k, x in enumerate(xs):
        force = np.zeros(model.n_dof)
        rz, _, rr = red.rows_at(x)
        force[o:o + red.n] = -(rz + span.track_offset_m * rr)
        influence[k] = -(mid_row @ static.solve(force)[o:o + red.n])
    train = get_train(train_name)
    best = 0.0
    # front axle at every grid point from 0 to L + train length
    for front in np.arange(0.0, span.span_m + train.length_m + 1e-9, step_m):
        x = front - train.positions_m
        on = (x >= 0.0) & (x <= span.span_m)
        if on.any():
            best = max(best, float(np.interp(x[on], xs, influence) @ train.axle_loads_N[on]))
    return best


def sweep_train(span: SpanModel, train_name: str, speeds_kmh: Sequence[float], *,
                time_step_s: float | None = None) -> pd.DataFrame:
    """One row per speed: peaks of ``train_name`` crossing ``span`` (module docstring)."""
    model = span.model
    train = get_train(train_name)
    dt = min(MAX_TIME_STEP_S, 0.9 * model.stable_time_step()) if time_step_s is None \
        else float(time_step_s)
    y_static = static_midspan_deflection_m(span, train_name)
    band = deck_filter(span.n0_hz, span.n3_hz)
    specs = _monitor_specs(span)
    rows = []
    for v_kmh in speeds_kmh:
        v = float(v_kmh) / 3.6
        loads = build_loads({"target": "girder",
                             "axle_train": {"train": train_name, "front_x0_m": 0.0,
                                            "speed_kmh": float(v_kmh)}}, model)
        duration = (span.span_m + train.length_m) / v + FREE_VIBRATION_S
        table, info = simulate(model, loads, dt, duration, monitor_specs=specs, check_dt=False)
        acc_cols = [f"deck_{round(1000 * f):04d}_z_acc_m_s2" for f in MONITOR_POSITIONS]
        acc = table[acc_cols].to_numpy()
        filtered = band.apply(acc, dt)
        mid = table["deck_0500_z_disp_mm"].to_numpy() * 1e-3
        ends = table[["end_a_slope_mrad", "end_b_slope_mrad"]].to_numpy() * 1e-3
        y_dyn = float(np.max(-mid))
        rows.append({
            "train": train_name, "span_m": span.span_m, "speed_kmh": float(v_kmh),
            "deck_acc_m_s2": float(np.max(np.abs(filtered))),
            "deck_acc_raw_m_s2": float(np.max(np.abs(acc))),
            "deflection_mm": 1e3 * y_dyn,
            "static_deflection_mm": 1e3 * y_static,
            "dynamic_amplification": y_dyn / y_static if y_static > 0 else float("nan"),
            "end_rotation_mrad": 1e3 * float(np.max(np.abs(ends))),
            "time_step_s": dt, "cpu_s": float(info["cpu_s"]),
        })
    return pd.DataFrame(rows)
