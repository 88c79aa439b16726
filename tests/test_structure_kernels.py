"""Structure kernels against slow, obviously correct references.

* _structure_accelerations == M^-1 (f - K u - C v) with M, K, C assembled by scipy.sparse from the
  same element/link data (independent vectorised assembly; tolerance 1e-10 relative).
* add_rail_point_load is the transpose of rail_point_kinematics (virtual work, exact to 1e-12).
* Hermite interpolation reproduces a cubic exactly (shape-function property).
* Zhai's stability limit omega*dt = 2.0 undamped and 1.81 at zeta = 0.05 (physics.md section 5).
* The beam kernel's chain form == element by element, bit for bit (same terms, same order).
"""

import numpy as np
import pytest
from scipy.sparse import linalg as splinalg

from ttbpipe.structure import build_structure
from ttbpipe.timestepping.zhai import zhai_critical_omega_dt
from ttbpipe.structure.kernels import structure_accelerations as _structure_accelerations
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh, rail_point_kinematics

SMALL = {"layout": {"approach_length_m": 12.0, "spans_m": [16.0, 12.0],
                    "approach_track": "ballasted"},
         "girder": {"element_length_m": 2.0}}


@pytest.fixture(scope="module")
def model():
    return build_structure(SMALL)


@pytest.mark.parametrize("approach,slab", [("ballasted", "continuous"), ("slab", "discrete"),
                                           ("rigid", "continuous")])
def test_accelerations_match_sparse_reference(approach, slab):
    cfg = {**SMALL, "layout": {**SMALL["layout"], "approach_track": approach},
           "slab": {"type": slab}}
    m = build_structure(cfg)
    M, K, C = m.matrices()
    rng = np.random.default_rng(1)
    u, v, f = (rng.normal(size=m.n_dof) for _ in range(3))
    acc = np.zeros(m.n_dof)
    _structure_accelerations(m.packed, u, v, f, acc)
    ref = splinalg.spsolve(M.tocsc(), f - K @ u - C @ v)
    assert np.max(np.abs(acc - ref)) <= 1e-10 * np.max(np.abs(ref))
    # K and C symmetric (reciprocity); M positive definite by construction
    assert abs(K - K.T).max() <= 1e-9 * abs(K).max()
    assert abs(C - C.T).max() <= 1e-9 * abs(C).max()


def test_point_force_is_transpose_of_kinematics(model):
    rng = np.random.default_rng(2)
    disp = rng.normal(size=model.n_dof)
    vel = rng.normal(size=model.n_dof)
    for rail in (0, 1):
        for x in (0.0, 3.3, 20.01, model.rail_x_range[1]):
            Fz, Fy, Mx = rng.normal(size=3)
            f = np.zeros(model.n_dof)
            add_rail_point_load(rail_mesh(model.packed, 0.0), rail, x, Fz, Fy, Mx, f)
            z, vz, y, vy, r, vr = rail_point_kinematics(rail_mesh(model.packed, 0.0), rail, x, disp, vel)
            assert f @ disp == pytest.approx(Fz * z + Fy * y + Mx * r, rel=1e-12, abs=1e-12)
            assert f @ vel == pytest.approx(Fz * vz + Fy * vy + Mx * vr, rel=1e-12, abs=1e-12)
    # outside the rails: nothing applied, zero kinematics
    f = np.zeros(model.n_dof)
    add_rail_point_load(rail_mesh(model.packed, 0.0), 0, -1.0, 1.0, 1.0, 1.0, f)
    assert not f.any()
    assert rail_point_kinematics(rail_mesh(model.packed, 0.0), 0, 1e6, disp, vel) == (0.0,) * 6


def test_hermite_interpolation_reproduces_cubic(model):
    p = model.packed
    x = p.rail_x0 + p.rail_dx * np.arange(p.rail_n_nodes)
    cubic = lambda s: 1e-3 * (0.2 + 0.1 * s - 0.01 * s ** 2 + 3e-4 * s ** 3)  # noqa: E731
    slope = lambda s: 1e-3 * (0.1 - 0.02 * s + 9e-4 * s ** 2)  # noqa: E731
    disp = np.zeros(model.n_dof)
    d0 = p.rail_dof0[1]
    disp[d0 + 5 * np.arange(x.size) + 2] = cubic(x)      # lateral y of the right rail
    disp[d0 + 5 * np.arange(x.size) + 3] = slope(x)
    for xq in (0.1, 7.77, 31.9):
        _, _, y, _, _, _ = rail_point_kinematics(rail_mesh(p, 0.0), 1, xq, disp, disp)
        assert y == pytest.approx(cubic(xq), rel=1e-12)


