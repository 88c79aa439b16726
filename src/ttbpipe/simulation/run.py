"""Run a moving-load case on the structure: config dict -> (monitor table, summary)."""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..structure import apply_factors, build_structure, carrier_positions
from ..structure.assembly import CARRIER_PARAMETERS, PARAMETER_CARRIER
from ..structure.moving_loads import build_loads, default_duration, simulate
from ..threads import pinned

log = logging.getLogger(__name__)


def property_factors(props_cfg: Mapping[str, Any] | None, model) -> dict[str, np.ndarray]:
    """Factors per carrier from the case's ``properties:`` section ({} if none)."""
    if not props_cfg:
        return {}
    factors: dict[str, np.ndarray] = {}
    positions = carrier_positions(model)
    if "field_samples" in props_cfg:
        from ..fields import load_field_factors

        fs = props_cfg["field_samples"]
        factors.update(load_field_factors(fs["path"], int(fs["sample_index"])))
        log.info("properties: %d parameters from %s sample %d", len(factors), fs["path"],
                 fs["sample_index"])
    if "independent" in props_cfg:
        ind = props_cfg["independent"]
        # SeedSequence([seed, index]): a sample's numbers depend only on seed and index
        rng = np.random.default_rng(np.random.SeedSequence([int(ind["seed"]),
                                                            int(ind.get("sample_index", 0))]))
        s = np.sqrt(np.log1p(float(ind["cov"]) ** 2))
        for name in sorted(CARRIER_PARAMETERS, key=str):
            for p in CARRIER_PARAMETERS[name]:
                n = positions[name].size
                draw = rng.lognormal(-0.5 * s * s, s, size=n)   # mean 1, drawn for every name
                if p in ind["parameters"]:
                    factors[p] = factors.get(p, 1.0) * draw
    for p, f in factors.items():
        n = positions[PARAMETER_CARRIER[p]].size
        if np.size(f) not in (n, 2 * n):
            raise ValueError(f"properties: {p} has {np.size(f)} factors but the structure has {n} "
                             f"{PARAMETER_CARRIER[p]} carriers; sample the fields at "
                             "ttbpipe.structure.carrier_positions(model)")
    return factors


@pinned
def run_moving_loads(case: Mapping[str, Any]) -> tuple[pd.DataFrame, dict]:
    """Build the structure, apply property factors, run the moving loads; (table, summary)."""
    model = build_structure(case.get("structure") or {})
    factors = property_factors(case.get("properties"), model)
    if factors:
        model = apply_factors(model, factors)
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
               "factored_parameters": sorted(factors)}
    if "stability" in info:
        summary["stable_time_step_limit_s"] = float(info["stability"]["dt_limit_s"])
    return table, summary
