"""Wall seconds per simulated second of the reference case (config/reference_case.yaml), one core.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_reference_case.py [--case path.yaml] [--dt 1.25e-4]
        [--lateral-creep semi_implicit|explicit] [--contact profiles] [--contact-points 1|2]
        [--creep-law kalker_she|polach]

``--contact profiles`` runs the case on S1002 / 60E1 (``train.contact: {profile: profiles}``,
docs/contact_geometry.md; give ``--dt 1e-4``: the pair's Hertz contact lowers the coupled step
limit); ``--contact-points`` selects one- or two-point contact on it (a tree without the
option rejects the key); ``--creep-law`` selects ``train.contact.creep_law`` (likewise).

Prints the set-up time (structure, stability check, static equilibrium), the time loop's wall and
CPU time, wall seconds per simulated second (target: at most 1 s on one core), the wall
time of a whole sample (``run_coupled``: set-up, loop, table, summary), and the split of a step
between the structure kernel and the rest (vehicle, contact, irregularity, monitors), with
``FIGURE`` lines for benchmarks/run_all.py. The script compiles (or loads the numba cache) on a
0.05 s run first.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402
import yaml  # noqa: E402

from ttbpipe.simulation.coupled import (integrate, prepare, results_table,  # noqa: E402
                                        summarise)

try:  # the kernel's public name; older trees (benchmarks/compare_revisions.py) had it private
    from ttbpipe.structure.kernels import structure_accelerations  # noqa: E402
except ImportError:  # pragma: no cover - only when timing an older revision
    from ttbpipe.structure.kernels import _structure_accelerations as structure_accelerations  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@njit
def _repeat_kernel(packed, disp, acc, n):
    for _ in range(n):
        structure_accelerations(packed, disp, disp, disp, acc)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--dt", type=float, default=None, help="override simulation.time_step_s")
    parser.add_argument("--lateral-creep", default=None, choices=["semi_implicit", "explicit"],
                        help="override simulation.lateral_creep")
    parser.add_argument("--contact", default=None, choices=["profiles"],
                        help="train.contact.profile (default: the case's)")
    parser.add_argument("--contact-points", type=int, default=None, choices=[1, 2],
                        help="train.contact.contact_points (with --contact profiles)")
    parser.add_argument("--creep-law", default=None, choices=["kalker_she", "polach"],
                        help="train.contact.creep_law (default: the case's)")
    args = parser.parse_args()
    case = yaml.safe_load(Path(args.case).read_text())
    if args.contact:
        case.setdefault("train", {})["contact"] = {"profile": args.contact}
        if args.contact_points:
            case["train"]["contact"]["contact_points"] = args.contact_points
    if args.creep_law:
        contact = case.setdefault("train", {}).setdefault("contact", {})
        contact["creep_law"] = args.creep_law
    sim = case.setdefault("simulation", {})
    if args.dt:
        sim["time_step_s"] = args.dt
    if args.lateral_creep:
        sim["lateral_creep"] = args.lateral_creep

    warm = {**case, "simulation": {**sim, "duration_s": 0.05}}
    integrate(prepare(warm))  # compile (or load the numba cache)

    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    setup = prepare(case)
    t_setup = time.perf_counter() - t0
    cpu0 = time.process_time()
    raw = integrate(setup)
    cpu_loop = time.process_time() - cpu0
    t0 = time.perf_counter()
    table = results_table(setup, raw)
    summarise(setup, raw, table)
    t_post = time.perf_counter() - t0
    simulated = setup.n_steps * setup.dt
    per_sample = t_setup + raw.wall_s + t_post

    # the kernel as the loop calls it (from numba: a call from Python would add the unboxing
    # of the ~45 arrays of the packed structure, about as long as the kernel itself)
    disp = np.zeros(setup.packed.n_dof)
    acc = np.zeros_like(disp)
    n_rep = 500
    _repeat_kernel(setup.packed, disp, acc, 1)
    t_struct = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        _repeat_kernel(setup.packed, disp, acc, n_rep)
        t_struct = min(t_struct, (time.perf_counter() - t0) / n_rep)

    per_step = raw.wall_s / setup.n_steps
    print(f"case: {args.case} (lateral creep: {setup.dt_limits['lateral_creep']})")
    print(f"structure DOF: {setup.packed.n_dof}, vehicle DOF: {setup.model.n_dof}, "
          f"wheels: {2 * setup.model.n_wheelsets}")
    print(f"time step: {setup.dt:.3g} s, steps: {setup.n_steps}, simulated: {simulated:.3f} s")
    print(f"set-up (structure, stability check, static equilibrium): {t_setup:.2f} s")
    print(f"time loop: {raw.wall_s:.2f} s wall ({cpu_loop:.2f} s CPU) = {per_step * 1e6:.1f} us "
          f"per step = {1 / per_step:.0f} steps per s; load average {load:.1f}")
    print(f"table + summary: {t_post:.2f} s; whole sample (run_coupled): {per_sample:.2f} s")
    print(f"structure kernel alone: {t_struct * 1e6:.1f} us per call "
          f"({100 * t_struct / per_step:.0f} % of a step)")
    print(f"WALL SECONDS PER SIMULATED SECOND: {raw.wall_s / simulated:.2f} (target <= 1)")
    print(f"FIGURE reference_case_wall_s_per_simulated_s = {raw.wall_s / simulated:.4g} s/s")
    print(f"FIGURE reference_case_cpu_s_per_simulated_s = {cpu_loop / simulated:.4g} s/s")
    print(f"FIGURE reference_case_wall_s_per_sample = {per_sample:.4g} s")
    print(f"FIGURE reference_case_setup_s = {t_setup:.4g} s")
    print(f"FIGURE reference_case_us_per_step = {per_step * 1e6:.4g} us")
    print(f"FIGURE reference_case_steps_per_s = {1 / per_step:.4g} 1/s")
    print(f"FIGURE reference_case_structure_kernel_us_per_call = {t_struct * 1e6:.4g} us")
    print(f"FIGURE reference_case_structural_dof = {setup.packed.n_dof} DOF")
    print(f"FIGURE reference_case_time_step = {setup.dt:.4g} s")


if __name__ == "__main__":
    main()
