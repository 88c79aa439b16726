"""Would advancing several samples in lockstep make the structure step cheaper per sample?

Measures, on the default structure (`build_structure({})`: 7 742 DOF), three of the structure
kernel's parts -- the beam elements (rails and slab, 1 205 elements), the rail pads (1 144) and
the CA link triples (189 triples, 30 DOFs each) --
as they run today (one sample per call, K calls) against prototype lockstep kernels written
here, which carry K samples side by side (displacements, velocities and forces of shape
(n_dof, K), the sample index innermost so that the K operations on one DOF are contiguous and
can be vectorised) and per-sample stiffness and damping (random property fields differ between
samples; shape (n, K)). The lockstep triples read the entries in the groups of today's kernel
(`group_triple_entries`: only the non-zero coefficients); the lockstep pads run one loop per pad
group, so that the sample loop has no branch. Both variants compute the same forces (checked
to 1e-12 relative).
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
from ttbpipe.structure.kernels import (_EVERY_ELEMENT, _beam_forces, _pad_forces,  # noqa: E402
                                       _triple_forces)
from ttbpipe.structure.shape_functions import hermite  # noqa: E402


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
def _add_vertical(dofs, coef, disp, vel, j0, j1, scratch):
    """Add the vertical link's terms of entries [j0, j1) to scratch rows 0 and 3 (K samples)."""
    for j in range(j0, j1):
        q = dofs[j]
        c0 = coef[3 * j]
        for k in range(disp.shape[1]):
            scratch[0, k] += c0 * disp[q, k]
            scratch[3, k] += c0 * vel[q, k]


@kernel
def _add_lateral_roll(dofs, coef, disp, vel, j0, j1, scratch):
    """Add the lateral and roll links' terms of entries [j0, j1) to scratch rows 1, 2, 4, 5."""
    for j in range(j0, j1):
        q = dofs[j]
        c1 = coef[3 * j + 1]
        c2 = coef[3 * j + 2]
        for k in range(disp.shape[1]):
            u = disp[q, k]
            w = vel[q, k]
            scratch[1, k] += c1 * u
            scratch[2, k] += c2 * u
            scratch[4, k] += c1 * w
            scratch[5, k] += c2 * w


