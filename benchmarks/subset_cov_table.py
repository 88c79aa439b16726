"""Subset simulation over repeated seeds on limit states with exact answers: the rows of the
measured tables of docs/reliability.md, section 10.

For each case, ``--seeds`` independent runs of
``ttbpipe.reliability.estimate_failure_probability(g, n_dims, method="subset", seed=s, ...)``
(s = 0, 1, ...); printed as a Markdown row: mean evaluations, mean estimate / exact value (with
its standard error over the seeds), the observed c.o.v. (standard deviation / mean of the
estimates over the seeds), the mean reported c.o.v. (lineage variance, and in brackets Au &
Beck's uncorrelated-levels value) and how often the nominal 95 % interval holds the exact value
(the reported interval, and in brackets the same lognormal interval with Au & Beck's c.o.v.).

Exact references: ``g = beta - a.u`` with |a| = 1, ``P = Phi(-beta)``; ``g = c - sum_{i<k} u_i^2``,
``P = chi2_k.sf(c)`` (scipy.stats).

    python benchmarks/subset_cov_table.py --case linear:4.75:200 --seeds 200
    python benchmarks/subset_cov_table.py --case chi2:1e-4:10:300 --n-per-level 500 --seeds 200
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np
from scipy import stats

from ttbpipe.reliability import estimate_failure_probability
from ttbpipe.reliability.result import lognormal_interval


def limit_state(case: str):
    """``linear:beta:n_dims``, ``chi2:probability:k:n_dims`` or ``parabolic:beta:kappa:n_dims``
    (``g = beta - u_1 + (kappa/2) sum_{i=2}^{11} u_i^2``, exact by quadrature over chi2_10)
    -> (g, n_dims, exact, label)."""
    kind, *args = case.split(":")
    if kind == "linear":
        beta, n_dims = float(args[0]), int(args[1])
        direction = np.ones(n_dims) / np.sqrt(n_dims)
        return (lambda u: beta - u @ direction), n_dims, float(stats.norm.sf(beta)), \
            f"linear, β = {beta:g}"
    if kind == "chi2":
        probability, k, n_dims = float(args[0]), int(args[1]), int(args[2])
        radius2 = float(stats.chi2.isf(probability, k))
        return (lambda u: radius2 - np.sum(u[:, :k] ** 2, axis=1)), n_dims, probability, \
            f"χ², k = {k}"
    if kind == "parabolic":
        from scipy import integrate

        beta, kappa, n_dims = float(args[0]), float(args[1]), int(args[2])
        exact = integrate.quad(
            lambda x: stats.norm.sf(beta + 0.5 * kappa * x) * stats.chi2.pdf(x, 10),
            0.0, np.inf, epsabs=0.0, epsrel=1e-10, limit=200)[0]
        return (lambda u: beta - u[:, 0] + 0.5 * kappa * np.sum(u[:, 1:11] ** 2, axis=1)), \
            n_dims, exact, f"parabolic, β = {beta:g}, κ = {kappa:g}"
    raise ValueError(f"unknown case {case!r}")


def row(case: str, seeds: int, **options) -> str:
    g, n_dims, exact, label = limit_state(case)
    t0 = time.time()
    runs = [estimate_failure_probability(g, n_dims, method="subset", seed=s, **options)
            for s in range(seeds)]
    p = np.array([r.probability for r in runs])
    cov_ab = np.array([r.details["cov_au_beck"] for r in runs])
    covers_ab = [lo <= exact <= hi for lo, hi in
                 (lognormal_interval(r.probability, c, r.confidence_level)
                  for r, c in zip(runs, cov_ab))]
    mean_ratio = p.mean() / exact
    se = p.std(ddof=1) / exact / np.sqrt(seeds)
    return (f"| {label} | {options.get('sampler', 'acs')} | {n_dims} | "
            f"{options.get('n_per_level', 1000)} | "
            f"{options.get('level_probability', 0.1):g} | "
            f"{np.mean([r.n_evaluations for r in runs]):.0f} | {exact:.3g} | "
            f"{mean_ratio:.2f} ± {se:.2f} | {p.std(ddof=1) / p.mean():.2f} | "
            f"{np.mean([r.cov for r in runs]):.2f} ({cov_ab.mean():.2f}) | "
            f"{np.mean([r.covers(exact) for r in runs]):.2f} ({np.mean(covers_ab):.2f}) | "
            f"{seeds} |  <!-- {time.time() - t0:.0f} s -->")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", action="append", required=True,
                        help="linear:beta:n_dims or chi2:probability:k:n_dims (repeatable)")
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--n-per-level", type=int, default=1000)
    parser.add_argument("--level-probability", type=float, default=0.1)
    parser.add_argument("--target-acceptance", type=float, default=0.44)
    parser.add_argument("--lineage-lag", type=int, default=2)
    parser.add_argument("--sampler", default="acs", help="acs or plane (SubsetSettings.sampler)")
    args = parser.parse_args()
    logging.disable(logging.WARNING)     # max_levels warnings of single runs
    print("| limit state | sampler | dimension | N per level | p0 | evaluations | exact P | mean / exact "
          "| c.o.v. observed | c.o.v. reported (Au & Beck) | coverage of the 95 % interval "
          "(with Au & Beck's c.o.v.) | seeds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for case in args.case:
        print(row(case, args.seeds, n_per_level=args.n_per_level,
                  level_probability=args.level_probability,
                  target_acceptance=args.target_acceptance, lineage_lag=args.lineage_lag,
                  sampler=args.sampler),
              flush=True)


if __name__ == "__main__":
    main()
