"""Benchmark: what a double-track deck and a second train cost per step, side by side.

1. ``structure_accelerations`` per call on the reference structure (100 m ballasted approach +
   5 x 32 m spans + 100 m ballasted approach, ``build_structure({})``), single-track deck vs
   double-track deck (``layout.tracks: 2``: four rails, two slabs, two sets of sleepers and
   ballast); calls interleaved in rounds, the minimum per round kept.
2. Coupled runs (the reference case's structure, config/reference_case.yaml: 130 m ballasted
   approaches, a 5-car train at 300 km/h, TB/T 3352 irregularity, dt 1.25e-4 s) for
   ``--duration`` simulated seconds: one train on the single-track deck, one train on the
   double-track deck, two trains meeting on the double-track deck; the loop's wall time per
   step (summary ``wall_s`` / ``n_steps``), rounds interleaved, the minimum kept.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_double_track.py [--duration 0.4] [--rounds 3]
"""

from __future__ import annotations

import argparse
import copy
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from ttbpipe.simulation.coupled import run_coupled  # noqa: E402
from ttbpipe.structure import build_structure  # noqa: E402
from ttbpipe.structure.kernels import structure_accelerations  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def kernel_us(model, calls: int) -> float:
    rng = np.random.default_rng(0)
    u, v, f = (1e-6 * rng.normal(size=model.n_dof) for _ in range(3))
    acc = np.zeros(model.n_dof)
    structure_accelerations(model.packed, u, v, f, acc)          # compile / warm
    t0 = time.perf_counter()
    for _ in range(calls):
        structure_accelerations(model.packed, u, v, f, acc)
    return 1e6 * (time.perf_counter() - t0) / calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=0.4, help="simulated s per run")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--calls", type=int, default=2000, help="kernel calls per round")
    args = parser.parse_args()

    models = {"single": build_structure({}), "double": build_structure({"layout": {"tracks": 2}})}
    best = {k: np.inf for k in models}
    for _ in range(args.rounds):
        for k, m in models.items():
            best[k] = min(best[k], kernel_us(m, args.calls))
    for k, m in models.items():
        print(f"{k}-track deck: {m.n_dof} DOF, structure_accelerations {best[k]:.1f} us per call")
        print(f"FIGURE structure_{k}_track_us_per_call = {best[k]:.4g} us")
    print(f"ratio double / single: {best['double'] / best['single']:.2f}")

    case = yaml.safe_load((ROOT / "config" / "reference_case.yaml").read_text())
    case["simulation"]["duration_s"] = args.duration
    double = copy.deepcopy(case)
    double["structure"]["layout"]["tracks"] = 2
    meeting = copy.deepcopy(double)
    # the second train enters from the far end; in a short run it stays on its approach
    meeting["second_train"] = {}
    cases = {"one_train_single_track": case, "one_train_double_track": double,
             "two_trains_double_track": meeting}
    per_step = {k: np.inf for k in cases}
    for r in range(args.rounds + 1):           # round 0 compiles (numba cache) and is dropped
        for k, c in cases.items():
            _, s = run_coupled(c)
            if r > 0:
                per_step[k] = min(per_step[k], 1e6 * s["wall_s"] / s["n_steps"])
    for k, us in per_step.items():
        print(f"coupled, {k}: {us:.1f} us per step")
        print(f"FIGURE coupled_{k}_us_per_step = {us:.4g} us")
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