@kernel
def _triple_forces_lockstep(ptr, group_end, dofs, coef, stiff, damp, disp, vel, force, scratch):
    """_triple_forces for K samples: disp, vel, force (n_dof, K); stiff, damp (3 n_tri, K);
    scratch (6, K). The entries in the groups of ``group_triple_entries`` (vertical only, lateral
    and roll only, general), each group reading its non-zero coefficients, as today's kernel
    does (the CA mortar has no general entry)."""
    n_samples = disp.shape[1]
    for t in range(stiff.shape[0] // 3):
        j0 = ptr[t]
        j_lat = group_end[2 * t]
        j_gen = group_end[2 * t + 1]
        j1 = ptr[t + 1]
        scratch[:, :] = 0.0
        _add_vertical(dofs, coef, disp, vel, j0, j_lat, scratch)
        _add_lateral_roll(dofs, coef, disp, vel, j_lat, j_gen, scratch)
        _add_vertical(dofs, coef, disp, vel, j_gen, j1, scratch)
        _add_lateral_roll(dofs, coef, disp, vel, j_gen, j1, scratch)
        for k in range(n_samples):
            scratch[0, k] = stiff[3 * t, k] * scratch[0, k] + damp[3 * t, k] * scratch[3, k]
            scratch[1, k] = stiff[3 * t + 1, k] * scratch[1, k] + damp[3 * t + 1, k] * scratch[4, k]
            scratch[2, k] = stiff[3 * t + 2, k] * scratch[2, k] + damp[3 * t + 2, k] * scratch[5, k]
        for j in range(j0, j_lat):
            q = dofs[j]
            c0 = coef[3 * j]
            for k in range(n_samples):
                force[q, k] -= c0 * scratch[0, k]
        for j in range(j_lat, j_gen):
            q = dofs[j]
            c1 = coef[3 * j + 1]
            c2 = coef[3 * j + 2]
            for k in range(n_samples):
                force[q, k] -= c1 * scratch[1, k] + c2 * scratch[2, k]
        for j in range(j_gen, j1):
            q = dofs[j]
            c0 = coef[3 * j]
            c1 = coef[3 * j + 1]
            c2 = coef[3 * j + 2]
            for k in range(n_samples):
                force[q, k] -= c0 * scratch[0, k] + c1 * scratch[1, k] + c2 * scratch[2, k]


@kernel
def _pad_rail_motion(disp, vel, rd, d_f, k):
    """Sample k's rail-side relative motion of a pad: (dz, dy, dr, vz, vy, vr)."""
    return (disp[rd, k], disp[rd + 2, k] + d_f * disp[rd + 4, k], disp[rd + 4, k],
            vel[rd, k], vel[rd + 2, k] + d_f * vel[rd + 4, k], vel[rd + 4, k])


@kernel
def _pad_link_forces(stiff, damp, force, p3, rd, d_f, k, dz, dy, dr, vz, vy, vr):
    """Sample k's pad forces (pz, py, pr) from its relative motion; subtracts them from the rail
    node (the foot's lateral force also as a roll moment) and returns them for the seat."""
    pz = stiff[p3, k] * dz + damp[p3, k] * vz
    py = stiff[p3 + 1, k] * dy + damp[p3 + 1, k] * vy
    pr = stiff[p3 + 2, k] * dr + damp[p3 + 2, k] * vr
    force[rd, k] -= pz
    force[rd + 2, k] -= py
    force[rd + 4, k] -= d_f * py + pr
    return pz, py, pr


@kernel
def _pad_forces_lockstep(rail, seat_a, seat_b, geom, n_slab, n_slab_ballast, d_f, t_half,
                         stiff, damp, disp, vel, force):
    """_pad_forces for K samples: disp, vel, force (n_dof, K); stiff, damp (3 n_pad, K). One
    loop per pad group (slab, sleepers, rigid ground), so that the sample loop has no branch;
    the shape values of a slab pad are computed once for its K samples."""
    n_samples = disp.shape[1]
    for p in range(n_slab):
        p3 = 3 * p
        rd = rail[p]
        e = geom[p3 + 2]
        da = seat_a[p]
        db = seat_b[p]
        xi = geom[p3]
        n1, n2, n3, n4 = hermite(xi, geom[p3 + 1])
        wa = 1.0 - xi
        for k in range(n_samples):
            dz, dy, dr, vz, vy, vr = _pad_rail_motion(disp, vel, rd, d_f, k)
            rs = wa * disp[da + 4, k] + xi * disp[db + 4, k]
            vrs = wa * vel[da + 4, k] + xi * vel[db + 4, k]
            dz -= (n1 * disp[da, k] + n2 * disp[da + 1, k] + n3 * disp[db, k]
                   + n4 * disp[db + 1, k] + e * rs)
            dy += t_half * rs - (n1 * disp[da + 2, k] + n2 * disp[da + 3, k]
                                 + n3 * disp[db + 2, k] + n4 * disp[db + 3, k])
            dr -= rs
            vz -= (n1 * vel[da, k] + n2 * vel[da + 1, k] + n3 * vel[db, k]
                   + n4 * vel[db + 1, k] + e * vrs)
            vy += t_half * vrs - (n1 * vel[da + 2, k] + n2 * vel[da + 3, k]
                                  + n3 * vel[db + 2, k] + n4 * vel[db + 3, k])
            vr -= vrs
            pz, py, pr = _pad_link_forces(stiff, damp, force, p3, rd, d_f, k,
                                          dz, dy, dr, vz, vy, vr)
            force[da, k] += n1 * pz
            force[da + 1, k] += n2 * pz
            force[db, k] += n3 * pz
            force[db + 1, k] += n4 * pz
            force[da + 2, k] += n1 * py
            force[da + 3, k] += n2 * py
            force[db + 2, k] += n3 * py
            force[db + 3, k] += n4 * py
            q = e * pz - t_half * py + pr
            force[da + 4, k] += wa * q
            force[db + 4, k] += xi * q
    for p in range(n_slab, n_slab_ballast):
        p3 = 3 * p
        rd = rail[p]
        e = geom[p3 + 2]
        sd = seat_a[p]
        for k in range(n_samples):
            dz, dy, dr, vz, vy, vr = _pad_rail_motion(disp, vel, rd, d_f, k)
            dz -= disp[sd, k] + e * disp[sd + 2, k]
            dy -= disp[sd + 1, k]
            dr -= disp[sd + 2, k]
            vz -= vel[sd, k] + e * vel[sd + 2, k]
            vy -= vel[sd + 1, k]
            vr -= vel[sd + 2, k]
            pz, py, pr = _pad_link_forces(stiff, damp, force, p3, rd, d_f, k,
                                          dz, dy, dr, vz, vy, vr)
            force[sd, k] += pz
            force[sd + 1, k] += py
            force[sd + 2, k] += e * pz + pr
    for p in range(n_slab_ballast, rail.shape[0]):
        p3 = 3 * p
        rd = rail[p]
        for k in range(n_samples):
            dz, dy, dr, vz, vy, vr = _pad_rail_motion(disp, vel, rd, d_f, k)
            pz, py, pr = _pad_link_forces(stiff, damp, force, p3, rd, d_f, k,
                                          dz, dy, dr, vz, vy, vr)


# Drivers: the repetitions run inside numba, so that the time is the kernels' own and not
# Python's call overhead (unboxing the packed structure costs microseconds per call).
# Today's kernels, one sample per call; part: 0 beams, 1 rail pads, 2 link triples (a code, as
# numba does not cache a kernel that takes a compiled function as an argument).
BEAMS, PADS, TRIPLES = 0, 1, 2


@kernel
def _repeat_today(part, packs, disp, vel, force, calls):
    for _ in range(calls):
        for k in range(len(packs)):
            if part == BEAMS:
                _beam_forces(packs[k], disp[k], vel[k], force[k], _EVERY_ELEMENT, 1)
            elif part == PADS:
                _pad_forces(packs[k], disp[k], vel[k], force[k], _EVERY_ELEMENT, 1)
            else:
                _triple_forces(packs[k], disp[k], vel[k], force[k], _EVERY_ELEMENT, 1)


@kernel
def _repeat_beams_lockstep(dof_a, dof_b, length, ei_v, ei_l, gk, disp, force, calls):
    for _ in range(calls):
        _beam_forces_lockstep(dof_a, dof_b, length, ei_v, ei_l, gk, disp, force)


@kernel
def _repeat_triples_lockstep(ptr, group_end, dofs, coef, stiff, damp, disp, vel, force,
                             scratch, calls):
    for _ in range(calls):
        _triple_forces_lockstep(ptr, group_end, dofs, coef, stiff, damp, disp, vel, force, scratch)


@kernel
def _repeat_pads_lockstep(rail, seat_a, seat_b, geom, n_slab, n_slab_ballast, d_f, t_half,
                          stiff, damp, disp, vel, force, calls):
    for _ in range(calls):
        _pad_forces_lockstep(rail, seat_a, seat_b, geom, n_slab, n_slab_ballast, d_f, t_half,
                             stiff, damp, disp, vel, force)


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
          f"{p.pad_rail.size} rail pads, "
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
        pad_factors = 1.0 + 0.1 * rng.standard_normal((p.pad_k.size, k_samples))
        pad_stiff = p.pad_k[:, None] * pad_factors
        pad_damp = p.pad_c[:, None] * pad_factors
        # today's kernels: one packed structure per sample (its own property arrays)
        packs = [p._replace(beam_EIv=np.ascontiguousarray(ei_v[:, k]),
                            beam_EIl=np.ascontiguousarray(ei_l[:, k]),
                            beam_GK=np.ascontiguousarray(gk[:, k]),
                            tri_k=np.ascontiguousarray(stiff[:, k]),
                            tri_c=np.ascontiguousarray(damp[:, k]),
                            pad_k=np.ascontiguousarray(pad_stiff[:, k]),
                            pad_c=np.ascontiguousarray(pad_damp[:, k]))
                 for k in range(k_samples)]
        packs = tuple(packs)
        d_rows = np.ascontiguousarray(disp.T)          # (K, n_dof): one sample per row
        v_rows = np.ascontiguousarray(vel.T)
        f_rows = np.zeros((k_samples, n))
        force = np.zeros((n, k_samples))
        scratch = np.zeros((6, k_samples))

        def beams_today(calls):
            _repeat_today(BEAMS, packs, d_rows, v_rows, f_rows, calls)

        def beams_lockstep(calls):
            _repeat_beams_lockstep(p.beam_dof_a, p.beam_dof_b, p.beam_L, ei_v, ei_l, gk, disp,
                                   force, calls)

        def triples_today(calls):
            _repeat_today(TRIPLES, packs, d_rows, v_rows, f_rows, calls)

        def triples_lockstep(calls):
            _repeat_triples_lockstep(p.tri_ptr, p.tri_group_end, p.tri_kernel_dof,
                                     p.tri_kernel_coef, stiff, damp, disp, vel, force, scratch,
                                     calls)

        n_slab = int(p.pad_group[0])
        n_slab_ballast = n_slab + int(p.pad_group[1])

        def pads_today(calls):
            _repeat_today(PADS, packs, d_rows, v_rows, f_rows, calls)

        def pads_lockstep(calls):
            _repeat_pads_lockstep(p.pad_rail, p.pad_seat_a, p.pad_seat_b, p.pad_geom, n_slab,
                                  n_slab_ballast, p.pad_foot_depth, p.pad_seat_half_thickness,
                                  pad_stiff, pad_damp, disp, vel, force, calls)

        for name, today, lock in (("beams", beams_today, beams_lockstep),
                                  ("rail pads", pads_today, pads_lockstep),
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
