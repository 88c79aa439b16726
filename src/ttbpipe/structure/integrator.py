"""Time integration of the structure: Zhai's explicit method, its stability limit, the time loop.

Zhai's two-step explicit method (Zhai 1996, IJNME 39:4199; physics.md section 5) with lumped
(diagonal) mass for rails, slab, sleepers, ballast and piers and a small dense inverse mass per
girder span block: no factorisation, no global matrix in the loop. The choice against Newmark and
the measurements behind it are in docs/structure.md.
"""

from __future__ import annotations

import logging
from functools import lru_cache

import numpy as np
from numba import njit
from scipy import sparse
from scipy.sparse import linalg as splinalg

from .kernels import (_add_rail_point_force_at, _structure_accelerations,
                      _zhai_predict)

log = logging.getLogger(__name__)


def zhai_amplification(omega_dt: float, zeta: float, psi: float = 0.5,
                       phi: float = 0.5) -> np.ndarray:
    """Amplification matrix of Zhai's method on x'' + 2 zeta w x' + w^2 x = 0.

    State (x, v dt, a dt^2, a_prev dt^2) at step n -> n+1, from the update formulas of
    physics.md section 5 with a_{n+1} = -w^2 x_{n+1} - 2 zeta w v_{n+1}: the one-DOF case of
    :func:`zhai_amplification_matrix` (unit mass, dt = 1).
    """
    O = omega_dt
    return zhai_amplification_matrix(np.ones(1), np.array([[O * O]]),
                                     np.array([[2 * zeta * O]]), 1.0, psi, phi)


def zhai_amplification_matrix(inv_mass: np.ndarray, stiffness: np.ndarray, damping: np.ndarray,
                              dt: float, psi: float = 0.5, phi: float = 0.5) -> np.ndarray:
    """Amplification matrix (4n x 4n) of Zhai's method on M x'' + C x' + K x = 0, M diagonal.

    State (x, v dt, a dt^2, a_prev dt^2) at step n -> n+1 (physics.md section 5):
    x' = x + v dt + (1/2 + psi) a dt^2 - psi a_prev dt^2, v' dt = v dt + (1 + phi) a dt^2 -
    phi a_prev dt^2, a' dt^2 = -M^-1 (K dt^2 x' + C dt (v' dt)), a_prev' = a. Dense arrays.
    """
    inv_mass = np.asarray(inv_mass, dtype=float)
    n = inv_mass.size
    eye = np.eye(n)
    A = np.zeros((4 * n, 4 * n))
    A[:n, :n], A[:n, n:2 * n] = eye, eye
    A[:n, 2 * n:3 * n], A[:n, 3 * n:] = (0.5 + psi) * eye, -psi * eye
    A[n:2 * n, n:2 * n] = eye
    A[n:2 * n, 2 * n:3 * n], A[n:2 * n, 3 * n:] = (1.0 + phi) * eye, -phi * eye
    kt = dt * dt * inv_mass[:, None] * np.asarray(stiffness, dtype=float)
    ct = dt * inv_mass[:, None] * np.asarray(damping, dtype=float)
    A[2 * n:3 * n] = -kt @ A[:n] - ct @ A[n:2 * n]
    A[3 * n:, 2 * n:3 * n] = eye
    return A


#: Spectral-radius tolerance of the linear stability checks: growth below 1e-6 per step is
#: < 10 % over 1e5 steps, and it absorbs the rounding of defective eigenvalues at 1 (rigid-body
#: modes: a Jordan block perturbed by eps splits by ~sqrt(eps) = 1.5e-8).
SPECTRAL_RADIUS_TOL = 1e-6


def zhai_spectral_radius(inv_mass, stiffness, damping, dt: float) -> float:
    """Largest |eigenvalue| of :func:`zhai_amplification_matrix` (psi = phi = 1/2)."""
    return float(np.max(np.abs(np.linalg.eigvals(
        zhai_amplification_matrix(inv_mass, stiffness, damping, dt)))))


