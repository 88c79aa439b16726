"""Timings and figures of the random-field stage. Prints; asserts nothing.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_fields.py [--config config/config.yaml]

Prints: set-up time (Nataf solves + KL bases) and drawing time of the default study's samples for
both methods, the per-sample cost at 1000 samples, a Nataf quadrature solve of 8 mixed
marginals, KL eigenvalue errors against the exact exponential-kernel solution with their
convergence ratio, and the modes capturing 95 % / 99 % of the variance on the default carriers.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import yaml

from ttbpipe.fields import (FieldSampler, KarhunenLoeve, NatafTransform, carrier_positions,
                            exponential_kernel_eigenvalues, make_marginal, modes_for_fractions)

from _timing import timed  # benchmarks/_timing.py (sibling module)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--config", default=str(Path(__file__).parents[1] / "config" /
                                                "config.yaml"))
    args = parser.parse_args()
    config = yaml.safe_load(Path(args.config).read_text())
    fields, seed = config["fields"], config["study"]["seed"]
    n_default = int(fields.get("samples", 50))

    print("== default study sampling ==")
    for method in ("kle", "mc"):
        t_setup, sampler = timed(lambda: FieldSampler(fields, seed, method=method))
        t_draw, df = timed(lambda: sampler.table(range(n_default)))
        t_1000, _ = timed(lambda: [sampler.sample(i) for i in range(1000)], repeat=1)
        coeffs = {s.group.name: s.n_coefficients for s in sampler.samplers}
        print(f"{method}: set-up {t_setup * 1e3:.1f} ms; {n_default} samples -> table "
              f"({len(df)} rows) {t_draw * 1e3:.1f} ms; 1000 samples (arrays) "
              f"{t_1000:.2f} s = {t_1000 / 1000:.2e} s/sample; coefficients per parameter {coeffs}")
        # machine-readable figures for benchmarks/run_all.py
        print(f"FIGURE field_sampling_{method}_setup = {t_setup:.4g} s")
        print(f"FIGURE field_sampling_{method}_per_sample = {t_1000 / 1000:.4g} s")

    print("== long line, eq. 34 division: 5 km plain track, C2 pads, 50 segments of 100 m ==")
    long_fields = dict(fields, geometry={"line_length_m": 5000.0, "fastener_spacing_m": 0.63},
                       groups={"C2": fields["groups"]["C2"]}, segments=50)
    t_setup, sampler = timed(lambda: FieldSampler(long_fields, seed), repeat=1)
    t_draw, _ = timed(lambda: [sampler.sample(i) for i in range(100)], repeat=1)
    n_bases = len({id(seg.basis) for seg in sampler.samplers[0].segments})
    print(f"{sampler.samplers[0].positions_m.size} fasteners: set-up {t_setup * 1e3:.0f} ms "
          f"({n_bases} distinct segment bases), 100 samples {t_draw:.2f} s")

    print("== Nataf quadrature solve, 8 mixed marginals ==")
    kinds = ["lognormal", "gamma", "weibull", "uniform", "truncated_normal", "lognormal",
             "gamma", "weibull"]
    marginals = [make_marginal(k, 1.0, 0.3, lower=0.5) if k == "truncated_normal"
                 else make_marginal(k, 1.0, 0.3) for k in kinds]
    target = np.full((8, 8), 0.5) + 0.5 * np.eye(8)
    t_nataf, nataf = timed(lambda: NatafTransform(marginals, target))
    worst = max(abs(nataf.pearson_from_gaussian(i, j, nataf.gaussian_correlation[i, j]) - 0.5)
                for i in range(8) for j in range(i + 1, 8))
    print(f"28 pairs, 64 nodes: {t_nataf * 1e3:.0f} ms; max residual of eq. 42: {worst:.1e}")

    print("== KL eigenvalues vs exact exponential kernel (Ghanem & Spanos), a = b = 1 ==")
    exact = exponential_kernel_eigenvalues(10, 1.0, 1.0)
    previous = None
    for n in (101, 201, 401, 801):
        err = np.abs(KarhunenLoeve(np.linspace(-1, 1, n), 1.0, n_modes=10).eigenvalues / exact - 1)
        ratio = "" if previous is None else f"; error ratio vs h*2: {np.max(previous / err):.3f}"
        print(f"h = {2 / (n - 1):.4f}: max rel. error of first 10 = {err.max():.2e}{ratio}")
        previous = err

    b = float(fields.get("correlation_length_m", 10.0))
    pos = carrier_positions(fields["geometry"])
    half = (pos["fastener"][-1] - pos["fastener"][0]) / 2
    x = pos["fastener"] - pos["fastener"][0] - half
    err = np.abs(KarhunenLoeve(x, b, n_modes=10).eigenvalues
                 / exponential_kernel_eigenvalues(10, half, b) - 1)
    print(f"default fastener grid (h = 0.63 m, b = {b} m, L = {2 * half:.1f} m): max rel. error "
          f"of first 10 = {err.max():.2e}")

    print(f"== modes for 95 % / 99 % of the variance at b = {b} m "
          f"({fields.get('kernel', 'exponential')}) ==")
    for kind, positions in pos.items():
        if positions.size:
            counts = modes_for_fractions(positions, b, fields.get("kernel", "exponential"))
            print(f"{kind}: {positions.size} carriers over {positions[-1] - positions[0]:.1f} m: "
                  f"{counts[0.95]} modes (95 %), {counts[0.99]} modes (99 %)")


if __name__ == "__main__":
    main()
