"""Benchmark: reference structure under a 5-car train of moving constant wheel loads.

Reference structure: 100 m approach + 5 x 32 m simply supported spans + 100 m approach,
two CHN60 rails on fasteners, CRTS II slab on CA on the girders, ballasted approaches, bearings and
piers; 20 axles (5 cars x 4) = 40 wheel loads of 70 kN moving at 300 km/h; Zhai's explicit method.
Prints the DOF count, steps per second and wall seconds per simulated second on one core.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_structure.py [--dt 1e-4] [--duration 0.5]
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from ttbpipe.structure import build_structure  # noqa: E402
from ttbpipe.structure.moving_loads import build_loads, simulate  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dt", type=float, default=1e-4, help="time step (s)")
    parser.add_argument("--duration", type=float, default=0.5, help="simulated time (s)")
    parser.add_argument("--repeat", type=int, default=3, help="timed repetitions (best is kept)")
    args = parser.parse_args()

    t0 = time.perf_counter()
    model = build_structure({})
    t_build = time.perf_counter() - t0
    loads = build_loads({"speed_kmh": 300.0,
                         "axle_train": {"cars": 5, "wheel_load_N": 70e3, "front_x0_m": 130.0}},
                        model)
    stab = model.stable_time_step()
    # warm-up: numba compile (cached on disk after the first run)
    simulate(model, loads, args.dt, 10 * args.dt, check_dt=False)
    best = None
    for _ in range(args.repeat):
        _, info = simulate(model, loads, args.dt, args.duration, check_dt=False,
                           output_every=10)
        if best is None or info["wall_s"] < best["wall_s"]:
            best = info
    p = model.packed
    print(f"DOF count:                     {model.n_dof}")
    print(f"  rails {model.dof_info['slab']}, slab {model.dof_info['sleeper'] - model.dof_info['slab']}, "
          f"sleepers+ballast {model.dof_info['pier'] - model.dof_info['sleeper']}, "
          f"piers {model.dof_info['span'] - model.dof_info['pier']}, "
          f"girder spans {model.n_dof - model.dof_info['span']}")
    print(f"beam elements {p.beam_L.size}, links {p.link_k.size} ({p.link_dof.size} terms)")
    print(f"wheel loads:                   {loads.n} at 300 km/h")
    print(f"build time:                    {t_build:.3f} s")
    print(f"stable Zhai step (x0.9):       {stab:.3e} s")
    print(f"time step used:                {args.dt:.3e} s")
    print(f"steps per second:              {best['n_steps'] / best['wall_s']:.0f}")
    print(f"us per step:                   {1e6 * best['wall_s'] / best['n_steps']:.1f}")
    print(f"wall s per simulated s:        {best['wall_s_per_simulated_s']:.3f}")
    print(f"CPU s per simulated s:         {best['cpu_s_per_simulated_s']:.3f}  (process time; "
          f"differs from wall when the cores are shared, load average {os.getloadavg()[0]:.1f})")
    print(f"FIGURE structure_moving_loads_us_per_step = {1e6 * best['wall_s'] / best['n_steps']:.4g} us")
    print(f"FIGURE structure_moving_loads_wall_s_per_simulated_s = "
          f"{best['wall_s_per_simulated_s']:.4g} s/s")
    at = stab   # model.stable_time_step() is already 0.9 x the limit
    print(f"at dt = {at:.3e} s (0.9 x limit): wall s per simulated s ~ "
          f"{best['wall_s_per_simulated_s'] * args.dt / at:.3f}")


if __name__ == "__main__":
    main()
