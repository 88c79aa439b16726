"""Time loop with the moving track window (``simulation.track_window_m``) against the whole track.

    NUMBA_NUM_THREADS=1 python benchmarks/track_window_cost.py [--case config/reference_case.yaml
        | --study config/config.yaml] [--margins 20 10] [--rounds 5] [--duration S]

Runs the case with the whole track and with each margin, the runs alternating round by round in
one process (the machine's load hits all alike; ``--study``: the study's single sample, its
structure, train and simulation settings on the mean-spectrum profile), and prints per variant
the median and minimum CPU time per step of the loop, the ratio to the whole track, and the
largest relative difference of the wheel-force peaks (max P, min P, max |Q|, max Q/P of every
wheel) and of the structure's monitored peaks (without the unfiltered rail accelerations,
listed apart), with ``FIGURE`` lines (benchmarks/compare_revisions.py). Not a ``bench_*``
script: a few minutes, too long for benchmarks/run_all.py. Method and decision:
docs/performance.md ("Moving window over the approach track").
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

from ttbpipe.simulation.coupled import integrate, prepare  # noqa: E402
from ttbpipe.study.samples import (build_case, mean_spectrum_irregularity,  # noqa: E402
                                   resolve_simulation)

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--margins", type=float, nargs="+", default=[20.0, 10.0])
    parser.add_argument("--study", default=None, help="a study configuration instead of --case")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--duration", type=float, default=None, help="simulation.duration_s")
    args = parser.parse_args()
    if args.study:
        config = yaml.safe_load(Path(args.study).read_text())
        sim = resolve_simulation(config.get("simulation"))
        case = build_case(sim, config["structure"], irregularity=mean_spectrum_irregularity(
            sim["irregularity"], config["study"]["seed"]))
        args.case = args.study
    else:
        case = yaml.safe_load(Path(args.case).read_text())
    if args.duration:
        case["simulation"]["duration_s"] = args.duration
    variants = [None, *args.margins]
    setups = {}
    for margin in variants:
        c = copy.deepcopy(case)
        c["simulation"]["track_window_m"] = margin
        setups[margin] = prepare(c)
    raws = {m: integrate(setups[m]) for m in variants}          # compile, or load the cache
    cpu = {m: [] for m in variants}
    for r in range(args.rounds):
        for m in (variants if r % 2 == 0 else variants[::-1]):
            t0 = time.process_time()
            raws[m] = integrate(setups[m])
            cpu[m].append((time.process_time() - t0) / setups[m].n_steps)
    ref, names = raws[None], setups[None].monitors.names
    rail = np.array([n.startswith("rail_") for n in names])
    base = float(np.median(cpu[None]))
    tag = Path(args.case).stem
    print(f"case {args.case}: {setups[None].n_steps} steps, {args.rounds} rounds, load "
          f"{os.getloadavg()[0]:.1f}")
    for m in variants:
        med, low = float(np.median(cpu[m])), float(np.min(cpu[m]))
        wheel = (np.abs(raws[m].wheel_peak - ref.wheel_peak).max(axis=(0, 1))
                 / np.abs(ref.wheel_peak).max(axis=(0, 1))).max()
        rel = np.abs(raws[m].monitors.peak - ref.monitors.peak) / np.abs(ref.monitors.peak)
        label = "whole track" if m is None else f"window {m:g} m"
        print(f"{label:14s} CPU {med * 1e6:7.1f} us/step (min {low * 1e6:7.1f}), ratio "
              f"{med / base:.3f}; peaks vs whole track: wheels {wheel:.1e}, structure "
              f"{rel[~rail].max():.1e}, rail accelerations {rel[rail].max():.1e}")
        key = "whole" if m is None else f"window_{m:g}m"
        print(f"FIGURE {tag}_{key}_cpu_us_per_step = {med * 1e6:.4g} us")


if __name__ == "__main__":
    main()
