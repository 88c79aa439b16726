"""Wall time of one study sample's stages outside its time loop (paper case 3's Monte Carlo samples).

    python benchmarks/study_sample_stages.py ROOT [--samples 6] [--configfile config/case3.yaml]
        [--scenario mc]

ROOT: a clone in which `snakemake --cores 2 --configfile config/case3.yaml` has written at least
the Monte Carlo design, the PSD tables and the span frequencies (results/case3/study/design/mc.parquet,
results/case3/psd/*.parquet, results/case3/study/span_frequencies.json; the pooled population
results/case3/study/mc_population.parquet is read where it exists, as the batches do); or, with
``--configfile config/case2.yaml --scenario C4`` (C1 .. C4, C4_mc), a clone with paper case 2's
designs and span frequencies, whose samples build their own structures. Runs the design's first
sample as a warm-up (population, structure, numba cache), then the next ``--samples`` ones
through `ttbpipe.study.samples.run_sample` as a batch does, with `time.perf_counter` timers
wrapped around its stages (profile or field factors, set-up, static state, train model, time loop, results table,
summary, finiteness check, assessment), and prints the warm-up sample's time outside its loop
(a batch's first sample), each stage's mean per sample and the time outside the loop. Compare
codes side by side (run the script of each checkout alternately).
Timings only; the results are those of the batch (tests/test_study_batch.py).
"""

from __future__ import annotations

import argparse
import collections
import functools
import time
from pathlib import Path

from _study_samples import study_sample_inputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", type=Path)
    parser.add_argument("--samples", type=int, default=6)
    parser.add_argument("--configfile", default="config/case3.yaml")
    parser.add_argument("--scenario", default="mc",
                        help="the design's scenario (results/<case>/study/design/<scenario>.parquet;"
                             " C1 .. C4, C4_mc for paper case 2)")
    args = parser.parse_args()

    import ttbpipe.assessment.study as assessment_study
    import ttbpipe.simulation.coupled as coupled
    import ttbpipe.simulation.setup as setup
    from ttbpipe.study import samples

    try:   # as ttbpipe.study.batch.simulate_batch does, in a checkout that has it
        from ttbpipe.memory import reuse_freed_memory
    except ImportError:
        pass
    else:
        reuse_freed_memory()
    spent: collections.Counter = collections.Counter()

    def timed(module, name: str) -> None:
        if not hasattr(module, name):     # an older checkout without that stage
            return
        function = getattr(module, name)

        @functools.wraps(function)
        def wrapper(*a, **k):
            start = time.perf_counter()
            try:
                return function(*a, **k)
            finally:
                spent[f"{module.__name__.rsplit('.', 1)[-1]}.{name}"] += time.perf_counter() - start

        setattr(module, name, wrapper)

    for module, name in [(samples, "mc_profile"), (samples, "read_profile"), (samples, "field_factors"),
                         (setup, "build_train_model"),
                         (setup, "static_equilibrium_trains"), (coupled, "prepare"),
                         (coupled, "integrate"), (coupled, "results_table"),
                         (coupled, "summarise"), (coupled, "check_finite"),
                         (assessment_study, "assess_sample")]:
        timed(module, name)

    _, rows, kwargs = study_sample_inputs(args.root, args.configfile, args.scenario)
    start = time.perf_counter()
    samples.run_sample(rows[0], **kwargs)
    first = time.perf_counter() - start
    print(f"first sample (the population, the structure, numba's cache): {first:.3f} s, "
          f"outside the time loop {first - spent['coupled.integrate']:.3f} s")
    spent.clear()
    start = time.perf_counter()
    for row in rows[1:1 + args.samples]:
        samples.run_sample(row, **kwargs)
    per_sample = (time.perf_counter() - start) / args.samples
    print(f"{args.samples} samples: {per_sample:.3f} s per sample")
    for stage, seconds in spent.most_common():
        print(f"  {stage:40s} {1e3 * seconds / args.samples:8.1f} ms")
    outside = per_sample - spent["coupled.integrate"] / args.samples
    print(f"  outside the time loop: {1e3 * outside:.1f} ms")


if __name__ == "__main__":
    main()
