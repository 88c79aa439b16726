"""Would advancing several samples in lockstep make the structure step cheaper per sample?

Measures, on the default structure (`build_structure({})`: 7 742 DOF), two of the structure
kernel's parts -- the beam elements (rails and slab, 1 205 elements) and the CA link triples (189
triples, 30 DOFs each) --
as they run today (one sample per call, K calls) against prototype lockstep kernels written
here, which carry K samples side by side (displacements, velocities and forces of shape
(n_dof, K), the sample index innermost so that the K operations on one DOF are contiguous and
can be vectorised) and per-sample stiffness and damping (random property fields differ between
samples; shape (n, K)). Both variants compute the same forces (checked to 1e-12 relative).
Prints CPU microseconds per sample and call (best of 5 alternating rounds of 3 x 2000
calls, repeated inside numba)
for K = 1, 2, 4, 8, 16.

This is a measurement for docs/performance.md ("lockstep samples"), not production code.

    NUMBA_NUM_THREADS=1 python benchmarks/lockstep_kernels.py
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from ttbpipe.jit import kernel  # noqa: E402
from ttbpipe.structure import build_structure  # noqa: E402
from ttbpipe.structure.kernels import _EVERY_ELEMENT, _beam_forces, _triple_forces  # noqa: E402


@kernel
def _beam_forces_lockstep(dof_a, dof_b, length, ei_v, ei_l, gk, disp, force):
    """_beam_forces for K samples: disp, force (n_dof, K); ei_v, ei_l, gk (n_beam, K)."""
    n_samples = disp.shape[1]
    for e in range(length.shape[0]):
        a = dof_a[e]
        b = dof_b[e]
        L = length[e]
        inv_l3 = 1.0 / (L * L * L)
        for plane in range(2):
            off = 2 * plane
            for k in range(n_samples):
                s = (ei_v[e, k] if plane == 0 else ei_l[e, k]) * inv_l3
                w1 = disp[a + off, k]
                t1 = disp[a + off + 1, k]
                w2 = disp[b + off, k]
                t2 = disp[b + off + 1, k]
                dw = w1 - w2
                f1 = s * (12.0 * dw + 6.0 * L * (t1 + t2))
                m1 = s * L * (6.0 * dw + L * (4.0 * t1 + 2.0 * t2))
                m2 = s * L * (6.0 * dw + L * (2.0 * t1 + 4.0 * t2))
                force[a + off, k] -= f1
                force[a + off + 1, k] -= m1
                force[b + off, k] += f1
                force[b + off + 1, k] -= m2
        for k in range(n_samples):
            kt = gk[e, k] / L * (disp[a + 4, k] - disp[b + 4, k])
            force[a + 4, k] -= kt
            force[b + 4, k] += kt


@kernel
def _triple_forces_lockstep(ptr, dofs, coef, stiff, damp, disp, vel, force, scratch):
    """_triple_forces for K samples: disp, vel, force (n_dof, K); stiff, damp (3 n_tri, K);
    scratch (6, K)."""
    n_samples = disp.shape[1]
    for t in range(stiff.shape[0] // 3):
        j0 = ptr[t]
        j1 = ptr[t + 1]
        scratch[:, :] = 0.0
        for j in range(j0, j1):
            q = dofs[j]
            c0 = coef[3 * j]
            c1 = coef[3 * j + 1]
            c2 = coef[3 * j + 2]
            for k in range(n_samples):
                u = disp[q, k]
                w = vel[q, k]
                scratch[0, k] += c0 * u
                scratch[1, k] += c1 * u
                scratch[2, k] += c2 * u
                scratch[3, k] += c0 * w
                scratch[4, k] += c1 * w
                scratch[5, k] += c2 * w
        for k in range(n_samples):
            scratch[0, k] = stiff[3 * t, k] * scratch[0, k] + damp[3 * t, k] * scratch[3, k]
            scratch[1, k] = stiff[3 * t + 1, k] * scratch[1, k] + damp[3 * t + 1, k] * scratch[4, k]
            scratch[2, k] = stiff[3 * t + 2, k] * scratch[2, k] + damp[3 * t + 2, k] * scratch[5, k]
        for j in range(j0, j1):
            q = dofs[j]
            c0 = coef[3 * j]
            c1 = coef[3 * j + 1]
            c2 = coef[3 * j + 2]
            for k in range(n_samples):
                force[q, k] -= c0 * scratch[0, k] + c1 * scratch[1, k] + c2 * scratch[2, k]


# Drivers: the repetitions run inside numba, so that the time is the kernels' own and not
# Python's call overhead (unboxing the packed structure costs microseconds per call).
@kernel
def _repeat_beams_today(packs, disp, vel, force, calls):
    for _ in range(calls):
        for k in range(len(packs)):
            _beam_forces(packs[k], disp[k], vel[k], force[k], _EVERY_ELEMENT, 1)


@kernel
def _repeat_triples_today(packs, disp, vel, force, calls):
    for _ in range(calls):
        for k in range(len(packs)):
            _triple_forces(packs[k], disp[k], vel[k], force[k], _EVERY_ELEMENT, 1)


@kernel
def _repeat_beams_lockstep(dof_a, dof_b, length, ei_v, ei_l, gk, disp, force, calls):
    for _ in range(calls):
        _beam_forces_lockstep(dof_a, dof_b, length, ei_v, ei_l, gk, disp, force)


@kernel
def _repeat_triples_lockstep(ptr, dofs, coef, stiff, damp, disp, vel, force, scratch, calls):
    for _ in range(calls):
        _triple_forces_lockstep(ptr, dofs, coef, stiff, damp, disp, vel, force, scratch)


ROUNDS = 5


def best_us(fn, calls: int = 2000, repeat: int = 3) -> float:
    """Best CPU time of ``fn(calls)`` over ``repeat`` runs, per call (us)."""
    fn(1)
    out = np.inf
    for _ in range(repeat):
        t = time.process_time()
        fn(calls)
        out = min(out, (time.process_time() - t) / calls)
    return 1e6 * out


def main() -> None:
    model = build_structure({})
    p = model.packed
    n = p.n_dof
    rng = np.random.default_rng(1)
    print(f"reference structure: {n} DOF, {p.beam_L.size} beam elements, "
          f"{p.tri_k.size // 3} link triples ({p.tri_dof.size} DOF entries)")
    print("| part | K | today: K calls, us per sample | lockstep, us per sample | ratio |")
    print("|---|---|---|---|---|")
    for k_samples in (1, 2, 4, 8, 16):
        disp = rng.standard_normal((n, k_samples)) * 1e-4
        vel = rng.standard_normal((n, k_samples)) * 1e-3
        factors = 1.0 + 0.1 * rng.standard_normal((p.beam_L.size, k_samples))
        ei_v = p.beam_EIv[:, None] * factors
        ei_l = p.beam_EIl[:, None] * factors
        gk = p.beam_GK[:, None] * factors
        tri_factors = 1.0 + 0.1 * rng.standard_normal((p.tri_k.size, k_samples))
        stiff = p.tri_k[:, None] * tri_factors
        damp = p.tri_c[:, None] * tri_factors
        # today's kernels: one packed structure per sample (its own property arrays)
        packs = [p._replace(beam_EIv=np.ascontiguousarray(ei_v[:, k]),
                            beam_EIl=np.ascontiguousarray(ei_l[:, k]),
                            beam_GK=np.ascontiguousarray(gk[:, k]),
                            tri_k=np.ascontiguousarray(stiff[:, k]),
                            tri_c=np.ascontiguousarray(damp[:, k])) for k in range(k_samples)]
        packs = tuple(packs)
        d_rows = np.ascontiguousarray(disp.T)          # (K, n_dof): one sample per row
        v_rows = np.ascontiguousarray(vel.T)
        f_rows = np.zeros((k_samples, n))
        force = np.zeros((n, k_samples))
        scratch = np.zeros((6, k_samples))

        def beams_today(calls):
            _repeat_beams_today(packs, d_rows, v_rows, f_rows, calls)

        def beams_lockstep(calls):
            _repeat_beams_lockstep(p.beam_dof_a, p.beam_dof_b, p.beam_L, ei_v, ei_l, gk, disp,
                                   force, calls)

        def triples_today(calls):
            _repeat_triples_today(packs, d_rows, v_rows, f_rows, calls)

        def triples_lockstep(calls):
            _repeat_triples_lockstep(p.tri_ptr, p.tri_dof, p.tri_coef, stiff, damp, disp, vel,
                                     force, scratch, calls)

        for name, today, lock in (("beams", beams_today, beams_lockstep),
                                  ("CA triples", triples_today, triples_lockstep)):
            f_rows[:] = 0.0
            force[:] = 0.0
            today(1)
            lock(1)
            reference = f_rows.T
            scale = np.abs(reference).max()
            assert np.abs(force - reference).max() <= 1e-12 * scale, name
            # alternate the two variants, keep each one's best: the machine is shared
            t_today, t_lock = np.inf, np.inf
            for _ in range(ROUNDS):
                t_today = min(t_today, best_us(today) / k_samples)
                t_lock = min(t_lock, best_us(lock) / k_samples)
            print(f"| {name} | {k_samples} | {t_today:.2f} | {t_lock:.2f} | "
                  f"{t_today / t_lock:.2f} |", flush=True)


if __name__ == "__main__":
    main()