def _decoupled_blocks(stiffness: np.ndarray, damping: np.ndarray) -> list[np.ndarray]:
    """DOF sets that K and C do not couple (connected components of their sparsity graph)."""
    from scipy.sparse.csgraph import connected_components

    pattern = (np.abs(stiffness) + np.abs(damping)) > 0.0
    n_comp, label = connected_components(sparse.csr_matrix(pattern), directed=False)
    return [np.flatnonzero(label == c) for c in range(n_comp)]


def zhai_critical_time_step(inv_mass, stiffness, damping, rtol: float = 1e-2) -> dict:
    """Largest dt at which Zhai's scheme (psi = phi = 1/2) is stable on M x'' + C x' + K x = 0.

    Linear, M diagonal, K and C symmetric positive semi-definite (so the exact solution does
    not grow and any growth is the scheme's). Criterion: spectral radius of
    :func:`zhai_amplification_matrix` <= 1 + :data:`SPECTRAL_RADIUS_TOL`. The DOFs are split into
    the blocks that K and C do not couple; per block, a scan up from a safe step by factors
    1.25 (starting at half of min(2/omega_max, 1/gamma_max), the undamped and pure-damper
    limits, with omega_max^2 and gamma_max the largest eigenvalues of M^-1/2 K M^-1/2 and
    M^-1/2 C M^-1/2) finds the first unstable step, then bisection narrows it to ``rtol``.
    Returns the stable end: dt_limit_s (inf without stiffness or damping), the block's DOF
    indices ``dofs`` and ``mode_dof``, the DOF with the largest mass-weighted amplitude in the
    growing mode just above the limit, and ``evaluations`` (eigenvalue problems solved).
    """
    inv_mass = np.asarray(inv_mass, dtype=float)
    stiffness = np.asarray(stiffness, dtype=float)
    damping = np.asarray(damping, dtype=float)
    best = {"dt_limit_s": np.inf, "dofs": np.zeros(0, dtype=np.int64), "mode_dof": -1,
            "evaluations": 0}
    for dofs in _decoupled_blocks(stiffness, damping):
        mi, k, c = inv_mass[dofs], stiffness[np.ix_(dofs, dofs)], damping[np.ix_(dofs, dofs)]
        if not (k.any() or c.any()):
            continue
        s = np.sqrt(mi)
        w2 = float(np.linalg.eigvalsh(s[:, None] * k * s[None, :]).max())
        g = float(np.linalg.eigvalsh(s[:, None] * c * s[None, :]).max())
        est = min(2.0 / np.sqrt(w2) if w2 > 0 else np.inf, 1.0 / g if g > 0 else np.inf)

        def stable(dt: float) -> bool:
            best["evaluations"] += 1
            return zhai_spectral_radius(mi, k, c, dt) <= 1.0 + SPECTRAL_RADIUS_TOL

        lo = 0.5 * est
        while not stable(lo):
            lo *= 0.5
            if lo < 1e-6 * est:   # pragma: no cover - not seen for PSD K and C
                raise ValueError("Zhai stability: no stable step found for a linear block")
        hi = lo * 1.25
        while stable(hi):
            lo, hi = hi, hi * 1.25
            if hi > 1e3 * est:    # pragma: no cover - stable far beyond the estimate
                lo = hi = np.inf
                break
        while hi / lo > 1.0 + rtol:
            mid = np.sqrt(lo * hi)
            lo, hi = (mid, hi) if stable(mid) else (lo, mid)
        if lo < best["dt_limit_s"]:
            w, vec = np.linalg.eig(zhai_amplification_matrix(mi, k, c, hi * (1.0 + rtol)))
            x = vec[:dofs.size, int(np.argmax(np.abs(w)))]
            best.update(dt_limit_s=float(lo), dofs=dofs,
                        mode_dof=int(dofs[int(np.argmax(np.abs(x) / s))]))
    return best


