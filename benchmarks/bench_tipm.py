"""Benchmark: TIPM selection of representative PSD sets on a synthetic population. Prints.

    python benchmarks/bench_tipm.py [--sections 1000] [--repeat 3]

Population: ``ttbpipe.tipm.synthetic_population`` with the TB/T 3352 mean PSD of the four
spectral channels, lognormal section levels and
Welch scatter (the statistics the TIPM tests check) on the uniform Welch grid of 1000 m
sections (wavelengths 2-200 m); selection: :class:`TIPMSelector` defaults
(copula method, variance matching, M = 10 % of the sections). Prints the best-of-repeat wall time
of ``select`` and the relative error of the selection's per-frequency mean, plus a
``FIGURE`` line (benchmarks/run_all.py).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.tipm import TIPMSelector, synthetic_population
from ttbpipe.channels import SPECTRAL_CHANNELS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sections", type=int, default=1000, help="sections in the population")
    parser.add_argument("--repeat", type=int, default=3, help="timed repetitions (best kept)")
    args = parser.parse_args()
    spectrum = get_spectrum("tbt3352")
    frequency = np.arange(1, 500) / 1000.0   # Welch grid of 1000 m sections, 2-1000 m
    frequency = frequency[frequency >= 1 / 200.0]
    mean_psd = np.stack([spectrum.psd_mm2_m(c, frequency) for c in SPECTRAL_CHANNELS], axis=1)
    population = synthetic_population(args.sections, frequency, mean_psd,
                                      np.random.default_rng(0))
    selector = TIPMSelector()
    best, selection = np.inf, None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        selection = selector.select(population)
        best = min(best, time.perf_counter() - t0)
    err = np.abs(selection.weighted_mean() / population.psd_mm2_m.mean(axis=0) - 1).max()
    print(f"population: {args.sections} sections x {frequency.size} frequencies x "
          f"{len(SPECTRAL_CHANNELS)} channels; selected {selection.n_samples} sets")
    print(f"TIPMSelector().select: {best:.3f} s (best of {args.repeat}); max relative error of "
          f"the per-frequency weighted mean {err:.2e}")
    print(f"FIGURE tipm_selection_{args.sections}_sections = {best:.4g} s")


if __name__ == "__main__":
    main()
