"""Line sampling against limit states with exact answers, over repeated seeds.

Prints, per case: evaluations, mean estimate / exact, the observed c.o.v. over the seeds, the
median reported c.o.v., and the coverage of the nominal 95 % interval (docs/reliability.md,
section 12). Exact references: the linear limit state beta - a.u, P = Phi(-beta); the parabolic
beta - u_1 + (kappa/2) sum_{i=2}^{k+1} u_i^2, P = E[Phi(-(beta + kappa X / 2))], X ~ chi2_k
(one-dimensional quadrature, scipy.integrate.quad, to 1e-12 relative).

    python benchmarks/line_sampling_table.py [--seeds 100] [--cases linear-2000,parabolic-200]
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np
from scipy import integrate, stats

from ttbpipe.reliability import estimate_failure_probability


def linear(beta: float, n_dims: int):
    a = np.ones(n_dims) / np.sqrt(n_dims)
    return (lambda u: beta - u @ a), float(stats.norm.sf(beta))


def parabolic(beta: float, kappa: float, k: int):
    def g(u):
        return beta - u[:, 0] + 0.5 * kappa * np.sum(u[:, 1:k + 1] ** 2, axis=1)
    exact, _ = integrate.quad(lambda x: stats.norm.sf(beta + 0.5 * kappa * x) * stats.chi2.pdf(x, k),
                              0.0, np.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return g, float(exact)


CASES = {
    "linear-2000": (lambda: linear(4.75, 2000), 2000),
    "linear-5000": (lambda: linear(4.75, 5000), 5000),
    "parabolic-200": (lambda: parabolic(4.5, 0.1, 10), 200),
    "parabolic-200-concave": (lambda: parabolic(4.9, -0.05, 10), 200),
    "parabolic-2000": (lambda: parabolic(4.5, 0.1, 10), 2000),
}


def run_case(name: str, seeds: int, options: dict) -> dict:
    make, n_dims = CASES[name]
    g, exact = make()
    rows = []
    start = time.perf_counter()
    for seed in range(seeds):
        r = estimate_failure_probability(g, n_dims, method="line_sampling", seed=seed, **options)
        rows.append((r.probability, r.ci_low, r.ci_high, r.cov, r.n_evaluations))
    a = np.array(rows)
    return {"case": name, "n_dims": n_dims, "exact": exact, "seeds": seeds,
            "evaluations": float(a[:, 4].mean()), "mean_over_exact": float(a[:, 0].mean() / exact),
            "se_mean": float(a[:, 0].std(ddof=1) / np.sqrt(seeds) / exact),
            "cov_observed": float(a[:, 0].std(ddof=1) / a[:, 0].mean()),
            "cov_reported": float(np.median(a[:, 3])),
            "coverage": float(np.mean((a[:, 1] <= exact) & (exact <= a[:, 2]))),
            "seconds": time.perf_counter() - start}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--n-lines", type=int, default=200)
    parser.add_argument("--direction-lines", type=int, default=100)
    parser.add_argument("--direction-levels", type=int, default=4)
    parser.add_argument("--direction-n-per-level", type=int, default=500)
    args = parser.parse_args()
    logging.disable(logging.WARNING)
    options = {"n_lines": args.n_lines, "direction_levels": args.direction_levels,
               "direction_lines": args.direction_lines,
               "direction_n_per_level": args.direction_n_per_level}
    print(f"line sampling, {options}")
    print("| case | dims | exact P | seeds | evaluations | mean / exact | c.o.v. observed | "
          "c.o.v. reported (median) | coverage of 95 % | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in args.cases.split(","):
        r = run_case(name, args.seeds, options)
        print(f"| {r['case']} | {r['n_dims']} | {r['exact']:.3e} | {r['seeds']} | "
              f"{r['evaluations']:.0f} | {r['mean_over_exact']:.3f} ± {r['se_mean']:.3f} | "
              f"{r['cov_observed']:.3f} | {r['cov_reported']:.3f} | {r['coverage']:.2f} | "
              f"{r['seconds']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
