"""Cost of the standards assessment in a study sample, side by side in one process.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_study_assessment.py [--configfile config/config.yaml]
        [--rounds 5]

Times the default study's "single" sample (config/config.yaml) three ways, interleaved round by
round so that a drift of the machine load hits all three: no assessment
(``assessment.standard: []``), every profile without the EN 1990 twist (no extra monitors) and
every profile with the twist (the run records the twist monitors of
:func:`ttbpipe.assessment.monitors.deck_check_monitors`). Prints the median and the minimum of
each and the extra cost of the assessment and of the twist monitors. Timings only.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import yaml  # noqa: E402

from ttbpipe.assessment.study import resolve_assessment  # noqa: E402
from ttbpipe.study.samples import resolve_simulation, run_sample  # noqa: E402

VARIANTS = {
    "no assessment": {"standard": []},
    "all profiles, no twist": {"options": {"en1990": {"twist": False}}},
    "all profiles with twist": {},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", default="config/config.yaml")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    config = yaml.safe_load(open(args.configfile))
    kwargs = dict(study_seed=config["study"]["seed"],
                  sim=resolve_simulation(config.get("simulation")), structure=config["structure"],
                  fields=config.get("fields"), profiles={})
    row = {"scenario": "single", "kind": "single", "sample_index": 0, "weight": 1.0,
           "profile_index": -1, "condition": "nominal", "seed_entropy": "0"}
    settings = {name: resolve_assessment(v) for name, v in VARIANTS.items()}
    for a in settings.values():       # warm-up: numba cache, imports, the modal analysis
        run_sample(row, assessment=a, **kwargs)
    times: dict[str, list[float]] = {name: [] for name in settings}
    for r in range(args.rounds):
        order = list(settings) if r % 2 == 0 else list(settings)[::-1]
        for name in order:
            t0 = time.perf_counter()
            run_sample(row, assessment=settings[name], **kwargs)
            times[name].append(time.perf_counter() - t0)
    for name, t in times.items():
        print(f"{name:26s} median {statistics.median(t):6.2f} s  min {min(t):6.2f} s")
    base = statistics.median(times["no assessment"])
    print(f"assessment without twist: +{statistics.median(times['all profiles, no twist']) - base:.2f} s")
    print(f"assessment with twist:    +{statistics.median(times['all profiles with twist']) - base:.2f} s")
    for name, t in times.items():
        key = name.replace(",", "").replace(" ", "_")
        print(f"FIGURE study_sample_{key} = {statistics.median(t):.4g} s")


if __name__ == "__main__":
    main()
