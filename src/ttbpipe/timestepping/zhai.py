"""Zhai's explicit two-step time integration: the update kernel and its linear stability.

One home of the time integrator every loop of ttbpipe uses (the coupled train-track-bridge
loop, the structure's moving-load loop): :func:`zhai_predict` advances displacements and
velocities from the accelerations of this and the previous step (Zhai 1996, IJNME 39:4199;
physics.md section 5). Its stability on a linear system is the spectral radius of the one-step
amplification matrix (:func:`zhai_amplification_matrix`); :func:`zhai_critical_omega_dt` gives
the critical omega dt of one damped mode, :func:`zhai_critical_time_step` the largest stable step
of a linear system. The limits of the models (structure, contact, vehicle, coupled) are
:mod:`ttbpipe.timestepping.limits`.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from ..index_ranges import range_span
from ..jit import kernel


@kernel(creates_arrays=False)
def zhai_predict(disp, vel, acc, acc_prev, dt, psi, phi):
    """Zhai's explicit two-step update of displacement and velocity, in place; the step's
    accelerations then become the previous ones (``acc_prev`` = ``acc``), ready for the
    accelerations of the new step.

    X_{n+1} = X_n + V_n dt + (1/2 + psi) A_n dt^2 - psi A_{n-1} dt^2,
    V_{n+1} = V_n + (1 + phi) A_n dt - phi A_{n-1} dt   (Zhai 1996, IJNME 39:4199;
    physics.md section 5). psi = phi = 0 on the first step, 1/2 afterwards. One pass over
    the arrays: the shift in a loop of its own cost the reference case's step 1-2 %.
    """
    _zhai_predict_span(disp, vel, acc, acc_prev, dt, psi, phi, np.uint64(0),
                       np.uint64(disp.shape[0]))


@kernel(creates_arrays=False)
def zhai_predict_ranges(disp, vel, acc, acc_prev, dt, psi, phi, ranges, n_ranges):
    """:func:`zhai_predict` on the entries in the first ``n_ranges`` rows [start, end) of
    ``ranges`` (end -1: to the last entry). The others must hold zero velocity and
    accelerations (the frozen track of a moving window, :mod:`ttbpipe.structure.window`): the
    update would leave them as they are."""
    for k in range(n_ranges):
        i0, i1 = range_span(ranges, k, disp.shape[0])
        _zhai_predict_span(disp, vel, acc, acc_prev, dt, psi, phi, i0, i1)


@kernel(inline="always")
def _zhai_predict_span(disp, vel, acc, acc_prev, dt, psi, phi, i0, i1):
    """:func:`zhai_predict` on entries [i0, i1) (unsigned: numba then drops the negative-index
    test on every access, which would keep the loop from being vectorised)."""
    h2 = dt * dt
    ca = (0.5 + psi) * h2
    cp = psi * h2
    va = (1.0 + phi) * dt
    vp = phi * dt
    for i in range(i0, i1):
        a = acc[i]
        ap = acc_prev[i]
        disp[i] += vel[i] * dt + ca * a - cp * ap
        vel[i] += va * a - vp * ap
        acc_prev[i] = a


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


def zhai_critical_omega_dt(zeta: float) -> float:
    """Largest omega*dt at which Zhai's scheme (psi = phi = 1/2) is stable on one damped mode.

    Omega_c = 2 (sqrt(1 + 4 zeta^2) - 2 zeta): where a root of the characteristic polynomial of
    :func:`zhai_amplification`, lambda (lambda - 1)^2 + Omega^2 [(3 lambda - 1)/2 + (lambda - 1/2)
    (lambda - 1)] + 2 zeta Omega (3 lambda - 1)(lambda - 1)/2, reaches lambda = -1
    (docs/reference/physics.md section 5): 2.0 undamped, 1.81 at zeta = 0.05, 1/(2 zeta) for a
    stiff damper. tests/test_vehicle_step_limit.py checks it against the bisection of the
    amplification matrix's spectral radius (a second method) for zeta in [0, 100]. A negative
    zeta (round-off of a positive semi-definite damping) counts as 0.
    """
    zeta = max(float(zeta), 0.0)
    return float(2.0 * (np.sqrt(1.0 + 4.0 * zeta * zeta) - 2.0 * zeta))
