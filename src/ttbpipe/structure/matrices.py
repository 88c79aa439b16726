"""Global sparse (M, K, C) of the structure from its packed arrays.

The reference against which the kernels are tested (tests/test_structure_kernels.py), and the
matrices of the modal analysis and the time-step check: built from the same packed arrays the
kernels use (:class:`~ttbpipe.structure.kernels.StructurePacked`), with the rail pads and the
ballast in their generic three-row forms.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .girder import hermite_shape
from .kernels import StructurePacked


def assemble_matrices(packed: StructurePacked):
    """Global sparse (M, K, C), CSR, from the packed arrays (reference for the kernels).

    Fixed DOFs keep their (unit) mass and get no special treatment here; callers restrict to
    ``~model.fixed``.
    """
    n = packed.n_dof
    rows, cols, kv, cv = [], [], [], []
    # beams
    a, b, L = packed.beam_dof_a, packed.beam_dof_b, packed.beam_L
    for plane, EI in ((0, packed.beam_EIv), (1, packed.beam_EIl)):
        d = np.stack([a + 2 * plane, a + 2 * plane + 1, b + 2 * plane, b + 2 * plane + 1], 1)
        s = EI / L ** 3
        ke = np.empty((L.size, 4, 4))
        base = [[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]]
        powers = [[0, 1, 0, 1], [1, 2, 1, 2], [0, 1, 0, 1], [1, 2, 1, 2]]
        for i in range(4):
            for j in range(4):
                ke[:, i, j] = s * base[i][j] * L ** powers[i][j]
        rows.append(np.repeat(d, 4, axis=1).ravel()); cols.append(np.tile(d, 4).ravel())
        kv.append(ke.ravel()); cv.append(np.zeros(ke.size))
    d = np.stack([a + 4, b + 4], 1)
    kt = packed.beam_GK / L
    ke = np.stack([kt, -kt, -kt, kt], 1)
    rows.append(np.repeat(d, 2, axis=1).ravel()); cols.append(np.tile(d, 2).ravel())
    kv.append(ke.ravel()); cv.append(np.zeros(ke.size))
    # links
    for l in range(packed.link_k.size):
        j0, j1 = packed.link_ptr[l], packed.link_ptr[l + 1]
        dof, coef = packed.link_dof[j0:j1], packed.link_coef[j0:j1]
        outer = np.outer(coef, coef).ravel()
        rows.append(np.repeat(dof, dof.size)); cols.append(np.tile(dof, dof.size))
        kv.append(packed.link_k[l] * outer); cv.append(packed.link_c[l] * outer)
    # link triples: three links over one DOF list
    for t in range(packed.tri_k.size // 3):
        j0, j1 = packed.tri_ptr[t], packed.tri_ptr[t + 1]
        dof = packed.tri_dof[j0:j1]
        coef = packed.tri_coef[3 * j0:3 * j1].reshape(-1, 3)
        kt = (coef * packed.tri_k[3 * t:3 * t + 3]) @ coef.T
        ct = (coef * packed.tri_c[3 * t:3 * t + 3]) @ coef.T
        rows.append(np.repeat(dof, dof.size)); cols.append(np.tile(dof, dof.size))
        kv.append(kt.ravel()); cv.append(ct.ravel())
    # rail pads and ballast: the generic three-row forms (the kernels compute them in place)
    for dof, coef, k3, c3 in (*pad_link_rows(packed), *ballast_link_rows(packed)):
        kt = (coef * k3) @ coef.T
        ct = (coef * c3) @ coef.T
        rows.append(np.repeat(dof, dof.size)); cols.append(np.tile(dof, dof.size))
        kv.append(kt.ravel()); cv.append(ct.ravel())
    # spans
    mrows, mcols, mv = [np.arange(packed.n_diag)], [np.arange(packed.n_diag)], []
    with np.errstate(divide="ignore"):
        diag = np.where(packed.inv_mass[:packed.n_diag] > 0,
                        1.0 / packed.inv_mass[:packed.n_diag], 1.0)
    mv.append(diag)
    for s in range(packed.span_dof0.size):
        o, m, base = packed.span_dof0[s], packed.span_n[s], packed.span_mat0[s]
        idx = np.arange(o, o + m)
        r_, c_ = np.repeat(idx, m), np.tile(idx, m)
        rows.append(r_); cols.append(c_)
        kv.append(packed.span_K[base:base + m * m]); cv.append(packed.span_C[base:base + m * m])
        Minv = packed.span_Minv[base:base + m * m].reshape(m, m)
        Mb = _span_mass_from_inverse(Minv)
        mrows.append(r_); mcols.append(c_); mv.append(Mb.ravel())
    R, Cc = np.concatenate(rows), np.concatenate(cols)
    K = sparse.coo_matrix((np.concatenate(kv), (R, Cc)), shape=(n, n)).tocsr()
    C = sparse.coo_matrix((np.concatenate(cv), (R, Cc)), shape=(n, n)).tocsr()
    M = sparse.coo_matrix((np.concatenate(mv), (np.concatenate(mrows), np.concatenate(mcols))),
                          shape=(n, n)).tocsr()
    return M, K, C


def pad_link_rows(packed: StructurePacked):
    """Yield (dofs, coef (n, 3), k3, c3) of every rail pad: the vertical, lateral and roll
    relative displacements as linear forms of the DOFs (the paper's eq. 22 with the seat's shape
    functions), from the compact pad arrays. Reference for :func:`kernels._pad_forces`."""
    d_f = float(packed.pad_foot_depth)
    t_half = float(packed.pad_seat_half_thickness)
    n_slab, n_ballast = int(packed.pad_group[0]), int(packed.pad_group[1])
    for p in range(packed.pad_rail.size):
        rd = int(packed.pad_rail[p])
        xi, L, e = packed.pad_geom[3 * p:3 * p + 3]
        rows = {rd: [1.0, 0.0, 0.0], rd + 2: [0.0, 1.0, 0.0], rd + 4: [0.0, d_f, 1.0]}
        if p < n_slab:
            da, db = int(packed.pad_seat_a[p]), int(packed.pad_seat_b[p])
            N = hermite_shape(xi, L)
            for q, n_q in zip((da, da + 1, db, db + 1), N):
                rows.setdefault(q, [0.0, 0.0, 0.0])[0] -= n_q
            for q, n_q in zip((da + 2, da + 3, db + 2, db + 3), N):
                rows.setdefault(q, [0.0, 0.0, 0.0])[1] -= n_q
            for q, w in ((da + 4, 1.0 - xi), (db + 4, xi)):
                r = rows.setdefault(q, [0.0, 0.0, 0.0])
                r[0] -= e * w
                r[1] += t_half * w
                r[2] -= w
        elif p < n_slab + n_ballast:
            sd = int(packed.pad_seat_a[p])
            rows[sd] = [-1.0, 0.0, 0.0]
            rows[sd + 1] = [0.0, -1.0, 0.0]
            rows[sd + 2] = [-e, 0.0, -1.0]
        dof = np.fromiter(rows, dtype=np.int64)
        coef = np.array([rows[q] for q in rows])
        yield dof, coef, packed.pad_k[3 * p:3 * p + 3], packed.pad_c[3 * p:3 * p + 3]


def ballast_link_rows(packed: StructurePacked):
    """Yield (dofs, coef (n, 3), k3, c3) of the ballasted track: per block the sleeper-block,
    block-subgrade and block-next-block springs, per sleeper its lateral resistance (as a row
    with one active direction). Reference for :func:`kernels._ballast_forces`."""
    k, c, e0 = packed.bal_k, packed.bal_c, float(packed.bal_half_gauge)
    for j in range(packed.bal_sleeper.size):
        sd = int(packed.bal_sleeper[j])
        for side in range(2):
            e = e0 if side == 0 else -e0
            bd = int(packed.bal_block[j]) + side
            nxt = bool(packed.bal_next[j])
            dof = np.array([sd, sd + 2, bd] + ([bd + 2] if nxt else []), dtype=np.int64)
            coef = np.zeros((dof.size, 3))
            coef[:3, 0] = [1.0, e, -1.0]
            coef[2, 1] = 1.0
            if nxt:
                coef[2, 2], coef[3, 2] = 1.0, -1.0
            yield (dof, coef, np.array([k[0], k[1], k[2] if nxt else 0.0]),
                   np.array([c[0], c[1], c[2] if nxt else 0.0]))
        yield (np.array([sd + 1], dtype=np.int64), np.array([[1.0, 0.0, 0.0]]),
               np.array([k[3], 0.0, 0.0]), np.array([c[3], 0.0, 0.0]))


def _span_mass_from_inverse(Minv: np.ndarray) -> np.ndarray:
    """Mass block from the stored inverse; fixed coordinates (zero rows) get a unit mass."""
    free = np.any(Minv != 0, axis=1)
    M = np.eye(Minv.shape[0])
    M[np.ix_(free, free)] = np.linalg.inv(Minv[np.ix_(free, free)])
    return M
