"""Fingerprints of results, to show that a change leaves existing results bit for bit unchanged.

Prints SHA-256 prefixes of the raw bytes of: the packed arrays of a structure (2 x 32 m spans,
ballasted approaches, track 2.5 m off the axis, deck edges), a moving-load run on it (2-car
axle train, 0.3 s), the coupled reference case shortened to 0.3 s (its table, column names and
summary without wall times), and a 1-car coupled run with two-point contact (S1002 / 60E1,
0.15 s). Run it on two trees and compare the output:

    PYTHONPATH=<tree>/src NUMBA_NUM_THREADS=1 python benchmarks/result_fingerprints.py > fp.json
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import yaml

from ttbpipe.simulation.coupled import run_coupled
from ttbpipe.structure import build_structure
from ttbpipe.structure.moving_loads import build_loads, simulate

ROOT = Path(__file__).resolve().parents[1]


def digest(a) -> str:
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()[:16]


def main() -> None:
    out = {}
    cfg = {"layout": {"approach_length_m": 30.0, "spans_m": [32.0, 32.0],
                      "approach_track": "ballasted"},
           "girder": {"track_offset_m": 2.5, "deck_width_m": 12.0}}
    m = build_structure(cfg)
    out["packed"] = digest(np.concatenate([np.asarray(v, float).ravel() for v in m.packed]))
    loads = build_loads({"speed_kmh": 300, "axle_train": {"cars": 2, "wheel_load_N": 70000,
                                                          "front_x0_m": 40}}, m)
    df, _ = simulate(m, loads, 1e-4, 0.3, output_every=10)
    out["moving"] = digest(df.to_numpy())
    out["moving_cols"] = digest(np.array(list(df.columns), dtype="U64"))
    case = yaml.safe_load((ROOT / "config" / "reference_case.yaml").read_text())
    case["simulation"]["duration_s"] = 0.3
    case["structure"]["girder"] = {"track_offset_m": 2.5, "deck_width_m": 12.0}
    table, s = run_coupled(case)
    out["coupled"] = digest(table.to_numpy())
    out["coupled_cols"] = digest(np.array(list(table.columns), dtype="U64"))
    kept = {k: v for k, v in s.items() if "wall" not in k and k != "dt_limits"}
    out["summary"] = hashlib.sha256(json.dumps(kept, sort_keys=True, default=str)
                                    .encode()).hexdigest()[:16]
    two_point = {
        "structure": {"layout": {"approach_length_m": 40.0, "spans_m": [32.0],
                                 "approach_track": "slab"}, "girder": {"track_offset_m": 2.5}},
        "train": {"composition": ["trailer"], "contact": {
            "profile": "profiles", "wheel_profile": "s1002", "rail_profile": "60e1",
            "rail_inclination": "1:40", "gauge_m": 1.435, "flange_back_m": 1.360,
            "contact_points": 2}},
        "simulation": {"speed_kmh": 250.0, "time_step_s": 1e-4, "duration_s": 0.15},
        "irregularity": {"source": "synthetic", "seed": 3}}
    table2, _ = run_coupled(two_point)
    out["coupled_two_point"] = digest(table2.to_numpy())
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
