"""A moving-load case on the structure (no vehicle): config dict -> (monitor table, summary)."""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..structure import apply_factors, build_structure
from ..structure.moving_loads import build_loads, default_duration, simulate
from ..structure.random_properties import property_factors
from ..threads import pinned

log = logging.getLogger(__name__)


@pinned
def run_moving_loads(case: Mapping[str, Any], *, factors: Mapping[str, np.ndarray] | None = None
                     ) -> tuple[pd.DataFrame, dict]:
    """Build the structure, apply property factors (``factors`` in memory, else the case's
    ``properties:`` section), run the moving loads; (table, summary)."""
    model = build_structure(case.get("structure") or {})
    if factors is None:
        factors = property_factors(case.get("properties"), model)
    if factors:
        model = apply_factors(model, dict(factors))
    loads = build_loads(case["loads"], model)
    sim = dict(case.get("simulation") or {})
    dt = sim.get("time_step_s", 1.0e-4)
    if dt == "auto":
        dt = model.stable_time_step()
    duration = float(sim.get("duration_s") or default_duration(model, loads))
    table, info = simulate(model, loads, float(dt), duration, case.get("monitors"),
                           output_every=int(sim.get("output_every", 10)),
                           check_dt=bool(sim.get("check_time_step", True)))
    summary = {"n_dof": info["n_dof"], "n_steps": info["n_steps"], "time_step_s": info["dt_s"],
               "duration_s": duration, "n_loads": loads.n, "wall_s": info["wall_s"],
               "factored_parameters": sorted(factors or {})}
    if "stability" in info:
        summary["stable_time_step_limit_s"] = float(info["stability"]["dt_limit_s"])
    return table, summary
