"""Cost of one implicit (Newmark) solve vs one explicit force evaluation, reference structure.

Newmark (average acceleration) needs K_eff = M + dt/2 C + dt^2/4 K factorised once and one
forward/back substitution per step (more with the vehicle's Hertz contact iterations), on top of
the same f - K u - C v evaluation the explicit method needs. This script times
(a) the explicit _structure_accelerations call, (b) a SuperLU solve with K_eff (scipy.sparse,
COLAMD ordering), (c) a banded Cholesky solve after reverse Cuthill-McKee reordering
(scipy.linalg.cho_solve_banded). CPU times (time.process_time), best of 5.

    NUMBA_NUM_THREADS=1 python benchmarks/structure_implicit_cost.py
"""

import time

import numpy as np
from scipy import linalg, sparse
from scipy.sparse import csgraph
from scipy.sparse import linalg as splinalg

from ttbpipe.structure import build_structure
from ttbpipe.structure.kernels import structure_accelerations as _structure_accelerations


def best(fn, n):
    fn()
    out = 1e9
    for _ in range(5):
        t = time.process_time()
        for _ in range(n):
            fn()
        out = min(out, (time.process_time() - t) / n)
    return out


def main():
    m = build_structure({})
    M, K, C = m.matrices()
    dt = 1e-4
    Keff = (M + 0.5 * dt * C + 0.25 * dt * dt * K).tocsc()
    rng = np.random.default_rng(0)
    b = rng.normal(size=m.n_dof)
    u = rng.normal(size=m.n_dof)
    acc = np.zeros(m.n_dof)
    t_exp = best(lambda: _structure_accelerations(m.packed, u, u, b, acc), 500)
    lu = splinalg.splu(Keff)
    t_lu = best(lambda: lu.solve(b), 200)
    perm = csgraph.reverse_cuthill_mckee(Keff.tocsr(), symmetric_mode=True)
    Kp = Keff[perm][:, perm].tocsr()
    coo = Kp.tocoo()
    bw = int(np.max(np.abs(coo.row - coo.col)))
    ab = np.zeros((bw + 1, m.n_dof))
    low = coo.row >= coo.col
    ab[coo.row[low] - coo.col[low], coo.col[low]] = coo.data[low]
    cb = linalg.cholesky_banded(ab, lower=True)
    bp = b[perm]
    t_band = best(lambda: linalg.cho_solve_banded((cb, True), bp), 200)
    print(f"DOF {m.n_dof}, RCM half-bandwidth {bw}, L nnz {lu.L.nnz + lu.U.nnz}")
    print(f"explicit force evaluation + lumped M^-1: {1e6 * t_exp:8.1f} us")
    print(f"SuperLU solve with K_eff:                 {1e6 * t_lu:8.1f} us (per right-hand side)")
    print(f"banded Cholesky solve (RCM):              {1e6 * t_band:8.1f} us")


if __name__ == "__main__":
    main()
