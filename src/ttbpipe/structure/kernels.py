"""Numba kernels of the track-bridge structure: forces, rail point kinematics and loads, Zhai step.

The structure is linear: M a + C v + K u = f. Its arrays are packed in :class:`StructurePacked`
(built by :mod:`ttbpipe.structure.assembly`); the kernels evaluate K u and C v element by
element (no global matrix in the time loop):

* beams (both rails and the slab): Hermite cubic bending in the vertical and lateral planes and
  linear torsion, per-element E*I and G*K (paper eqs. 12-13);
* links: every discrete or lumped spring-damper (sleepers and ballast, bearings, piers) as a
  relative displacement d = sum_j coef_j u_{dof_j}, force k d + c d', and the transposed scatter
  (paper eqs. 22-27 with the shape functions folded into coef); CA quadrature points as link
  *triples* (vertical, lateral, roll over one shared DOF list); rail pads and the ballasted
  track in compact forms (:func:`_pad_forces`, :func:`_ballast_forces`);
* girder spans: a dense reduced block per span (Craig-Bampton boundary + fixed-interface modal
  coordinates) with its own K, Rayleigh C (eq. 18) and the inverse of its mass block.

DOFs ``[0, n_diag)`` have a diagonal (lumped) mass; the span blocks follow.
Node layout of beams (5 DOF): z, dz/dx, y, dy/dx, roll. Loads and kinematics at points of the
rails: :mod:`ttbpipe.structure.rail_mesh` (the interface to whatever runs on the rails).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..index_ranges import range_span as _element_span
from ..jit import kernel
from .shape_functions import hermite

StructurePacked = namedtuple("StructurePacked", [
    "n_dof", "n_diag", "inv_mass",
    "beam_dof_a", "beam_dof_b", "beam_L", "beam_EIv", "beam_EIl", "beam_GK",
    "link_ptr", "link_dof", "link_coef", "link_k", "link_c",
    "span_dof0", "span_n", "span_mat0", "span_K", "span_C", "span_Minv", "span_scratch",
    "n_rails", "rail_x0", "rail_dx", "rail_n_nodes", "rail_dof0",
    "tri_ptr", "tri_dof", "tri_coef", "tri_k", "tri_c",
    "pad_rail", "pad_seat_a", "pad_seat_b", "pad_geom", "pad_k", "pad_c", "pad_group",
    "pad_foot_depth", "pad_seat_half_thickness",
    "bal_sleeper", "bal_block", "bal_next", "bal_k", "bal_c", "bal_half_gauge",
    "tri_group_end", "tri_kernel_dof", "tri_kernel_coef", "tri_run_of_three",
])
# Link triples, rail pads and ballast default to none, so that a structure without them (a bare
# girder, rails on rigid ground) is built by keyword without listing them.
StructurePacked.__new__.__defaults__ = (
    np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0),
    np.zeros(0),
    np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64),
    np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(3, dtype=np.int64), 0.0, 0.0,
    np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64),
    np.zeros(4), np.zeros(4), 0.0,
    np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0),
    np.zeros(0, dtype=np.uint8))


# Element indices are unsigned in the element loops: numba then drops the negative-index
# wrap-around test on every access it makes with them (10-15 % of the beam and pad loops).
_ONE, _TWO, _THREE = np.uint64(1), np.uint64(2), np.uint64(3)


@kernel(inline="always")
def _node_values(values, d):
    """The five values of a beam node from DOF ``d`` on (z, dz/dx, y, dy/dx, roll)."""
    return values[d], values[d + 1], values[d + 2], values[d + 3], values[d + 4]


@kernel(inline="always")
def _set_node_values(values, d, v0, v1, v2, v3, v4):
    """Write the five values of a beam node from DOF ``d`` on."""
    values[d] = v0
    values[d + 1] = v1
    values[d + 2] = v2
    values[d + 3] = v3
    values[d + 4] = v4


@kernel(inline="always")
def _hermite_end_forces(EI, L, w1, t1, w2, t2):
    """(f1, m1, m2) of a Hermite beam element in one plane: k_e [w1, t1, w2, t2] is
    (f1, m1, -f1, m2)."""
    s = EI / (L * L * L)
    dw = w1 - w2
    f1 = s * (12.0 * dw + 6.0 * L * (t1 + t2))
    m1 = s * L * (6.0 * dw + L * (4.0 * t1 + 2.0 * t2))
    m2 = s * L * (6.0 * dw + L * (2.0 * t1 + 4.0 * t2))
    return f1, m1, m2


@kernel(creates_arrays=False)
def _beam_forces(packed, disp, vel, force, ranges, n_ranges):
    """Subtract the elastic forces K_e u_e of every beam element (rails and slab) from ``force``.

    Hermite element, slopes as DOFs: k = EI/L^3 [[12, 6L, -12, 6L], [6L, 4L^2, -6L, 2L^2],
    [-12, -6L, 12, -6L], [6L, 2L^2, -6L, 4L^2]] (Przemieniecki 1968; paper eq. 13), the same
    matrix for the vertical (EIv) and lateral (EIl) planes; torsion GK/L [[1, -1], [-1, 1]].
    Beams carry no internal damping (pads and CA carry it).

    The elements of a rail or of the slab are stored in a chain, node b of one being node a of
    the next (5 DOF per node: z, dz/dx, y, dy/dx, roll). Along a chain the shared node's
    displacements and its force are kept from one element to the next and its force written
    once, after both elements have added theirs: half the memory traffic of reading and
    writing both end nodes per element. Every force receives the same terms in the same order
    as element by element, so the results are the same numbers; an element that does not
    continue the chain writes the pending node first.
    """
    n_beam = packed.beam_L.shape[0]
    for k in range(n_ranges):
        e0, e1 = _element_span(ranges, k, n_beam)
        prev_b = -1
        # node b of the previous element: its displacements (u*) and its force so far (g*)
        u0 = u1 = u2 = u3 = u4 = 0.0
        g0 = g1 = g2 = g3 = g4 = 0.0
        for e in range(e0, e1):
            a = packed.beam_dof_a[e]
            b = packed.beam_dof_b[e]
            L = packed.beam_L[e]
            if a == prev_b:
                w1, t1, y1, s1, r1 = u0, u1, u2, u3, u4
                fa0, fa1, fa2, fa3, fa4 = g0, g1, g2, g3, g4
            else:
                if prev_b >= 0:
                    _set_node_values(force, prev_b, g0, g1, g2, g3, g4)
                w1, t1, y1, s1, r1 = _node_values(disp, a)
                fa0, fa1, fa2, fa3, fa4 = _node_values(force, a)
            u0, u1, u2, u3, u4 = _node_values(disp, b)
            g0, g1, g2, g3, g4 = _node_values(force, b)
            f1, m1, m2 = _hermite_end_forces(packed.beam_EIv[e], L, w1, t1, u0, u1)
            fa0 -= f1
            fa1 -= m1
            g0 += f1
            g1 -= m2
            f1, m1, m2 = _hermite_end_forces(packed.beam_EIl[e], L, y1, s1, u2, u3)
            fa2 -= f1
            fa3 -= m1
            g2 += f1
            g3 -= m2
            kt = packed.beam_GK[e] / L * (r1 - u4)
            fa4 -= kt
            g4 += kt
            _set_node_values(force, a, fa0, fa1, fa2, fa3, fa4)
            prev_b = b
        if prev_b >= 0:
            _set_node_values(force, prev_b, g0, g1, g2, g3, g4)


@kernel(creates_arrays=False)
def _link_forces(packed, disp, vel, force, ranges, n_ranges):
    """Subtract the forces of every spring-damper link from ``force``.

    Link l: relative displacement d = sum_j coef_j u[dof_j] (and d' likewise from ``vel``); force
    p = k d + c d'; generalised forces coef_j * p are subtracted (virtual work, paper eq. 4).
    """
    n_link = packed.link_k.shape[0]
    for k in range(n_ranges):
        l0, l1 = _element_span(ranges, k, n_link)
        for l in range(l0, l1):
            j0 = packed.link_ptr[l]
            j1 = packed.link_ptr[l + _ONE]
            d = 0.0
            v = 0.0
            for j in range(j0, j1):
                q = packed.link_dof[j]
                c = packed.link_coef[j]
                d += c * disp[q]
                v += c * vel[q]
            p = packed.link_k[l] * d + packed.link_c[l] * v
            for j in range(j0, j1):
                force[packed.link_dof[j]] -= packed.link_coef[j] * p


def group_triple_entries(tri_ptr, tri_dof, tri_coef):
    """The link triples' entries reordered for :func:`_triple_forces`: returns
    (``tri_group_end``, ``tri_kernel_dof``, ``tri_kernel_coef``, ``tri_run_of_three``).

    Within each triple the entries (DOF, three coefficients) are put in three groups, each in
    its original order: those acting on the vertical link only (c1 = c2 = 0), those on the
    lateral and roll links only (c0 = 0), and the rest. ``tri_group_end[2 t]`` and
    ``[2 t + 1]`` are the ends of the first two groups of triple t (the third ends at
    ``tri_ptr[t + 1]``). Two thirds of the CA mortar's coefficients are zero (a quadrature
    point's vertical link has no lateral DOF in it, and the other way round); the kernel skips
    them. ``tri_dof`` and ``tri_coef`` keep their order (the assembled matrices and the moving
    window read them). ``tri_run_of_three`` marks the runs of three triples over the same
    grouped DOFs (:func:`triple_runs_of_three`), which the kernel evaluates together.
    """
    n_tri = tri_ptr.shape[0] - 1
    coef = np.asarray(tri_coef, dtype=float).reshape(-1, 3)
    group_end = np.zeros(2 * n_tri, dtype=np.int64)
    order = np.empty(tri_dof.shape[0], dtype=np.int64)
    for t in range(n_tri):
        j0, j1 = int(tri_ptr[t]), int(tri_ptr[t + 1])
        entries = np.arange(j0, j1)
        c = coef[j0:j1]
        vertical = (c[:, 1] == 0.0) & (c[:, 2] == 0.0)
        lateral_roll = ~vertical & (c[:, 0] == 0.0)
        rest = ~(vertical | lateral_roll)
        order[j0:j1] = np.concatenate([entries[vertical], entries[lateral_roll], entries[rest]])
        group_end[2 * t] = j0 + int(vertical.sum())
        group_end[2 * t + 1] = group_end[2 * t] + int(lateral_roll.sum())
    kernel_dof = np.ascontiguousarray(tri_dof[order])
    return (group_end, kernel_dof, np.ascontiguousarray(coef[order].ravel()),
            triple_runs_of_three(tri_ptr, group_end, kernel_dof))


def _same_layout(a, b) -> bool:
    """Two triples' (group sizes..., grouped DOFs) of :func:`triple_runs_of_three` equal."""
    return a[:3] == b[:3] and np.array_equal(a[3], b[3])


def triple_runs_of_three(tri_ptr, group_end, kernel_dof):
    """1 at the first triple of each run of three consecutive link triples that
    :func:`_triple_forces` evaluates together (``tri_run_of_three``), else 0: the three have the
    same entries' DOFs in the same groups (a CA slab element's three quadrature points over its
    own and its girder's DOFs), only a vertical and a lateral-roll group, and no DOF in both.
    The kernel then reads each DOF's index, displacement, velocity and force once for the three
    (docs/performance.md, "The CA triples in runs of three")."""
    n_tri = tri_ptr.shape[0] - 1
    runs = np.zeros(n_tri, dtype=np.uint8)

    def layout(t):
        j0, j1 = int(tri_ptr[t]), int(tri_ptr[t + 1])
        return (int(group_end[2 * t]) - j0, int(group_end[2 * t + 1]) - j0, j1 - j0,
                kernel_dof[j0:j1])

    t = 0
    while t + 2 < n_tri:
        first = layout(t)
        n_vertical, n_two_groups, n_all, dofs = first
        if (n_two_groups == n_all
                and not np.intersect1d(dofs[:n_vertical], dofs[n_vertical:]).size
                and all(_same_layout(layout(u), first) for u in (t + 1, t + 2))):
            runs[t] = 1
            t += 3
        else:
            t += 1
    return runs


# The two group sums are inlined into _triple_forces: called as functions, once or twice per
# triple, they cost the structure kernel 14 % (docs/performance.md, "Side by side in run_all.py").
@kernel(inline="always")
def _vertical_terms(coef, j, u, w, d0, v0):
    """(d0, v0) plus entry j's vertical term at displacement u, velocity w."""
    c0 = coef[3 * j]
    return d0 + c0 * u, v0 + c0 * w


@kernel(inline="always")
def _vertical_sums(dofs, coef, disp, vel, j0, j1, d0, v0):
    """(d0, v0) plus the vertical link's terms of entries [j0, j1) of a link triple."""
    for j in range(j0, j1):
        q = dofs[j]
        d0, v0 = _vertical_terms(coef, j, disp[q], vel[q], d0, v0)
    return d0, v0


@kernel(inline="always")
def _lateral_roll_terms(coef, j, u, w, d1, d2, v1, v2):
    """(d1, d2, v1, v2) plus entry j's lateral and roll terms at displacement u, velocity w."""
    c1 = coef[3 * j + 1]
    c2 = coef[3 * j + 2]
    return d1 + c1 * u, d2 + c2 * u, v1 + c1 * w, v2 + c2 * w


@kernel(inline="always")
def _lateral_roll_sums(dofs, coef, disp, vel, j0, j1, d1, d2, v1, v2):
    """(d1, d2, v1, v2) plus the lateral and roll links' terms of entries [j0, j1)."""
    for j in range(j0, j1):
        q = dofs[j]
        d1, d2, v1, v2 = _lateral_roll_terms(coef, j, disp[q], vel[q], d1, d2, v1, v2)
    return d1, d2, v1, v2


@kernel(inline="always")
def _triple_link_forces(packed, t3, d0, d1, d2, v0, v1, v2):
    """(p0, p1, p2) = k d + c d' of the three links of the triple whose first link is ``t3``."""
    return (packed.tri_k[t3] * d0 + packed.tri_c[t3] * v0,
            packed.tri_k[t3 + _ONE] * d1 + packed.tri_c[t3 + _ONE] * v1,
            packed.tri_k[t3 + _TWO] * d2 + packed.tri_c[t3 + _TWO] * v2)


@kernel(inline="always")
def _triple_forces_one(packed, dofs, coef, disp, vel, force, t):
    """Subtract the forces of link triple ``t`` (:func:`_triple_forces`)."""
    j0 = packed.tri_ptr[t]
    j_lat = packed.tri_group_end[_TWO * t]
    j_gen = packed.tri_group_end[_TWO * t + _ONE]
    j1 = packed.tri_ptr[t + _ONE]
    t3 = _THREE * t
    d0, v0 = _vertical_sums(dofs, coef, disp, vel, j0, j_lat, 0.0, 0.0)
    d1, d2, v1, v2 = _lateral_roll_sums(dofs, coef, disp, vel, j_lat, j_gen,
                                        0.0, 0.0, 0.0, 0.0)
    # the general group: each link's terms in the entries' order, as in the groups
    d0, v0 = _vertical_sums(dofs, coef, disp, vel, j_gen, j1, d0, v0)
    d1, d2, v1, v2 = _lateral_roll_sums(dofs, coef, disp, vel, j_gen, j1, d1, d2, v1, v2)
    p0, p1, p2 = _triple_link_forces(packed, t3, d0, d1, d2, v0, v1, v2)
    for j in range(j0, j_lat):
        force[dofs[j]] -= coef[3 * j] * p0
    for j in range(j_lat, j_gen):
        force[dofs[j]] -= coef[3 * j + 1] * p1 + coef[3 * j + 2] * p2
    for j in range(j_gen, j1):
        force[dofs[j]] -= coef[3 * j] * p0 + coef[3 * j + 1] * p1 + coef[3 * j + 2] * p2


@kernel(inline="always")
def _triple_forces_three(packed, dofs, coef, disp, vel, force, t):
    """Subtract the forces of link triples ``t``, ``t + 1``, ``t + 2``, a run of three over
    the same DOFs (:func:`triple_runs_of_three`): each DOF's index, displacement, velocity and
    force read once for the three. Every sum takes the same terms in the same order as
    :func:`_triple_forces_one` three times: a DOF's force has the three triples' terms
    subtracted in the triples' order, as there, since no other triple comes between them."""
    a = packed.tri_ptr[t]
    b = packed.tri_ptr[t + _ONE]
    c = packed.tri_ptr[t + _TWO]
    n_vertical = packed.tri_group_end[_TWO * t] - a
    n_all = packed.tri_group_end[_TWO * t + _ONE] - a
    d0a = v0a = d0b = v0b = d0c = v0c = 0.0
    for i in range(n_vertical):
        q = dofs[a + i]
        u = disp[q]
        w = vel[q]
        d0a, v0a = _vertical_terms(coef, a + i, u, w, d0a, v0a)
        d0b, v0b = _vertical_terms(coef, b + i, u, w, d0b, v0b)
        d0c, v0c = _vertical_terms(coef, c + i, u, w, d0c, v0c)
    d1a = d2a = v1a = v2a = d1b = d2b = v1b = v2b = d1c = d2c = v1c = v2c = 0.0
    for i in range(n_vertical, n_all):
        q = dofs[a + i]
        u = disp[q]
        w = vel[q]
        d1a, d2a, v1a, v2a = _lateral_roll_terms(coef, a + i, u, w, d1a, d2a, v1a, v2a)
        d1b, d2b, v1b, v2b = _lateral_roll_terms(coef, b + i, u, w, d1b, d2b, v1b, v2b)
        d1c, d2c, v1c, v2c = _lateral_roll_terms(coef, c + i, u, w, d1c, d2c, v1c, v2c)
    t3 = _THREE * t
    p0a, p1a, p2a = _triple_link_forces(packed, t3, d0a, d1a, d2a, v0a, v1a, v2a)
    p0b, p1b, p2b = _triple_link_forces(packed, t3 + _THREE, d0b, d1b, d2b, v0b, v1b, v2b)
    p0c, p1c, p2c = _triple_link_forces(packed, t3 + _THREE + _THREE, d0c, d1c, d2c, v0c, v1c,
                                        v2c)
    for i in range(n_vertical):
        q = dofs[a + i]
        f = force[q]
        f -= coef[3 * (a + i)] * p0a
        f -= coef[3 * (b + i)] * p0b
        f -= coef[3 * (c + i)] * p0c
        force[q] = f
    for i in range(n_vertical, n_all):
        q = dofs[a + i]
        f = force[q]
        f -= coef[3 * (a + i) + 1] * p1a + coef[3 * (a + i) + 2] * p2a
        f -= coef[3 * (b + i) + 1] * p1b + coef[3 * (b + i) + 2] * p2b
        f -= coef[3 * (c + i) + 1] * p1c + coef[3 * (c + i) + 2] * p2c
        force[q] = f


@kernel(creates_arrays=False)
def _triple_forces(packed, disp, vel, force, ranges, n_ranges):
    """Subtract the forces of every link triple (CA quadrature points; rail pads and ballast have
    compact kernels of their own).

    A triple is three links (vertical, lateral, roll) over one shared DOF list: relative
    displacements d_r = sum_j coef[j, r] u[dof_j] (r = 0, 1, 2), forces p_r = k_r d_r + c_r d'_r,
    generalised forces sum_r coef[j, r] p_r subtracted. Same physics as three CSR links, one pass
    over the DOFs (measured 1.5x faster for the pads).

    The entries are read in the groups of :func:`group_triple_entries` and only their non-zero
    coefficients are used: a term with a zero coefficient adds nothing to a sum, so each d_r
    and each DOF's force are the same numbers as over the whole dense list (bit for bit when
    no entry of the third group shares a link with the first two, as in the CA mortar; else
    equal to rounding, the terms of d_r summed in another order). Runs of three triples over
    the same DOFs (``tri_run_of_three``) are evaluated together, bit for bit as one by one.
    """
    n_tri = packed.tri_k.shape[0] // 3
    runs = packed.tri_run_of_three
    n_marked = np.uint64(runs.shape[0])
    dofs = packed.tri_kernel_dof
    coef = packed.tri_kernel_coef
    for k in range(n_ranges):
        t0, t1 = _element_span(ranges, k, n_tri)
        t = t0
        while t < t1:
            if t < n_marked and runs[t] != 0 and t + _TWO < t1:
                _triple_forces_three(packed, dofs, coef, disp, vel, force, t)
                t += _THREE
            else:
                _triple_forces_one(packed, dofs, coef, disp, vel, force, t)
                t += _ONE


@kernel(inline="always")
def _pad_rail_motion(rd, disp, vel, d_f):
    """The rail side of a pad at rail node DOF ``rd``: (d_z, d_y, d_roll) and their rates, d_y
    at the rail foot (``d_f`` below the shear centre)."""
    return (disp[rd], disp[rd + 2] + d_f * disp[rd + 4], disp[rd + 4],
            vel[rd], vel[rd + 2] + d_f * vel[rd + 4], vel[rd + 4])


@kernel(inline="always")
def _pad_law(packed, p3, dz, dy, dr, vz, vy, vr):
    """A pad's forces (p_z, p_y, p_roll) = k d + c d' per direction (pad ``p3 / 3``)."""
    kk = packed.pad_k
    cc = packed.pad_c
    return (kk[p3] * dz + cc[p3] * vz, kk[p3 + _ONE] * dy + cc[p3 + _ONE] * vy,
            kk[p3 + _TWO] * dr + cc[p3 + _TWO] * vr)


@kernel(inline="always")
def _pad_rail_forces(force, rd, d_f, pz, py, pr):
    """Subtract a pad's forces (p_z, p_y at the foot, p_roll) from its rail node's."""
    force[rd] -= pz
    force[rd + 2] -= py
    force[rd + 4] -= d_f * py + pr


@kernel(creates_arrays=False)
def _slab_pads(packed, disp, vel, force, p0, p1):
    """Pads [p0, p1) on the slab (:func:`_pad_forces`), a slab element's two nodes (seats a, b)
    held in registers over the run of pads on it."""
    d_f = packed.pad_foot_depth
    t_half = packed.pad_seat_half_thickness
    rail = packed.pad_rail
    seat_a = packed.pad_seat_a
    seat_b = packed.pad_seat_b
    geom = packed.pad_geom
    da = -1
    db = -1
    ua0 = ua1 = ua2 = ua3 = ua4 = ub0 = ub1 = ub2 = ub3 = ub4 = 0.0
    va0 = va1 = va2 = va3 = va4 = vb0 = vb1 = vb2 = vb3 = vb4 = 0.0
    fa0 = fa1 = fa2 = fa3 = fa4 = fb0 = fb1 = fb2 = fb3 = fb4 = 0.0
    xi = wa = rs = vrs = sz = sy = svz = svy = n1 = n2 = n3 = n4 = 0.0
    new_run = True
    for p in range(p0, p1):
        a = seat_a[p]
        b = seat_b[p]
        if a != da or b != db:
            if da >= 0:
                _set_node_values(force, da, fa0, fa1, fa2, fa3, fa4)
                _set_node_values(force, db, fb0, fb1, fb2, fb3, fb4)
            da = a
            db = b
            ua0, ua1, ua2, ua3, ua4 = _node_values(disp, da)
            ub0, ub1, ub2, ub3, ub4 = _node_values(disp, db)
            va0, va1, va2, va3, va4 = _node_values(vel, da)
            vb0, vb1, vb2, vb3, vb4 = _node_values(vel, db)
            fa0, fa1, fa2, fa3, fa4 = _node_values(force, da)
            fb0, fb1, fb2, fb3, fb4 = _node_values(force, db)
            new_run = True
        p3 = _THREE * p
        rd = rail[p]
        e = geom[p3 + _TWO]
        dz, dy, dr, vz, vy, vr = _pad_rail_motion(rd, disp, vel, d_f)
        x = geom[p3]
        if x != xi or new_run:
            # the slab point's motion (one element: one length), shared by the pads of both
            # rails at one place
            xi = x
            new_run = False
            n1, n2, n3, n4 = hermite(xi, geom[p3 + _ONE])
            wa = 1.0 - xi
            rs = wa * ua4 + xi * ub4
            vrs = wa * va4 + xi * vb4
            sz = n1 * ua0 + n2 * ua1 + n3 * ub0 + n4 * ub1
            sy = n1 * ua2 + n2 * ua3 + n3 * ub2 + n4 * ub3
            svz = n1 * va0 + n2 * va1 + n3 * vb0 + n4 * vb1
            svy = n1 * va2 + n2 * va3 + n3 * vb2 + n4 * vb3
        dz -= sz + e * rs
        dy += t_half * rs - sy
        dr -= rs
        vz -= svz + e * vrs
        vy += t_half * vrs - svy
        vr -= vrs
        pz, py, pr = _pad_law(packed, p3, dz, dy, dr, vz, vy, vr)
        _pad_rail_forces(force, rd, d_f, pz, py, pr)
        fa0 += n1 * pz
        fa1 += n2 * pz
        fb0 += n3 * pz
        fb1 += n4 * pz
        fa2 += n1 * py
        fa3 += n2 * py
        fb2 += n3 * py
        fb3 += n4 * py
        q = e * pz - t_half * py + pr
        fa4 += wa * q
        fb4 += xi * q
    if da >= 0:
        _set_node_values(force, da, fa0, fa1, fa2, fa3, fa4)
        _set_node_values(force, db, fb0, fb1, fb2, fb3, fb4)


@kernel(creates_arrays=False)
def _sleeper_pads(packed, disp, vel, force, p0, p1):
    """Pads [p0, p1) on sleepers (:func:`_pad_forces`), a sleeper held over its pads."""
    d_f = packed.pad_foot_depth
    rail = packed.pad_rail
    seat_a = packed.pad_seat_a
    geom = packed.pad_geom
    sd = -1
    u0 = u1 = u2 = w0 = w1 = w2 = f0 = f1 = f2 = 0.0
    for p in range(p0, p1):
        s = seat_a[p]
        if s != sd:
            if sd >= 0:
                force[sd] = f0
                force[sd + 1] = f1
                force[sd + 2] = f2
            sd = s
            u0, u1, u2 = disp[sd], disp[sd + 1], disp[sd + 2]
            w0, w1, w2 = vel[sd], vel[sd + 1], vel[sd + 2]
            f0, f1, f2 = force[sd], force[sd + 1], force[sd + 2]
        p3 = _THREE * p
        rd = rail[p]
        e = geom[p3 + _TWO]
        dz, dy, dr, vz, vy, vr = _pad_rail_motion(rd, disp, vel, d_f)
        dz -= u0 + e * u2
        dy -= u1
        dr -= u2
        vz -= w0 + e * w2
        vy -= w1
        vr -= w2
        pz, py, pr = _pad_law(packed, p3, dz, dy, dr, vz, vy, vr)
        _pad_rail_forces(force, rd, d_f, pz, py, pr)
        f0 += pz
        f1 += py
        f2 += e * pz + pr
    if sd >= 0:
        force[sd] = f0
        force[sd + 1] = f1
        force[sd + 2] = f2


@kernel(creates_arrays=False)
def _rigid_pads(packed, disp, vel, force, p0, p1):
    """Pads [p0, p1) on rigid ground (:func:`_pad_forces`)."""
    d_f = packed.pad_foot_depth
    rail = packed.pad_rail
    for p in range(p0, p1):
        p3 = _THREE * p
        rd = rail[p]
        dz, dy, dr, vz, vy, vr = _pad_rail_motion(rd, disp, vel, d_f)
        pz, py, pr = _pad_law(packed, p3, dz, dy, dr, vz, vy, vr)
        _pad_rail_forces(force, rd, d_f, pz, py, pr)


@kernel(creates_arrays=False)
def _pad_forces(packed, disp, vel, force, ranges, n_ranges):
    """Subtract the forces of every rail pad (fastener): vertical, lateral and roll spring-dampers
    between a rail node and its seat (paper eq. 22).

    Pads are stored compactly (docs/performance.md: half the time of the generic link
    triples, which read 6-13 (DOF, 3 coefficients) entries per pad): rail node first DOF ``rd``
    (z, dz/dx, y, dy/dx, roll), seat DOFs, geometry ``pad_geom[3p:3p+3]`` = (xi, L, e) and
    k, c per direction (vertical, lateral at the rail foot, roll). ``pad_group`` = numbers of
    pads on (slab, ballasted sleepers, rigid ground), stored in that order. Relative motions,
    d_f = ``pad_foot_depth`` (shear centre to foot), t = ``pad_seat_half_thickness``:

    * slab seat in the slab element (nodes a, b; Hermite N_i(xi, L), roll linear, rail at
      lateral offset e): d_z = z_r - N.w_slab - e r_s, d_y = y_r + d_f roll_r - N.v_slab + t r_s,
      d_roll = roll_r - r_s with r_s = (1 - xi) roll_a + xi roll_b;
    * sleeper (z, y, roll at ``seat_a``): d_z = z_r - z_s - e roll_s, d_y = y_r + d_f roll_r - y_s,
      d_roll = roll_r - roll_s;
    * rigid ground: d = (z_r, y_r + d_f roll_r, roll_r).

    Force p = k d + c d' per direction; the generalised forces are the transpose (virtual work).
    Same physics as the link-triple form (``assemble_matrices`` builds K, C from that form; the
    kernel test compares them).

    The pads of one seat are stored one after the other (a slab element carries the pads of
    both rails over its length, a sleeper the pair of its rail seats): each group's kernel
    reads a seat's displacements and velocities once per run of pads on it, keeps its forces
    in registers and writes them when the run ends, and the two pads at one place (left and
    right rail, the same slab point) share the slab point's motion. Every force receives the
    same terms in the same order as pad by pad, so the results are the same numbers.
    """
    n_slab = np.uint64(packed.pad_group[0])
    n_slab_ballast = n_slab + np.uint64(packed.pad_group[1])
    n_pad = packed.pad_rail.shape[0]
    for k in range(n_ranges):
        p0, p1 = _element_span(ranges, k, n_pad)
        _slab_pads(packed, disp, vel, force, p0, min(p1, n_slab))
        _sleeper_pads(packed, disp, vel, force, max(p0, n_slab), min(p1, n_slab_ballast))
        _rigid_pads(packed, disp, vel, force, max(p0, n_slab_ballast), p1)


@kernel(creates_arrays=False)
def _ballast_forces(packed, disp, vel, force, ranges, n_ranges):
    """Subtract the forces of the ballasted track under the rails (Zhai's model; paper 2.1 (2)).

    Per sleeper j (z, y, roll at ``bal_sleeper[j]``) two ballast blocks (z at ``bal_block[j]``
    + side, side 0 under the left rail seat at e = +``bal_half_gauge``, side 1 at -e): sleeper ->
    block spring-damper on z_s + e roll_s - z_b (``bal_k[0]``, ``bal_c[0]``), block -> subgrade on
    z_b (index 1), shear between the block and the same side's block of the next sleeper on
    z_b - z_b,next when ``bal_next[j]`` (index 2), and the sleeper's lateral resistance on y_s
    (index 3). Same physics as the generic link rows (``assembly.ballast_link_rows``), which the
    reference matrices use.
    """
    e = packed.bal_half_gauge
    kz, ksub, ksh, ky = packed.bal_k[0], packed.bal_k[1], packed.bal_k[2], packed.bal_k[3]
    cz, csub, csh, cy = packed.bal_c[0], packed.bal_c[1], packed.bal_c[2], packed.bal_c[3]
    sleeper = packed.bal_sleeper
    block = packed.bal_block
    nxt = packed.bal_next
    for k in range(n_ranges):
        j0, j1 = _element_span(ranges, k, sleeper.shape[0])
        for j in range(j0, j1):
            sd = sleeper[j]
            zs = disp[sd]
            rs = disp[sd + 2]
            vzs = vel[sd]
            vrs = vel[sd + 2]
            force[sd + 1] -= ky * disp[sd + 1] + cy * vel[sd + 1]
            for side in range(2):
                es = e if side == 0 else -e
                bd = block[j] + side
                zb = disp[bd]
                vb = vel[bd]
                p0 = kz * (zs + es * rs - zb) + cz * (vzs + es * vrs - vb)
                force[sd] -= p0
                force[sd + 2] -= es * p0
                force[bd] += p0 - (ksub * zb + csub * vb)
                if nxt[j] != 0:
                    p2 = ksh * (zb - disp[bd + 2]) + csh * (vb - vel[bd + 2])
                    force[bd] -= p2
                    force[bd + 2] += p2


#: Element ranges meaning "every element" ([start, end) rows; end -1: to the last element), a
#: compile-time constant of the kernels.
_EVERY_ELEMENT = np.array([[0, -1]], dtype=np.int64)


@kernel(creates_arrays=False)
def structure_accelerations(packed, disp, vel, nodal_force, acc_out):
    """acc_out = M^-1 (nodal_force - K disp - C vel) for the whole structure.

    ``nodal_force`` holds the external loads only and is not modified. Diagonal-mass DOFs use
    ``inv_mass`` (0 for fixed DOFs); each girder span block uses its dense inverse mass.
    """
    for i in range(packed.n_dof):
        acc_out[i] = nodal_force[i]
    structure_accelerations_in_place(packed, disp, vel, acc_out)


@kernel(creates_arrays=False)
def structure_accelerations_in_place(packed, disp, vel, acc):
    """:func:`structure_accelerations` with the external loads in ``acc`` on entry, replaced by
    the accelerations: the coupled loop adds its wheel loads to ``acc`` directly, which saves
    clearing a separate load vector and copying it at every step."""
    _accelerations(packed, disp, vel, acc, packed.inv_mass, _EVERY_ELEMENT, 1,
                   _EVERY_ELEMENT, 1, _EVERY_ELEMENT, 1, _EVERY_ELEMENT, 1, _EVERY_ELEMENT, 1)


@kernel(creates_arrays=False)
def windowed_accelerations_in_place(packed, window, disp, vel, acc):
    """:func:`structure_accelerations_in_place` with the track outside a window frozen
    (:mod:`ttbpipe.structure.window`): only the elements in the window's ranges are evaluated
    (those with a DOF that moves), and the frozen DOFs have a zero inverse mass
    (``window.inv_mass``), like fixed DOFs. ``window.n_ranges`` counts the rows of each
    element kind's ranges (beams, links, pads, ballast, link triples). A window without
    segments (:func:`ttbpipe.structure.window.no_window`) gives
    :func:`structure_accelerations_in_place` bit for bit."""
    n = window.n_ranges
    _accelerations(packed, disp, vel, acc, window.inv_mass,
                   window.beam_ranges, n[0], window.link_ranges, n[1], window.pad_ranges, n[2],
                   window.ballast_ranges, n[3], window.triple_ranges, n[4])


@kernel(creates_arrays=False)
def _accelerations(packed, disp, vel, acc_out, inv_mass, beams, n_beams, links,
                   n_links, pads, n_pads, ballast, n_ballast, triples, n_triples):
    """The accelerations, in place of the external loads in ``acc_out``, with the given
    diagonal inverse mass, evaluating the elements in the given ranges of each kind (rows
    [start, end) of element indices, the first ``n_*`` rows)."""
    _beam_forces(packed, disp, vel, acc_out, beams, n_beams)
    _link_forces(packed, disp, vel, acc_out, links, n_links)
    _pad_forces(packed, disp, vel, acc_out, pads, n_pads)
    _ballast_forces(packed, disp, vel, acc_out, ballast, n_ballast)
    _triple_forces(packed, disp, vel, acc_out, triples, n_triples)
    for i in range(packed.n_diag):
        acc_out[i] *= inv_mass[i]
    tmp = packed.span_scratch
    for s in range(packed.span_dof0.shape[0]):
        o = packed.span_dof0[s]
        m = packed.span_n[s]
        base = packed.span_mat0[s]
        for i in range(m):
            f = acc_out[o + i]
            row = base + i * m
            for j in range(m):
                f -= packed.span_K[row + j] * disp[o + j] + packed.span_C[row + j] * vel[o + j]
            tmp[i] = f
        for i in range(m):
            row = base + i * m
            a = 0.0
            for j in range(m):
                a += packed.span_Minv[row + j] * tmp[j]
            acc_out[o + i] = a
