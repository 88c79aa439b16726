"""Global sparse (M, K, C) of the structure from its packed arrays.

The matrices of the static solve, the modal analysis and the time-step check, built from the
same packed arrays the kernels use (:class:`~ttbpipe.structure.kernels.StructurePacked`), with
the rail pads and the ballast in their generic three-row forms.

Two assemblies of the same matrices: :func:`assemble_matrices_by_element`, element by element
in Python (the obviously correct reference against which the kernels are tested), and
:func:`assemble_matrices`, the same entries in the same order computed for every element of a
kind at once with numpy (a structure is assembled once per sample of a study: the loops took
0.117 s on the default study's structure, the vectorised form 0.041 s). tests/test_structure_matrices.py
checks that the two are equal bit for bit.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .girder import hermite_shape
from .kernels import StructurePacked
from .shape_functions import hermite


def _beam_entries(packed: StructurePacked):
    """COO (rows, cols, K values, C values) of the beams: bending in two planes, torsion."""
    rows, cols, kv, cv = [], [], [], []
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
    return rows, cols, kv, cv


def _span_entries(packed: StructurePacked):
    """COO of the girder span blocks (K, C) and of the mass matrix (diagonal DOFs, span blocks)."""
    rows, cols, kv, cv = [], [], [], []
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
    return rows, cols, kv, cv, mrows, mcols, mv


def _csr(packed: StructurePacked, rows, cols, kv, cv, mrows, mcols, mv):
    n = packed.n_dof
    R, Cc = np.concatenate(rows), np.concatenate(cols)
    K = sparse.coo_matrix((np.concatenate(kv), (R, Cc)), shape=(n, n)).tocsr()
    C = sparse.coo_matrix((np.concatenate(cv), (R, Cc)), shape=(n, n)).tocsr()
    M = sparse.coo_matrix((np.concatenate(mv), (np.concatenate(mrows), np.concatenate(mcols))),
                          shape=(n, n)).tocsr()
    return M, K, C


def assemble_matrices_by_element(packed: StructurePacked):
    """Global sparse (M, K, C), CSR, from the packed arrays, element by element (the reference
    for the kernels and for :func:`assemble_matrices`).

    Fixed DOFs keep their (unit) mass and get no special treatment here; callers restrict to
    ``~model.fixed``.
    """
    rows, cols, kv, cv = _beam_entries(packed)
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
    srows, scols, skv, scv, mrows, mcols, mv = _span_entries(packed)
    return _csr(packed, rows + srows, cols + scols, kv + skv, cv + scv, mrows, mcols, mv)


def assemble_matrices(packed: StructurePacked):
    """Global sparse (M, K, C), CSR: :func:`assemble_matrices_by_element` with every element
    of a kind at once (the same COO entries in the same order, so the same matrices bit for
    bit). Fixed DOFs keep their (unit) mass; callers restrict to ``~model.fixed``."""
    rows, cols, kv, cv = _beam_entries(packed)
    a, b, e = _pairs(packed.link_ptr)
    outer = packed.link_coef[a] * packed.link_coef[b]
    rows.append(packed.link_dof[a]); cols.append(packed.link_dof[b])
    kv.append(packed.link_k[e] * outer); cv.append(packed.link_c[e] * outer)
    n_tri = packed.tri_k.size // 3
    groups = [(packed.tri_ptr, packed.tri_dof, packed.tri_coef.reshape(-1, 3),
               packed.tri_k.reshape(n_tri, 3), packed.tri_c.reshape(n_tri, 3)),
              _pad_rows_at_once(packed), _ballast_rows_at_once(packed)]
    for ptr, dof, coef, k3, c3 in groups:
        a, b, _ = _pairs(ptr)
        rows.append(dof[a]); cols.append(dof[b])
        kv.append(_three_row_products(ptr, coef, k3)); cv.append(_three_row_products(ptr, coef, c3))
    srows, scols, skv, scv, mrows, mcols, mv = _span_entries(packed)
    return _csr(packed, rows + srows, cols + scols, kv + skv, cv + scv, mrows, mcols, mv)


def _pairs(ptr: np.ndarray):
    """(a, b, element) of every ordered pair of entries of each element, whose entries are
    [ptr[e], ptr[e + 1]): element by element, a-major (the order of np.repeat / np.tile of
    one element's DOFs)."""
    ptr = np.asarray(ptr, dtype=np.int64)
    n = np.diff(ptr)
    sq = n * n
    element = np.repeat(np.arange(n.size), sq)
    offset = np.arange(int(sq.sum())) - np.repeat(np.cumsum(sq) - sq, sq)
    first, size = ptr[:-1][element], n[element]
    return first + offset // size, first + offset % size, element


def _three_row_products(ptr: np.ndarray, coef: np.ndarray, k3: np.ndarray) -> np.ndarray:
    """(coef_e * k3_e) @ coef_e.T of every element e (entries [ptr[e], ptr[e + 1]) of ``coef``),
    raveled element after element (the order of :func:`_pairs`). The elements of one size go
    through one stacked np.matmul, which multiplies slice by slice as the reference's one
    product per element does (the same BLAS call: the same sums, bit for bit)."""
    ptr = np.asarray(ptr, dtype=np.int64)
    n = np.diff(ptr)
    start = np.cumsum(n * n) - n * n
    out = np.empty(int((n * n).sum()))
    for size in np.unique(n):
        if size == 0:
            continue
        elements = np.flatnonzero(n == size)
        c = coef[ptr[elements][:, None] + np.arange(size)]           # (elements, size, 3)
        product = np.matmul(c * k3[elements][:, None, :], np.swapaxes(c, 1, 2))
        out[start[elements][:, None] + np.arange(size * size)] = product.reshape(elements.size, -1)
    return out


def _stacked(dofs: list[np.ndarray], coefs: list[np.ndarray]):
    """(ptr, dof, coef) of elements of equal size given as one array per slot: DOFs (element,)
    and coefficient rows (element, 3), slots in the reference's order."""
    dof = np.stack(dofs, axis=1)
    ptr = np.arange(dof.shape[0] + 1) * dof.shape[1]
    return ptr, dof.ravel(), np.stack(coefs, axis=1).reshape(-1, 3)


def _rows3(n: int, c0, c1, c2) -> np.ndarray:
    out = np.empty((n, 3))
    out[:, 0], out[:, 1], out[:, 2] = c0, c1, c2
    return out


def _pad_rows_at_once(packed: StructurePacked):
    """(ptr, dof, coef (entries, 3), k3 (pads, 3), c3) of every rail pad: the rows of
    :func:`pad_link_rows` in its order (slab pads, sleeper pads, pads on rigid ground)."""
    d_f = float(packed.pad_foot_depth)
    t_half = float(packed.pad_seat_half_thickness)
    n_slab, n_ballast = int(packed.pad_group[0]), int(packed.pad_group[1])
    n_pad = packed.pad_rail.size
    rd = np.asarray(packed.pad_rail, dtype=np.int64)
    geom = np.asarray(packed.pad_geom, dtype=float).reshape(-1, 3)
    parts = []
    bounds = ((0, n_slab), (n_slab, n_slab + n_ballast), (n_slab + n_ballast, n_pad))
    for seat, (first, last) in zip(("slab", "sleeper", "rigid"), bounds):
        n = last - first
        r = rd[first:last]
        dofs = [r, r + 2, r + 4]
        coefs = [_rows3(n, 1.0, 0.0, 0.0), _rows3(n, 0.0, 1.0, 0.0), _rows3(n, 0.0, d_f, 1.0)]
        xi, L, e = geom[first:last, 0], geom[first:last, 1], geom[first:last, 2]
        if seat == "slab":    # slab seat: Hermite rows of the slab element's nodes a, b
            da = np.asarray(packed.pad_seat_a[first:last], dtype=np.int64)
            db = np.asarray(packed.pad_seat_b[first:last], dtype=np.int64)
            # the shape functions' own formula, on arrays (the kernel's Python function)
            N = hermite.py_func(xi, L)
            for column, offset in ((0, 0), (1, 2)):
                for q, n_q in zip((da + offset, da + offset + 1, db + offset, db + offset + 1), N):
                    row = np.zeros((n, 3))
                    row[:, column] = 0.0 - n_q
                    dofs.append(q); coefs.append(row)
            for q, w in ((da + 4, 1.0 - xi), (db + 4, xi)):
                dofs.append(q); coefs.append(_rows3(n, 0.0 - e * w, 0.0 + t_half * w, 0.0 - w))
        elif seat == "sleeper":    # sleeper seat: z, y, roll of the sleeper
            sd = np.asarray(packed.pad_seat_a[first:last], dtype=np.int64)
            dofs += [sd, sd + 1, sd + 2]
            coefs += [_rows3(n, -1.0, 0.0, 0.0), _rows3(n, 0.0, -1.0, 0.0), _rows3(n, -e, 0.0, -1.0)]
        ptr, dof, coef = _stacked(dofs, coefs)
        parts.append((ptr, dof, coef))
    ptr, dof, coef = _concatenate_elements(parts)
    return (ptr, dof, coef, np.asarray(packed.pad_k).reshape(n_pad, 3),
            np.asarray(packed.pad_c).reshape(n_pad, 3))


def _ballast_rows_at_once(packed: StructurePacked):
    """(ptr, dof, coef, k3, c3) of the ballasted track: the rows of :func:`ballast_link_rows`
    in its order (per sleeper: the blocks under rails 0 and 1, then the lateral resistance)."""
    k, c, e0 = np.asarray(packed.bal_k), np.asarray(packed.bal_c), float(packed.bal_half_gauge)
    sd = np.asarray(packed.bal_sleeper, dtype=np.int64)
    n = sd.size
    nxt = np.asarray(packed.bal_next, dtype=bool)
    dofs, coefs, valid = [], [], []
    for side in range(2):
        e = e0 if side == 0 else -e0
        bd = np.asarray(packed.bal_block, dtype=np.int64) + side
        dofs += [sd, sd + 2, bd, bd + 2]
        coefs += [_rows3(n, 1.0, 0.0, 0.0), _rows3(n, e, 0.0, 0.0),
                  _rows3(n, -1.0, 1.0, np.where(nxt, 1.0, 0.0)), _rows3(n, 0.0, 0.0, -1.0)]
        valid += [np.ones(n, bool), np.ones(n, bool), np.ones(n, bool), nxt]
    dofs.append(sd + 1); coefs.append(_rows3(n, 1.0, 0.0, 0.0)); valid.append(np.ones(n, bool))
    valid = np.stack(valid, axis=1)
    dof = np.stack(dofs, axis=1)
    coef = np.stack(coefs, axis=1)
    slot_element = np.array([0, 0, 0, 0, 1, 1, 1, 1, 2])     # element of each slot in a sleeper
    counts = np.stack([valid[:, slot_element == i].sum(axis=1) for i in range(3)], axis=1)
    ptr = np.concatenate([[0], np.cumsum(counts.ravel())])
    k2, c2 = np.where(nxt, k[2], 0.0), np.where(nxt, c[2], 0.0)
    k3 = np.empty((n, 3, 3))
    c3 = np.empty((n, 3, 3))
    for side in range(2):
        k3[:, side] = _rows3(n, k[0], k[1], k2)
        c3[:, side] = _rows3(n, c[0], c[1], c2)
    k3[:, 2] = _rows3(n, k[3], 0.0, 0.0)
    c3[:, 2] = _rows3(n, c[3], 0.0, 0.0)
    return ptr, dof[valid], coef[valid], k3.reshape(-1, 3), c3.reshape(-1, 3)


def _concatenate_elements(parts):
    """(ptr, dof, coef) of several element groups one after the other."""
    ptrs, offset = [np.zeros(1, dtype=np.int64)], 0
    for ptr, _, _ in parts:
        ptrs.append(ptr[1:] + offset)
        offset += int(ptr[-1])
    return (np.concatenate(ptrs), np.concatenate([d for _, d, _ in parts]),
            np.concatenate([c for _, _, c in parts]).reshape(-1, 3))


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