@lru_cache(maxsize=256)
def zhai_critical_omega_dt(zeta: float) -> float:
    """Largest omega*dt with spectral radius <= 1 (bisection); 2.0 undamped, ~1.81 at zeta 0.05."""
    def stable(O: float) -> bool:
        return np.max(np.abs(np.linalg.eigvals(zhai_amplification(O, zeta)))) <= 1.0 + 1e-9
    lo, hi = 1e-3, 4.0
    if not stable(lo):
        return 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def _mass_inverse_sqrt(model, M):
    """Sparse L^-1 with M_ff = L L^T on the free DOFs (diagonal part + dense span blocks)."""
    free = ~model.fixed
    nd = model.packed.n_diag
    diag = M.diagonal()[:nd][free[:nd]]
    blocks = [sparse.diags(1.0 / np.sqrt(diag))]
    for o, red in zip(model.dof_info["span_dof0"], model.spans):
        f = free[o:o + red.n]
        if f.any():
            L = np.linalg.cholesky(red.M[np.ix_(f, f)])
            blocks.append(sparse.csr_matrix(np.linalg.inv(L)))
    return sparse.block_diag(blocks).tocsr()


def stable_time_step(model, safety: float = 0.9, n_modes: int = 6) -> dict:
    """Stability limit of Zhai's method for this structure.

    The top ``n_modes`` eigenpairs of (K, M), computed as the largest eigenvalues of the
    standard form L^-1 K L^-T (M = L L^T, block-diagonal so L is cheap; ARPACK, ~0.05 s for
    the reference structure), give omega and the modal damping ratio
    zeta = x^T C x / (2 omega) with x = L^-T y; each mode allows dt = Omega_crit(zeta) / omega.
    Returns the minimum times ``safety`` with its mode.
    """
    M, K, C = model.matrices()
    free = np.flatnonzero(~model.fixed)
    K, C = (A[free][:, free].tocsr() for A in (K, C))
    Linv = _mass_inverse_sqrt(model, M)
    A = (Linv @ K @ Linv.T).tocsr()
    k = min(n_modes, free.size - 2)
    # loose tol: the top eigenvalues are clustered (identical rail bays), so tight vector
    # convergence costs thousands of iterations. For a symmetric matrix each Ritz value is within
    # the residual tol*|lambda| of an eigenvalue (and its vector's Rayleigh quotient within
    # ~tol^2): tol 1e-3 bounds omega to 0.05 %, far inside the 0.9 safety factor. Measured on
    # the reference case: tol 1e-3 0.03 s vs 1e-5 0.55 s, top four omega identical to 1e-10,
    # limit unchanged (docs/performance.md). Fixed start vector: deterministic run time/result.
    v0 = np.random.default_rng(20261121).standard_normal(A.shape[0])
    w2, vec = splinalg.eigsh(A, k=k, which="LA", tol=1e-3, v0=v0)
    best = None
    for i in range(w2.size):
        w = np.sqrt(max(w2[i], 0.0))
        if w <= 0:
            continue
        x = Linv.T @ vec[:, i]
        zeta = float(x @ (C @ x)) / (2 * w)
        dt = zhai_critical_omega_dt(round(zeta, 6)) / w
        if best is None or dt < best["dt_limit_s"]:
            best = {"dt_limit_s": dt, "omega_rad_s": w, "frequency_hz": w / (2 * np.pi),
                    "zeta": zeta}
    best["dt_s"] = safety * best["dt_limit_s"]
    best["omega_max_rad_s"] = float(np.sqrt(np.max(w2)))
    return best