def test_zhai_stability_limits():
    # physics.md section 5: omega dt <= 2.0 undamped, ~1.81 at zeta = 0.05
    assert zhai_critical_omega_dt(0.0) == pytest.approx(2.0, abs=1e-6)
    assert zhai_critical_omega_dt(0.05) == pytest.approx(1.81, abs=0.005)


def test_time_step_check_names_remedy(model):
    limit = model.stable_time_step(safety=1.0)
    model.check_time_step(0.9 * limit)
    with pytest.raises(ValueError, match="time_step_s"):
        model.check_time_step(1.2 * limit)


def test_static_signs_follow_axes():
    """+Fy moves the rail left (+y), +Mx rolls it positively, -Fz pushes it down; a down load on
    the left rail lowers the left seat, so the slab rolls negative (left side down).
    Axes: channels.py (y left, z up, roll right-hand about +x: positive roll lifts the left)."""
    m = build_structure({"layout": {"approach_length_m": 6.0, "spans_m": [12.0]},
                         "girder": {"element_length_m": 1.0}})
    _, K, _ = m.matrices()
    solve = splinalg.factorized(K.tocsc())
    x = 12.0
    for (Fz, Fy, Mx), check in (((-1e4, 0, 0), lambda k: k[0] < 0),
                                ((0, 1e4, 0), lambda k: k[2] > 0),
                                ((0, 0, 1e3), lambda k: k[4] > 0)):
        f = np.zeros(m.n_dof)
        add_rail_point_load(rail_mesh(m.packed, 0.0), 0, x, Fz, Fy, Mx, f)
        u = solve(f)
        assert check(rail_point_kinematics(rail_mesh(m.packed, 0.0), 0, x, u, u))
    f = np.zeros(m.n_dof)
    add_rail_point_load(rail_mesh(m.packed, 0.0), 0, x, -1e5, 0, 0, f)
    u = solve(f)
    from ttbpipe.structure.monitors import point_rows
    d, c = point_rows(m, {"kind": "slab", "x_m": x})["roll"]
    assert float(u[np.asarray(d)] @ c) < 0


