"""Could a fields sample's set-up do without its own global matrices? (docs/performance.md,
"Where a fields sample's set-up goes").

    python benchmarks/fields_setup_alternatives.py [--config config/config.yaml] [--samples 2]

For ``--samples`` samples of each fields condition of the study (default study: C1 rail, C2
pads, C3 CA mortar, C4 girders), prints

* the time to assemble the sample's global matrices and to factorise its free-DOF stiffness
  (sparse LU: what the set-up does today);
* the static solve of a random load by conjugate gradients on the sample's stiffness,
  preconditioned with the nominal structure's LU (scipy ``cg``, relative tolerance 1e-12):
  iterations, time, and the difference to the direct solve relative to its peak;
* the top structural frequency from the sample's own stability analysis, the nominal one, and
  a Rayleigh-quotient upper bound from the nominal one and the range of the sample's factors
  (omega^2 <= lambda_nominal * max factor / min factor, valid when every element's stiffness
  and mass contributions are scaled by factors inside that range).

A sample whose structure has another DOF count than the nominal one (girder factors change how
many girder modes fall below the cut-off) cannot be preconditioned with the nominal LU; it is
reported as such. Timings only; run on a quiet machine.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla
import yaml

from ttbpipe.structure import build_structure
from ttbpipe.structure.static import StructureStatic
from ttbpipe.study.samples import field_factors
from ttbpipe.timestepping.limits import _stability_analysis

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=str(ROOT / "config" / "config.yaml"))
    parser.add_argument("--samples", type=int, default=2)
    args = parser.parse_args()
    cfg = yaml.safe_load(Path(args.config).read_text())
    structure, seed, fields = cfg.get("structure", {}), cfg["study"]["seed"], cfg["fields"]
    nominal = build_structure(structure)
    nominal_lu = StructureStatic(nominal)._lu
    omega_nominal = _stability_analysis(nominal, 6)["omega_max_rad_s"]
    free = ~np.asarray(nominal.fixed, dtype=bool)
    load = np.random.default_rng(1).standard_normal(int(free.sum())) * 1e4
    for condition in fields.get("groups", {}):
        for index in range(args.samples):
            factors = field_factors(fields, structure, seed, condition, index)
            model = build_structure(structure, factors=factors)
            ranges = [np.asarray(v, dtype=float) for v in factors.values()]
            f_min = min(float(v.min()) for v in ranges)
            f_max = max(float(v.max()) for v in ranges)
            head = (f"{condition} sample {index} ({', '.join(sorted(factors))}; "
                    f"factors {f_min:.2f}-{f_max:.2f})")
            if model.n_dof != nominal.n_dof:
                print(f"{head}: {model.n_dof} DOF against the nominal {nominal.n_dof}: "
                      "no nominal preconditioner")
                continue
            t = time.perf_counter()
            _, stiffness, _ = model.matrices()
            t_assembly = time.perf_counter() - t
            k_free = stiffness.tocsr()[free][:, free]
            t = time.perf_counter()
            lu = spla.splu(k_free.tocsc())
            t_lu = time.perf_counter() - t
            direct = lu.solve(load)
            iterations = [0]

            def count(_):
                iterations[0] += 1

            preconditioner = spla.LinearOperator(k_free.shape, matvec=nominal_lu.solve)
            t = time.perf_counter()
            iterative, info = spla.cg(k_free, load, M=preconditioner, rtol=1e-12, atol=0.0,
                                      maxiter=500, callback=count)
            t_cg = time.perf_counter() - t
            difference = np.abs(iterative - direct).max() / np.abs(direct).max()
            omega = _stability_analysis(model, 6)["omega_max_rad_s"]
            bound = omega_nominal * np.sqrt(f_max / f_min)
            print(f"{head}: assembly {1e3 * t_assembly:.0f} ms, LU {1e3 * t_lu:.0f} ms; "
                  f"PCG {iterations[0]} iterations {1e3 * t_cg:.0f} ms (status {info}, "
                  f"difference {difference:.1e}); top omega {omega:.0f} rad/s, nominal "
                  f"{omega_nominal:.0f}, bound {bound:.0f}")


if __name__ == "__main__":
    main()