def check_time_step(model, dt: float) -> dict:
    """Raise ValueError naming the remedy when dt exceeds the Zhai stability limit."""
    info = stable_time_step(model, safety=1.0)
    if dt > info["dt_limit_s"]:
        raise ValueError(
            f"time step dt={dt:.3g} s exceeds the Zhai stability limit {info['dt_limit_s']:.3g} s "
            f"of this structure (mode at {info['frequency_hz']:.0f} Hz, damping ratio "
            f"{info['zeta']:.3f}); set simulation.time_step_s <= "
            f"{0.9 * info['dt_limit_s']:.3g}, or raise structure.rail.rotary_inertia_scaling / "
            "coarsen structure.slab.element_length_m (see docs/structure.md)")
    return info


@njit(cache=True)
def _run_moving_loads(packed, load_rail, load_x0, load_v, load_F0, load_F1, load_freq,
                      load_phase, extra_dofs, extra_force, dt, n_steps, out_every,
                      mon_ptr, mon_dof, mon_coef, mon_qty, disp, vel, acc, acc_prev,
                      nodal_force, out, blowup_m):
    """Zhai time loop with moving point loads on the rails; records monitors every out_every steps.

    Load i: rail load_rail[i], position x = load_x0[i] + load_v[i] t, forces
    (Fz, Fy, Mx) = load_F0[i] + load_F1[i] sin(2 pi load_freq[i] t + load_phase[i]).
    extra_force[step, j] is added to DOF extra_dofs[j] (loads acting directly on the girder
    coordinates, for girder-only validation). Monitor channel c is sum_j mon_coef_j q[mon_dof_j]
    with q = disp, vel or acc (mon_qty[c] = 0, 1, 2). Returns the step at which a monitored or
    rail value exceeded ``blowup_m`` or became NaN (-1 if none).
    """
    n_loads = load_rail.shape[0]
    n_mon = mon_qty.shape[0]
    n_extra = extra_dofs.shape[0]
    rail_x0, rail_dx, rail_n_nodes = packed.rail_x0, packed.rail_dx, packed.rail_n_nodes
    if packed.n_rails == 0:
        rail_n_nodes = 0
    rail_dof0 = packed.rail_dof0
    row = 0
    for step in range(n_steps + 1):
        t = step * dt
        if step > 0:
            psi = 0.0 if step == 1 else 0.5
            _zhai_predict(disp, vel, acc, acc_prev, dt, psi, psi)
            for i in range(disp.shape[0]):
                acc_prev[i] = acc[i]
        for i in range(nodal_force.shape[0]):
            nodal_force[i] = 0.0
        for i in range(n_loads):
            x = load_x0[i] + load_v[i] * t
            s = np.sin(2.0 * np.pi * load_freq[i] * t + load_phase[i])
            # scalar-geometry form: no StructurePacked pass per load (docs/performance.md)
            _add_rail_point_force_at(rail_x0, rail_dx, rail_n_nodes, rail_dof0[load_rail[i]], x,
                                     load_F0[i, 0] + load_F1[i, 0] * s,
                                     load_F0[i, 1] + load_F1[i, 1] * s,
                                     load_F0[i, 2] + load_F1[i, 2] * s, nodal_force)
        if n_extra > 0:
            for j in range(n_extra):
                nodal_force[extra_dofs[j]] += extra_force[step, j]
        _structure_accelerations(packed, disp, vel, nodal_force, acc)
        if step % out_every == 0:
            out[row, 0] = t
            bad = False
            for c in range(n_mon):
                v = 0.0
                for j in range(mon_ptr[c], mon_ptr[c + 1]):
                    q = mon_dof[j]
                    if mon_qty[c] == 0:
                        v += mon_coef[j] * disp[q]
                    elif mon_qty[c] == 1:
                        v += mon_coef[j] * vel[q]
                    else:
                        v += mon_coef[j] * acc[q]
                out[row, 1 + c] = v
                if mon_qty[c] == 0 and not (abs(v) < blowup_m):
                    bad = True
            row += 1
            if bad:
                return step
        if step % 1000 == 0:
            for i in range(packed.n_diag):
                if not (abs(disp[i]) < blowup_m):
                    return step
    return -1