def _dense_triple_forces(packed, disp, vel):
    """Slow reference of the link triples: every entry with its three coefficients, in the
    assembled order (the kernel's form before it skipped the zero coefficients)."""
    force = np.zeros(packed.n_dof)
    coef = packed.tri_coef.reshape(-1, 3)
    for t in range(packed.tri_k.size // 3):
        j0, j1 = packed.tri_ptr[t], packed.tri_ptr[t + 1]
        d = np.zeros(3)
        v = np.zeros(3)
        for j in range(j0, j1):
            for r in range(3):
                d[r] += coef[j, r] * disp[packed.tri_dof[j]]
                v[r] += coef[j, r] * vel[packed.tri_dof[j]]
        p = packed.tri_k[3 * t:3 * t + 3] * d + packed.tri_c[3 * t:3 * t + 3] * v
        for j in range(j0, j1):
            force[packed.tri_dof[j]] -= (coef[j, 0] * p[0] + coef[j, 1] * p[1]) + coef[j, 2] * p[2]
    return force


def test_triple_kernel_skips_only_zero_coefficients(model):
    """The CA mortar's triples read in groups (vertical only, lateral and roll only, general;
    ``group_triple_entries``) and in runs of three over the same DOFs give the dense
    evaluation's forces bit for bit, and the runs give the one-by-one evaluation's bit for bit
    over any ranges of triples (a moving window's); with entries in
    the general group (coefficients made non-zero at random) equal to rounding (1e-12 of the
    largest force), as the terms of a sum are then added in another order."""
    from ttbpipe.structure.kernels import _EVERY_ELEMENT, _triple_forces, group_triple_entries

    packed = model.packed
    coef = packed.tri_coef.reshape(-1, 3)
    assert packed.tri_k.size > 0 and (coef == 0.0).mean() > 0.5     # the case worth skipping
    rng = np.random.default_rng(7)
    u, v = rng.normal(size=packed.n_dof), rng.normal(size=packed.n_dof)
    force = np.zeros(packed.n_dof)
    _triple_forces(packed, u, v, force, _EVERY_ELEMENT, 1)
    assert np.array_equal(force, _dense_triple_forces(packed, u, v))
    # runs of three over the same DOFs evaluated together (tri_run_of_three), bit for bit as
    # one by one, also where a moving window's ranges start or end inside a run
    runs = np.flatnonzero(packed.tri_run_of_three)
    assert runs.size > 0 and np.all(np.diff(runs) >= 3)
    one_by_one = packed._replace(tri_run_of_three=np.zeros(0, dtype=np.uint8))
    cut = np.array([[runs[0] + 1, runs[1] + 2], [runs[2], runs[-1] + 3], [0, 0]], dtype=np.int64)
    for ranges, n_ranges in ((_EVERY_ELEMENT, 1), (cut, 2)):
        force, ref = np.zeros(packed.n_dof), np.zeros(packed.n_dof)
        _triple_forces(packed, u, v, force, ranges, n_ranges)
        _triple_forces(one_by_one, u, v, ref, ranges, n_ranges)
        assert np.array_equal(force, ref) and np.abs(ref).max() > 0

    mixed = coef.copy()
    fill = rng.random(mixed.shape) < 0.2
    mixed[fill] = rng.normal(size=fill.sum())
    group_end, kdof, kcoef, runs = group_triple_entries(packed.tri_ptr, packed.tri_dof,
                                                        mixed.ravel())
    general = packed._replace(tri_coef=mixed.ravel(), tri_group_end=group_end,
                              tri_kernel_dof=kdof, tri_kernel_coef=kcoef, tri_run_of_three=runs)
    assert (group_end[1::2] < packed.tri_ptr[1:]).any()        # the general group is used
    force = np.zeros(packed.n_dof)
    _triple_forces(general, u, v, force, _EVERY_ELEMENT, 1)
    ref = _dense_triple_forces(general, u, v)
    assert np.max(np.abs(force - ref)) <= 1e-12 * np.max(np.abs(ref))


def _element_by_element_beam_forces(packed, disp, force, elements):
    """Slow reference of the beams: each element's end forces read from and written to
    ``force`` in turn, in the given order (the kernel's form before it carried the shared node
    along a chain)."""
    for e in elements:
        a, b, L = int(packed.beam_dof_a[e]), int(packed.beam_dof_b[e]), float(packed.beam_L[e])
        for off, EI in ((0, packed.beam_EIv[e]), (2, packed.beam_EIl[e])):
            s = float(EI) / (L * L * L)
            w1, t1, w2, t2 = disp[a + off], disp[a + off + 1], disp[b + off], disp[b + off + 1]
            dw = w1 - w2
            force[a + off] -= s * (12.0 * dw + 6.0 * L * (t1 + t2))
            force[a + off + 1] -= s * L * (6.0 * dw + L * (4.0 * t1 + 2.0 * t2))
            force[b + off] += s * (12.0 * dw + 6.0 * L * (t1 + t2))
            force[b + off + 1] -= s * L * (6.0 * dw + L * (2.0 * t1 + 4.0 * t2))
        kt = float(packed.beam_GK[e]) / L * (disp[a + 4] - disp[b + 4])
        force[a + 4] -= kt
        force[b + 4] += kt


@pytest.mark.parametrize("ranges", [[[0, -1]], [[0, 5], [7, 20], [31, -1]], [[3, 4], [4, 9]]])
def test_beam_chain_matches_element_by_element(model, ranges):
    """The beam kernel carries the shared node of consecutive elements in registers
    (``_beam_forces``); every force must get the same terms in the same order as element by
    element, so the two agree bit for bit: over every element, over ranges that cut the
    chains (a moving window's), and with the elements shuffled so that no pair chains."""
    from ttbpipe.structure.kernels import _beam_forces

    packed = model.packed
    n_beam = packed.beam_L.size
    a, b = packed.beam_dof_a, packed.beam_dof_b
    assert (a[1:] == b[:-1]).mean() > 0.9                       # the rails and slab do chain
    rng = np.random.default_rng(11)
    u = rng.normal(size=packed.n_dof)
    f0 = rng.normal(size=packed.n_dof)
    rows = np.array(ranges, dtype=np.int64)
    elements = [e for r0, r1 in ranges for e in range(r0, n_beam if r1 < 0 else r1)]
    shuffled = rng.permutation(n_beam)
    for pk in (packed, packed._replace(**{name: getattr(packed, name)[shuffled] for name in (
            "beam_dof_a", "beam_dof_b", "beam_L", "beam_EIv", "beam_EIl", "beam_GK")})):
        force = f0.copy()
        _beam_forces(pk, u, u, force, rows, rows.shape[0])
        ref = f0.copy()
        _element_by_element_beam_forces(pk, u, ref, elements)
        assert np.array_equal(force, ref)
        assert not np.array_equal(force, f0)


def _pad_by_pad_forces(packed, disp, vel, force, pads):
    """Slow reference of the rail pads: each pad reads its rail node and seat from the arrays
    and adds its forces to ``force`` in turn, in the given order (the kernel's form before it
    held a seat over the run of pads on it)."""
    from ttbpipe.structure.shape_functions import hermite

    d_f, t_half = packed.pad_foot_depth, packed.pad_seat_half_thickness
    n_slab = packed.pad_group[0]
    n_slab_ballast = n_slab + packed.pad_group[1]
    for p in pads:
        rd, da, db = packed.pad_rail[p], packed.pad_seat_a[p], packed.pad_seat_b[p]
        xi, L, e = packed.pad_geom[3 * p:3 * p + 3]
        k, c = packed.pad_k[3 * p:3 * p + 3], packed.pad_c[3 * p:3 * p + 3]
        dz, dy, dr = disp[rd], disp[rd + 2] + d_f * disp[rd + 4], disp[rd + 4]
        vz, vy, vr = vel[rd], vel[rd + 2] + d_f * vel[rd + 4], vel[rd + 4]
        if p < n_slab:
            n1, n2, n3, n4 = hermite(xi, L)
            wa = 1.0 - xi
            rs, vrs = wa * disp[da + 4] + xi * disp[db + 4], wa * vel[da + 4] + xi * vel[db + 4]
            dz -= n1 * disp[da] + n2 * disp[da + 1] + n3 * disp[db] + n4 * disp[db + 1] + e * rs
            dy += t_half * rs - (n1 * disp[da + 2] + n2 * disp[da + 3] + n3 * disp[db + 2]
                                 + n4 * disp[db + 3])
            dr -= rs
            vz -= n1 * vel[da] + n2 * vel[da + 1] + n3 * vel[db] + n4 * vel[db + 1] + e * vrs
            vy += t_half * vrs - (n1 * vel[da + 2] + n2 * vel[da + 3] + n3 * vel[db + 2]
                                  + n4 * vel[db + 3])
            vr -= vrs
        elif p < n_slab_ballast:
            dz -= disp[da] + e * disp[da + 2]
            dy -= disp[da + 1]
            dr -= disp[da + 2]
            vz -= vel[da] + e * vel[da + 2]
            vy -= vel[da + 1]
            vr -= vel[da + 2]
        pz, py, pr = k[0] * dz + c[0] * vz, k[1] * dy + c[1] * vy, k[2] * dr + c[2] * vr
        force[rd] -= pz
        force[rd + 2] -= py
        force[rd + 4] -= d_f * py + pr
        if p < n_slab:
            for dof, coef, load in ((da, n1, pz), (da + 1, n2, pz), (db, n3, pz), (db + 1, n4, pz),
                                    (da + 2, n1, py), (da + 3, n2, py), (db + 2, n3, py),
                                    (db + 3, n4, py)):
                force[dof] += coef * load
            q = e * pz - t_half * py + pr
            force[da + 4] += wa * q
            force[db + 4] += xi * q
        elif p < n_slab_ballast:
            force[da] += pz
            force[da + 1] += py
            force[da + 2] += e * pz + pr


@pytest.mark.parametrize("approach,slab", [("ballasted", "continuous"), ("rigid", "continuous"),
                                           ("slab", "discrete")])
@pytest.mark.parametrize("ranges", [[[0, -1]], [[1, 6], [6, 7], [30, 75], [90, -1]]])
def test_pad_runs_match_pad_by_pad(approach, slab, ranges):
    """The pad kernel holds a seat (slab element, sleeper) over the run of pads on it and
    shares the slab point between the two rails' pads (``_pad_forces``); every force must get
    the same terms in the same order as pad by pad, so the two agree bit for bit: over every
    pad (slab, sleeper and rigid-ground groups) and over ranges that cut the runs (a moving
    window's)."""
    from ttbpipe.structure.kernels import _pad_forces

    m = build_structure({**SMALL, "layout": {**SMALL["layout"], "approach_track": approach},
                         "slab": {"type": slab}})
    packed = m.packed
    n_pad = packed.pad_rail.size
    group = {"ballasted": 1, "rigid": 2, "slab": 0}[approach]     # the approach's pads
    assert packed.pad_group[0] > 0 and packed.pad_group[group] > 0
    seat = np.stack([packed.pad_seat_a, packed.pad_seat_b], axis=1)
    assert (seat[1:] == seat[:-1]).all(axis=1).mean() > 0.5     # the runs worth holding
    rng = np.random.default_rng(12)
    u, v, f0 = (rng.normal(size=packed.n_dof) for _ in range(3))
    rows = np.array(ranges, dtype=np.int64)
    pads = [p for r0, r1 in ranges for p in range(r0, n_pad if r1 < 0 else r1)]
    force = f0.copy()
    _pad_forces(packed, u, v, force, rows, rows.shape[0])
    ref = f0.copy()
    _pad_by_pad_forces(packed, u, v, ref, pads)
    assert np.array_equal(force, ref)
    assert not np.array_equal(force, f0)
