"""What the track's curvature in plan on straight spans changes: one coupled run per variant.

    NUMBA_NUM_THREADS=1 python benchmarks/plan_curvature_effect.py RADIUS_M CANT_MM SPEED_KMH

The reference case's bridge (5 x 32 m, deck 12 m wide) under a 3-car train (motor, trailer,
motor) on a left-hand curve of RADIUS_M (80 m clothoids, 600 m arc from x = 120 m, so the whole
bridge is on the arc) with CANT_MM, at SPEED_KMH, on the reference case's irregularity. Three
runs: the girders' axes on the track's centre line everywhere (``straight``: the model before
the curvature in plan, the plan knots withheld), ``chord`` and ``split_versine``
(``structure.girder.placement_on_curves``, ttbpipe.structure.plan). Prints the largest |value|
of the girder and deck monitors of spans 1 and 3 and the ratios to ``straight``; the deck
monitors under the rails move with the track on a curve, so their ratios mix place and physics.
Results: docs/structure.md section 11.
"""
import copy
import sys
import time

import numpy as np
import yaml

import ttbpipe.simulation.setup as S
import ttbpipe.vehicle.curving as C
from ttbpipe.simulation.coupled import run_coupled


def main(radius: float, cant_mm: float, speed: float) -> None:
    base = yaml.safe_load(open("config/reference_case.yaml"))
    base["train"]["composition"] = ["motor", "trailer", "motor"]
    base["simulation"]["speed_kmh"] = speed
    base["simulation"]["layout"] = {"curves": [{"start_x_m": 40.0, "transition_m": 80.0,
        "length_m": 600.0, "radius_m": radius, "cant_mm": cant_mm, "direction": "left"}]}
    base["structure"]["girder"] = {"deck_width_m": 12.0}
    real_plan = C.plan_knots
    rows = {}
    for variant in ("straight", "chord", "split_versine"):
        case = copy.deepcopy(base)
        if variant != "straight":
            case["structure"]["girder"]["placement_on_curves"] = variant
        C.plan_knots = (lambda layout: None) if variant == "straight" else real_plan
        S._NOMINAL_STRUCTURES.clear()
        t = time.perf_counter()
        table, summary = run_coupled(case)
        cols = [c for c in table.columns if ("deck" in c or "girder" in c) and ("acc" in c or "disp" in c)]
        rows[variant] = {c: float(np.abs(table[c]).max()) for c in cols}
        print(variant, f"{time.perf_counter()-t:.1f} s", flush=True)
    C.plan_knots = real_plan
    keys = sorted(rows["straight"])
    print(f"R {radius} m, cant {cant_mm} mm, {speed} km/h, versine {32**2/(8*radius)*1e3:.1f} mm")
    print(f"{'column':45s} {'straight':>11s} {'chord':>11s} {'split':>11s}")
    for k in keys:
        s, c, p = rows["straight"][k], rows["chord"][k], rows["split_versine"][k]
        if "span3" in k or "span1" in k:
            print(f"{k:45s} {s:11.4g} {c:11.4g} ({c/s:5.3f}) {p:11.4g} ({p/s:5.3f})")


if __name__ == "__main__":
    main(float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]))
