"""How much longer a step would a rail (and slab) without slope inertia allow? (docs/performance.md)

The explicit step of the coupled model is bounded by the structure's highest mode and by the
Hertz contact mode (``ttbpipe.timestepping.limits``: coupled bound omega_c^2 <= omega_s^2 +
omega_H^2 by Weyl's inequality). The structure's highest modes are the rail's slope DOFs. A rail
with translational DOFs only (slopes following the nodal displacements, as a discrete Kirchhoff
or cubic-spline rail would have them) removes those modes without building that rail: the slope
DOFs are made massless and condensed statically, K_c = K_tt - K_ts K_ss^-1 K_st, and the top
eigenvalues of M_tt^-1 K_c are computed (ARPACK on the mass-normalised operator, one sparse LU of
K_ss). Same for the slab beam's slope DOFs, which bind next.

Prints, for the reference case (``config/reference_case.yaml``): the Hertz limit, the structure's
highest mode and the coupled limit as built, with the rail slopes massless, and with the rail and
slab slopes massless, and which DOFs the highest mode moves; the as-built row beside the
coupled limit ttbpipe's own check computes (a second method). About 8 s on one core.

    python benchmarks/step_limits_without_slope_inertia.py
"""

from __future__ import annotations

import logging

import numpy as np
import yaml
from scipy.sparse import linalg as splinalg

from ttbpipe.simulation.setup import prepare
from ttbpipe.structure.rail_mesh import NODE_DOFS, Y_OFFSET, rail_mesh, rail_node_dofs
from ttbpipe.timestepping.limits import _mass_inverse_sqrt
from ttbpipe.timestepping.zhai import zhai_critical_omega_dt

#: offsets of the vertical and lateral slope in a 5-DOF beam node (z, dz/dx, y, dy/dx, roll)
SLOPE_OFFSETS = (1, Y_OFFSET + 1)


def slope_dofs(structure, with_slab: bool) -> np.ndarray:
    """Boolean mask of the rails' (and optionally the slab's) slope DOFs."""
    mask = np.zeros(structure.n_dof, dtype=bool)
    mesh = rail_mesh(structure.packed, 0.0)
    nodes = [rail_node_dofs(mesh, r) for r in range(int(mesh.n_rails))]
    if with_slab:
        nodes.append(np.asarray(structure.dof_info["slab_node_dof0"], dtype=np.int64))
    for base in nodes:
        for offset in SLOPE_OFFSETS:
            mask[base + offset] = True
    return mask


def kind_of_dofs(structure) -> np.ndarray:
    """A label per DOF: rail or slab node DOF (z, slope_z, y, slope_y, roll), else 'other'."""
    names = np.array(["z", "slope_z", "y", "slope_y", "roll"])
    kind = np.full(structure.n_dof, "other", dtype=object)
    mesh = rail_mesh(structure.packed, 0.0)
    for r in range(int(mesh.n_rails)):
        base = rail_node_dofs(mesh, r)
        for o in range(NODE_DOFS):
            kind[base + o] = "rail " + names[o]
    base = np.asarray(structure.dof_info["slab_node_dof0"], dtype=np.int64)
    for o in range(NODE_DOFS):
        kind[base + o] = "slab " + names[o]
    return kind


def top_mode(structure, massless: np.ndarray, kinds: np.ndarray, n_modes: int = 4):
    """(omega_max, label of the DOF kind with the largest share of the top mode's kinetic energy)
    of the structure with the DOFs ``massless`` condensed out (``kinds``: :func:`kind_of_dofs`)."""
    M, K, _ = structure.matrices()
    free = np.flatnonzero(~structure.fixed)
    l_inv = _mass_inverse_sqrt(structure, M)            # M_ff = L L^T, block-diagonal
    cond = massless[free]
    keep = ~cond
    K = K[free][:, free].tocsr()
    l_keep = l_inv[keep][:, keep].tocsr()               # the condensed DOFs have diagonal mass
    k_tt, k_ts = K[keep][:, keep], K[keep][:, cond]
    k_st = K[cond][:, keep]
    lu = splinalg.splu(K[cond][:, cond].tocsc()) if cond.any() else None

    def matvec(y):
        x = l_keep.T @ y
        f = k_tt @ x
        if lu is not None:
            f = f - k_ts @ lu.solve(k_st @ x)
        return l_keep @ f

    n = l_keep.shape[0]
    op = splinalg.LinearOperator((n, n), matvec=matvec, dtype=float)
    v0 = np.random.default_rng(20261204).standard_normal(n)
    w2, y = splinalg.eigsh(op, k=n_modes, which="LA", tol=1e-6, v0=v0)
    top = int(np.argmax(w2))
    kinetic = y[:, top] ** 2                            # mass-normalised: y^2 is kinetic energy
    kinds = kinds[free][keep]
    shares = {k: float(kinetic[kinds == k].sum()) for k in np.unique(kinds)}
    return float(np.sqrt(w2[top])), max(shares, key=shares.get)


def main() -> None:
    logging.getLogger("ttbpipe").setLevel(logging.WARNING)
    with open("config/reference_case.yaml") as fh:
        case = yaml.safe_load(fh)
    setup = prepare(case)
    structure, limits = setup.structure, setup.dt_limits
    omega_h = float(limits["omega_hertz_rad_s"])
    crit = zhai_critical_omega_dt(0.0)
    print(f"reference case, step {setup.dt:.3g} s; Hertz mode {omega_h:.0f} rad/s, limit "
          f"{crit / omega_h:.3g} s (with safety 0.9: {limits['dt_hertz_s']:.3g} s)")
    print(f"{'model':38s} {'omega_max rad/s':>15s} {'moved most':>14s} {'structure':>10s} "
          f"{'coupled':>9s} {'x now':>6s}")
    rows = [("as built (slopes with rotary inertia)", np.zeros(structure.n_dof, dtype=bool)),
            ("rail slopes massless", slope_dofs(structure, with_slab=False)),
            ("rail and slab slopes massless", slope_dofs(structure, with_slab=True))]
    kinds = kind_of_dofs(structure)
    base = None
    for label, massless in rows:
        omega, kind = top_mode(structure, massless, kinds)
        # undamped Omega_crit = 2 for every row alike (the top mode's zeta 0.013 lowers the
        # limit by about 3 %, as the last line shows), so the ratios compare the modes alone
        coupled = crit / np.hypot(omega, omega_h)
        base = base or coupled
        print(f"{label:38s} {omega:15.0f} {kind:>14s} {crit / omega:10.3g} {coupled:9.3g} "
              f"{coupled / base:6.2f}")
    print(f"as built, ttbpipe's check (damped): coupled limit {limits['dt_coupled_limit_s']:.3g} s, "
          f"structure {limits['dt_structure_limit_s']:.3g} s")


if __name__ == "__main__":
    main()
