"""Cost of the EN 1990 A2 span frequencies of one sample (ttbpipe.assessment.modal.analyse).

    NUMBA_NUM_THREADS=1 python benchmarks/bench_span_frequencies.py [--configfile config/case2.yaml]
        [--repeats 3]

A sample whose structure properties are random (a fields scenario) gets its own modal analysis
in the EN 1990 assessment. Prints, best of ``--repeats`` alternating rounds, the wall time of
the matrix assembly, of ``analyse`` as it is (the matrices assembled once and passed to every
eigen-solve) and of the earlier path (each eigen-solve assembling them again, emulated by
dropping the passed matrices), and checks that both give the same frequencies.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import yaml  # noqa: E402
from snakemake.utils import update_config  # noqa: E402

from ttbpipe.assessment import modal as assessment_modal  # noqa: E402
from ttbpipe.structure import build_structure  # noqa: E402
from ttbpipe.structure import modal as structure_modal  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", default="config/case2.yaml")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    config = yaml.safe_load(open("config/config.yaml"))
    if args.configfile != "config/config.yaml":
        # merged as `snakemake --configfile` merges it
        update_config(config, yaml.safe_load(open(args.configfile)))
    model = build_structure(config["structure"])
    fast = structure_modal.modal_analysis

    def reassembling(member, n_modes=20, sigma_hz=0.0, matrices=None):
        return fast(member, n_modes=n_modes, sigma_hz=sigma_hz)

    timings = {"assembly": [], "now": [], "earlier": []}
    results = {}
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        model.matrices()
        timings["assembly"].append(time.perf_counter() - t0)
        for name, function in (("now", fast), ("earlier", reassembling)):
            structure_modal.modal_analysis = function
            try:
                t0 = time.perf_counter()
                results[name] = assessment_modal.analyse(model)
                timings[name].append(time.perf_counter() - t0)
            finally:
                structure_modal.modal_analysis = fast
    assert results["now"] == results["earlier"], results
    best = {k: min(v) for k, v in timings.items()}
    print(f"structure of {args.configfile}: {model.n_dof} DOF, {len(model.spans)} spans; "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"matrix assembly: {best['assembly']:.3f} s")
    print(f"span frequencies now: {best['now']:.3f} s; earlier path: {best['earlier']:.3f} s "
          f"(ratio {best['earlier'] / best['now']:.2f}); same frequencies")
    print(f"FIGURE span_frequencies = {best['now']:.3f} s")


if __name__ == "__main__":
    main()
