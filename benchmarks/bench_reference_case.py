"""Wall seconds per simulated second of the reference case (config/reference_case.yaml), one core.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_reference_case.py [--case path.yaml] [--dt 4e-5]

Prints the set-up time (structure, static equilibrium), the time loop's wall time and its
wall seconds per simulated second (issue 4 target: at most 5 s), and the split between the
structure kernel and the rest of a step (vehicle, contact, irregularity, monitors). The first
run of a fresh checkout includes numba compilation; the script compiles on a 0.05 s run first.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from ttbpipe.simulation.coupled import integrate, prepare  # noqa: E402
from ttbpipe.structure.kernels import _structure_accelerations  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--dt", type=float, default=None, help="override simulation.time_step_s")
    args = parser.parse_args()
    case = yaml.safe_load(Path(args.case).read_text())
    if args.dt:
        case.setdefault("simulation", {})["time_step_s"] = args.dt

    warm = {**case, "simulation": {**case.get("simulation", {}), "duration_s": 0.05}}
    integrate(prepare(warm))  # compile (or load the numba cache)

    t0 = time.perf_counter()
    setup = prepare(case)
    t_setup = time.perf_counter() - t0
    raw = integrate(setup)
    simulated = setup.n_steps * setup.dt

    disp = np.zeros(setup.packed.n_dof)
    acc = np.zeros_like(disp)
    n_rep = 500
    t0 = time.perf_counter()
    for _ in range(n_rep):
        _structure_accelerations(setup.packed, disp, disp, disp, acc)
    t_struct = (time.perf_counter() - t0) / n_rep

    per_step = raw.wall_s / setup.n_steps
    print(f"case: {args.case}")
    print(f"structure DOF: {setup.packed.n_dof}, vehicle DOF: {setup.model.n_dof}, "
          f"wheels: {2 * setup.model.n_wheelsets}")
    print(f"time step: {setup.dt:.3g} s, steps: {setup.n_steps}, simulated: {simulated:.3f} s")
    print(f"set-up (structure, static equilibrium): {t_setup:.2f} s")
    print(f"time loop: {raw.wall_s:.2f} s wall = {per_step * 1e6:.1f} us per step")
    print(f"structure kernel alone: {t_struct * 1e6:.1f} us per call "
          f"({100 * t_struct / per_step:.0f} % of a step)")
    print(f"WALL SECONDS PER SIMULATED SECOND: {raw.wall_s / simulated:.2f} (target <= 5)")


if __name__ == "__main__":
    main()
