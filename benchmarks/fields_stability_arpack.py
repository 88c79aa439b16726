"""ARPACK's subspace and tolerance for a fields sample's stability analysis (docs/performance.md,
"Another Krylov space or tolerance for a fields sample's stability analysis").

    python benchmarks/fields_stability_arpack.py ROOT [--configfile config/case2.yaml]
        [--scenario C4_mc] [--samples 7]

ROOT: a clone in which `snakemake --cores 2 --configfile config/case2.yaml` has written paper
case 2's designs. For the first ``--samples`` samples of the fields scenario, builds the
sample's set-up (its structure with its property factors, as a batch does), forms the standard
form L^-1 K L^-T of `ttbpipe.timestepping.limits` and solves its top six eigenpairs with
ARPACK as the set-up does (fixed start vector, ``tol`` 1e-3, 20 Lanczos vectors) and with other
subspaces (13, 16, 24 vectors) and a looser tolerance (3e-3). Prints, per sample and variant,
the matrix-vector products, the best of three solve times, the top frequency and the largest
relative difference of the six frequencies to the set-up's own solve. Timings only.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.sparse import linalg as splinalg

from _study_samples import study_sample_inputs
from _timing import timed

VARIANTS = {"20 vectors, tol 1e-3 (the set-up's)": {"tol": 1e-3},
            "13 vectors": {"tol": 1e-3, "ncv": 13},
            "16 vectors": {"tol": 1e-3, "ncv": 16},
            "24 vectors": {"tol": 1e-3, "ncv": 24},
            "tol 3e-3": {"tol": 3e-3}}


def standard_form(model):
    """L^-1 K L^-T on the free DOFs, as ttbpipe.timestepping.limits._stability_analysis forms it."""
    from ttbpipe.timestepping.limits import _mass_inverse_sqrt

    M, K, _ = model.matrices()
    free = np.flatnonzero(~model.fixed)
    K = K[free][:, free].tocsr()
    Linv = _mass_inverse_sqrt(model, M)
    return (Linv @ K @ Linv.T).tocsr()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", type=Path)
    parser.add_argument("--configfile", default="config/case2.yaml")
    parser.add_argument("--scenario", default="C4_mc")
    parser.add_argument("--samples", type=int, default=7)
    args = parser.parse_args()

    from ttbpipe.assessment.study import run_case
    from ttbpipe.simulation.setup import prepare
    from ttbpipe.study.samples import build_case, field_factors, mean_spectrum_irregularity

    _, rows, kwargs = study_sample_inputs(args.root, args.configfile, args.scenario)
    sim, structure, seed = kwargs["sim"], kwargs["structure"], kwargs["study_seed"]
    case = run_case(build_case(sim, structure, irregularity=mean_spectrum_irregularity(
        sim["irregularity"], seed)), kwargs.get("assessment"))
    for row in rows[:args.samples]:
        kind, index = str(row["kind"]), int(row["sample_index"])
        if kind not in ("fields", "fields_mc"):
            raise SystemExit(f"scenario {args.scenario}: kind {kind}, not a fields scenario")
        factors = field_factors(kwargs["fields"], structure, seed, str(row["condition"]), index,
                                method="mc" if kind == "fields_mc" else None)
        A = standard_form(prepare(case, factors=factors).structure)
        v0 = np.random.default_rng(20261121).standard_normal(A.shape[0])  # as the set-up
        reference = None
        for name, options in VARIANTS.items():
            products = [0]

            def matvec(x, products=products):
                products[0] += 1
                return A @ x

            operator = splinalg.LinearOperator(A.shape, matvec=matvec, dtype=float)

            def solve(operator=operator, options=options, products=products):
                products[0] = 0
                return splinalg.eigsh(operator, k=6, which="LA", v0=v0, **options)

            best, (w2, _) = timed(solve, 3)
            omega = np.sqrt(np.sort(w2)[::-1])
            reference = omega if reference is None else reference
            print(f"{args.scenario}/{index} {name:38s} {products[0]:4d} products "
                  f"{1e3 * best:6.1f} ms  top {omega[0]:9.3f} rad/s  six within "
                  f"{np.max(np.abs(omega - reference) / reference):.1e}")


if __name__ == "__main__":
    main()
