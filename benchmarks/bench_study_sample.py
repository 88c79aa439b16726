"""Wall time of one sample of the default study (config/config.yaml: structure + simulation).

    NUMBA_NUM_THREADS=1 python benchmarks/bench_study_sample.py [--configfile config/config.yaml]

Prints the wall time of a "single" sample (mean-spectrum irregularity, nominal parameters) and of
a "fields" sample (condition C4: random girder) after a warm-up sample (numba cache load and
imports), the part of each outside the time loop (set-up, static state, reductions, assessment),
and the resulting estimate for the study's sample count on N cores. Size the default
study (study.scenarios, simulation:, structure:) from these figures.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import yaml  # noqa: E402

import ttbpipe.simulation.coupled as coupled  # noqa: E402
from ttbpipe.assessment.study import resolve_assessment  # noqa: E402
from ttbpipe.study.samples import resolve_simulation, run_sample  # noqa: E402

LOOP_S: list[float] = []
_integrate = coupled.integrate


def _timed_integrate(setup):
    """The time loop, its wall time recorded: a sample's time outside the loop (set-up,
    reductions, assessment) is its wall time minus this."""
    t0 = time.perf_counter()
    raw = _integrate(setup)
    LOOP_S.append(time.perf_counter() - t0)
    return raw


coupled.integrate = _timed_integrate


def timed_sample(row, kwargs) -> tuple[float, float]:
    """(wall s, s outside the time loop) of one sample."""
    t0 = time.perf_counter()
    run_sample(row, **kwargs)
    wall = time.perf_counter() - t0
    return wall, wall - LOOP_S[-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", default="config/config.yaml")
    parser.add_argument("--samples", type=int, default=61, help="samples of the study")
    parser.add_argument("--cores", type=int, default=2)
    args = parser.parse_args()
    config = yaml.safe_load(open(args.configfile))
    sim = resolve_simulation(config.get("simulation"))
    kwargs = dict(study_seed=config["study"]["seed"], sim=sim, structure=config["structure"],
                  fields=config.get("fields"), profiles={},
                  assessment=resolve_assessment(config.get("assessment")))
    row = {"scenario": "single", "kind": "single", "sample_index": 0, "weight": 1.0,
           "profile_index": -1, "condition": "nominal", "seed_entropy": "0"}
    warm, _ = timed_sample(row, kwargs)
    single, single_outside = timed_sample(row, kwargs)
    fields_row = {**row, "scenario": "C4", "kind": "fields", "condition": "C4"}
    first_fields, _ = timed_sample(fields_row, kwargs)   # includes the KLE/Nataf set-up of the condition
    fields, fields_outside = timed_sample({**fields_row, "sample_index": 1}, kwargs)
    print(f"first sample of a process (imports, numba cache): {warm:.1f} s")
    print(f"single sample: {single:.1f} s ({single_outside:.2f} s outside the time loop)")
    print(f"fields sample: first of its condition {first_fields:.1f} s, next {fields:.1f} s "
          f"({fields_outside:.2f} s outside the time loop)")
    per = max(single, fields)
    print(f"estimate for {args.samples} samples on {args.cores} cores: "
          f"{args.samples * per / args.cores:.0f} s (+ job overheads)")
    # machine-readable figures for benchmarks/run_all.py
    print(f"FIGURE study_single_sample = {single:.4g} s")
    print(f"FIGURE study_fields_sample = {fields:.4g} s")
    print(f"FIGURE study_single_sample_outside_loop = {single_outside:.4g} s")
    print(f"FIGURE study_fields_sample_outside_loop = {fields_outside:.4g} s")
    print(f"FIGURE study_first_sample_of_process = {warm:.4g} s")


if __name__ == "__main__":
    main()
