"""Wall time of building a case's structure and of re-assembling it with random property factors.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_structure_build.py [--case config/case2.yaml]
        [--calls 15]

A fields sample (paper case 2, the default study's C1 .. C4) builds its own structure from the
nominal one and its factors (`ttbpipe.structure.apply_factors`) before its stability analysis
and static state. Builds the case's nominal structure (``structure:`` and
``simulation.layout`` of the case file merged over config/config.yaml, as a study does), then
re-assembles it with factors uniform in [0.8, 1.2] on the girder elements and, separately, on
the rail elements (one draw each, fixed seed), ``--calls`` times each after a warm-up. Prints
the medians as ``FIGURE`` lines (milliseconds), for `benchmarks/compare_revisions.py --script
benchmarks/bench_structure_build.py --figure structure_apply_factors_girder_ms`. Timings only.
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
import yaml

from _timing import median_time

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--case", default="config/case2.yaml")
    parser.add_argument("--calls", type=int, default=15)
    args = parser.parse_args()

    from snakemake.utils import update_config

    from ttbpipe.structure import (CARRIER_PARAMETERS, apply_factors, build_structure,
                                   carrier_positions)
    from ttbpipe.vehicle.curving import cant_knots, plan_knots

    config = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    update_config(config, yaml.safe_load((ROOT / args.case).read_text()))
    structure_cfg = config.get("structure") or {}
    layout = (config.get("simulation") or {}).get("layout")
    # as ttbpipe.simulation.setup builds a case's nominal structure
    build = lambda: build_structure(copy.deepcopy(structure_cfg), cant=cant_knots(layout),  # noqa: E731
                                    plan=plan_knots(layout))
    nominal = build()
    positions = carrier_positions(nominal)
    print(f"{args.case}: {nominal.n_dof} structural DOF, {nominal.packed.pad_rail.size} rail pads, "
          f"{nominal.packed.tri_ptr.size - 1} CA link triples")
    print(f"FIGURE structure_build_ms = {1e3 * median_time(build, args.calls):.2f} ms")
    for kind, label in (("girder_element", "girder"), ("rail_element", "rail")):
        rng = np.random.default_rng(20261206)
        factors = {name: rng.uniform(0.8, 1.2, positions[kind].size)
                   for name in CARRIER_PARAMETERS[kind]}
        ms = 1e3 * median_time(lambda: apply_factors(nominal, factors), args.calls)
        print(f"FIGURE structure_apply_factors_{label}_ms = {ms:.2f} ms")


if __name__ == "__main__":
    main()
