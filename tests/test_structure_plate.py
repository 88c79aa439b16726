"""The Kirchhoff thin-plate element (ttbpipe.structure.plate) against closed-form plate solutions.

Plate data: the model's slab panel (CRTS II, 6.45 x 2.55 x 0.20 m, E 3.6e10, nu 0.2, 2500 kg/m3;
structure.properties.SLAB) and its CA mortar as a Winkler foundation (3.0e9 N/m2 over the 2.55 m
width: 1.18e9 N/m3; structure.properties.CA). References and tolerances:

* simply supported rectangle: Navier's exact frequencies omega_mn = pi^2 ((m/a)^2 + (n/b)^2)
  sqrt(D / rho t) (Navier; Leissa 1969, Vibration of Plates, NASA SP-160, ch. 4); conforming
  elements with consistent mass are Rayleigh-Ritz upper bounds: every frequency above the exact
  one, the first eight within 0.1 % on a 16 x 8 mesh (measured: 4.0e-4 at most, O(h^4));
* two opposite edges simply supported, two free (the slab's long edges are free): the exact Levy
  characteristic equations (Leissa 1973, J. Sound Vib. 31:257, section 2; free edge: M_y = 0 and
  V_y = 0), solved here; the solver reproduces Leissa's square-plate values for nu = 0.3
  (9.6314, 16.135, 36.726, 38.945, 46.738, 70.740, his SS-F-SS-F table) to 1e-4; FE on a
  16 x 8 mesh within 0.1 % and above (measured: the first eight within 2.7e-4);
* infinite plate on a Winkler foundation under a point load (Hertz; Timoshenko & Woinowsky-Krieger
  1959, Theory of Plates and Shells, ch. 8): w(r) = -(P l^2 / (2 pi D)) kei(r / l),
  l = (D / k)^(1/4), w(0) = P / (8 sqrt(k D)). A free quarter plate of 10 l x 10 l with symmetry
  conditions, elements l / 4: the load point within 0.2 % (measured -0.10 %, O(h^2) from the
  point load's r^2 log r singularity: -0.42 % at l / 2), the profile at r = l, 2 l, 3 l within
  0.01 % (measured 1e-5);
* patch tests with free edges, exact in the element's polynomial space (1e-9): pure bending
  (edge moments M: w = -M (x^2 - nu y^2) / (2 D (1 - nu^2)), the anticlastic surface) and pure
  twist (rectangle on three corners loaded at the fourth: w = P x y / (2 D (1 - nu))).

About 2 s.
"""

import numpy as np
import pytest
from scipy import linalg, special
from scipy.optimize import brentq
from scipy.sparse import linalg as splinalg

from ttbpipe.structure.plate import RectangularPlate, element_mass, element_stiffness
from ttbpipe.structure.properties import CA, SLAB

A, B = SLAB["unit_length_m"], SLAB["width_m"]
E, NU, T, RHO = SLAB["E_Pa"], SLAB["poisson"], SLAB["thickness_m"], SLAB["density_kg_m3"]
K_CA = CA["kz_N_m2"] / SLAB["width_m"]          # N/m3


def _lowest(plate, fixed, n):
    K, M = plate.stiffness_matrix(), plate.mass_matrix()
    free = np.setdiff1d(np.arange(plate.n_dof), fixed)
    w2 = linalg.eigh(K[free][:, free].toarray(), M[free][:, free].toarray(),
                     eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(w2)


def _simply_supported_edges(plate, x_edges=True, y_edges=True):
    """w and its tangential slope fixed on the chosen edges."""
    fixed = []
    nx, ny = plate.x.size - 1, plate.y.size - 1
    for i in range(nx + 1):
        for j in range(ny + 1):
            d = plate.node_dofs(i, j)
            if x_edges and i in (0, nx):
                fixed += [d[0], d[2]]
            if y_edges and j in (0, ny):
                fixed += [d[0], d[1]]
    return np.unique(fixed)


def test_element_matrices_symmetric_and_rigid_body_modes():
    k = element_stiffness(0.4, 0.3, 1.0, NU)
    m = element_mass(0.4, 0.3, 1.0)
    assert np.allclose(k, k.T, rtol=0, atol=1e-12 * abs(k).max())
    assert np.allclose(m, m.T, rtol=0, atol=1e-14)
    # three zero-energy modes (w = 1, x, y), all others strictly positive
    ev = np.linalg.eigvalsh(k)
    assert np.sum(np.abs(ev) < 1e-9 * ev.max()) == 3
    assert ev.min() > -1e-9 * ev.max()
    # mass: total mass of the element for the rigid translation
    u = np.zeros(16)
    u[[0, 2, 8, 10]] = 1.0     # Kronecker order: w = 1 at the four nodes, slopes 0
    assert u @ m @ u == pytest.approx(0.4 * 0.3, rel=1e-12)
    # the global DOFs of a one-element plate are its nodes' (w, w_x, w_y, w_xy)
    plate = RectangularPlate([0, 0.4], [0, 0.3], E, NU, T, RHO)
    assert sorted(plate.element_dofs(0, 0)) == list(range(16))
    assert plate.element_dofs(0, 0)[[0, 2, 8, 10]].tolist() == [0, 4, 8, 12]


def test_simply_supported_frequencies_navier():
    plate = RectangularPlate(np.linspace(0, A, 17), np.linspace(0, B, 9), E, NU, T, RHO)
    omega = _lowest(plate, _simply_supported_edges(plate), 8)
    exact = sorted(np.pi ** 2 * ((m / A) ** 2 + (n / B) ** 2) * np.sqrt(plate.D / (RHO * T))
                   for m in range(1, 9) for n in range(1, 5))[:8]
    rel = omega / np.array(exact) - 1.0
    assert np.all(rel > -1e-9)              # upper bounds (conforming, consistent mass)
    assert np.all(rel < 1e-3)


def _levy_determinant(lam2, alpha, b, nu, symmetric):
    """Free edges at y = +-b/2 of w = sin(alpha x) Y(y), lam2 = omega sqrt(rho t / D) (1/m^2)."""
    k1 = np.sqrt(lam2 + alpha ** 2 + 0j)
    k2 = np.sqrt(lam2 - alpha ** 2 + 0j)          # imaginary below alpha^2: cos -> cosh
    h, c = b / 2, (2 - nu) * alpha ** 2
    if symmetric:      # Y = cosh(k1 y), cos(k2 y); rows: M_y = 0, V_y = 0
        m = [[(k1 ** 2 - nu * alpha ** 2) * np.cosh(k1 * h),
              (-k2 ** 2 - nu * alpha ** 2) * np.cos(k2 * h)],
             [(k1 ** 2 - c) * k1 * np.sinh(k1 * h), (k2 ** 2 + c) * k2 * np.sin(k2 * h)]]
    else:              # Y = sinh(k1 y), sin(k2 y) / k2 (real for imaginary k2)
        m = [[(k1 ** 2 - nu * alpha ** 2) * np.sinh(k1 * h),
              (-k2 ** 2 - nu * alpha ** 2) * np.sin(k2 * h) / k2],
             [(k1 ** 2 - c) * k1 * np.cosh(k1 * h), (-k2 ** 2 - c) * np.cos(k2 * h)]]
    return float(np.linalg.det(np.array(m)).real)


def _levy_roots(a, b, nu, lam2_max, n_half_waves):
    roots = []
    for m in range(1, n_half_waves + 1):
        alpha = m * np.pi / a
        for sym in (True, False):
            grid = np.linspace(1e-9, lam2_max, 4001)
            grid = grid[np.abs(grid - alpha ** 2) > 1e-6]
            v = [_levy_determinant(g, alpha, b, nu, sym) for g in grid]
            for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:])):
                roots.append(brentq(_levy_determinant, grid[i], grid[i + 1],
                                    args=(alpha, b, nu, sym), xtol=1e-13))
    return np.sort(roots)


def test_levy_solver_reproduces_leissa_square_plate():
    lam = _levy_roots(1.0, 1.0, 0.3, 100.0, 3)[:6]
    leissa = [9.6314, 16.135, 36.726, 38.945, 46.738, 70.740]
    assert lam == pytest.approx(leissa, rel=1e-4)


def test_simply_supported_free_frequencies_levy():
    """The slab panel simply supported at its ends (x = 0, a), long edges free."""
    plate = RectangularPlate(np.linspace(0, A, 17), np.linspace(-B / 2, B / 2, 9), E, NU, T, RHO)
    omega = _lowest(plate, _simply_supported_edges(plate, y_edges=False), 8)
    lam2 = _levy_roots(A, B, NU, 30.0, 6)[:8]
    exact = lam2 * np.sqrt(plate.D / (RHO * T))
    rel = omega / exact - 1.0
    assert np.all(rel > -1e-9)
    assert np.all(rel < 1e-3)


def test_point_load_on_winkler_foundation_westergaard():
    plate0 = RectangularPlate([0, 1], [0, 1], E, NU, T, RHO)
    D = plate0.D
    ell = (D / K_CA) ** 0.25                   # 0.382 m: radius of relative stiffness
    n = 40                                     # elements l / 4 on a quarter plate of 10 l
    nodes = np.linspace(0.0, 10 * ell, n + 1)
    plate = RectangularPlate(nodes, nodes, E, NU, T, RHO)
    K = plate.stiffness_matrix() + plate.foundation_matrix(K_CA)
    # symmetry about x = 0 and y = 0: odd derivatives vanish there
    fixed = [plate.node_dofs(0, j)[[1, 3]] for j in range(n + 1)]
    fixed += [plate.node_dofs(i, 0)[[2, 3]] for i in range(n + 1)]
    free = np.setdiff1d(np.arange(plate.n_dof), np.concatenate(fixed))
    P = 1.0e5
    f = np.zeros(plate.n_dof)
    f[plate.node_dofs(0, 0)[0]] = P / 4
    u = np.zeros(plate.n_dof)
    u[free] = splinalg.spsolve(K[free][:, free].tocsc(), f[free])
    assert plate.deflection(u, 0, 0) == pytest.approx(P / (8 * np.sqrt(K_CA * D)), rel=2e-3)
    for r in (ell, 2 * ell, 3 * ell):
        exact = -P * ell ** 2 / (2 * np.pi * D) * special.kei(r / ell)
        assert plate.deflection(u, r, 0) == pytest.approx(exact, rel=1e-4)
        assert plate.deflection(u, r / np.sqrt(2), r / np.sqrt(2)) == pytest.approx(exact, rel=1e-3)


def test_pure_bending_patch_free_edges():
    a, b, M0 = 3.0, 1.7, 1.0e4
    plate = RectangularPlate(np.linspace(0, a, 5), [0, 0.3, 1.1, 1.7], E, NU, T, RHO)
    c = -M0 / (2 * plate.D * (1 - NU ** 2))
    u = np.zeros(plate.n_dof)
    for i, x in enumerate(plate.x):
        for j, y in enumerate(plate.y):
            u[plate.node_dofs(i, j)] = [c * (x ** 2 - NU * y ** 2), 2 * c * x, -2 * c * NU * y, 0]
    K = plate.stiffness_matrix()
    # strain energy M^2 A / (2 D (1 - nu^2)) of uniform moments M_x = M, M_y = 0
    assert 0.5 * u @ (K @ u) == pytest.approx(M0 ** 2 * a * b / (2 * plate.D * (1 - NU ** 2)),
                                              rel=1e-9)
    # equilibrium inside: no force on interior nodes' w and the free edges' w
    r = K @ u
    interior = [plate.node_dofs(i, j)[0] for i in range(plate.x.size) for j in range(plate.y.size)]
    assert np.abs(r[interior]).max() < 1e-9 * M0


def test_pure_twist_corner_loaded_plate():
    plate = RectangularPlate(np.linspace(0, A, 4), [0, 0.5, 1.7, B], E, NU, T, RHO)
    K = plate.stiffness_matrix()
    nx, ny = plate.x.size - 1, plate.y.size - 1
    fixed = [plate.node_dofs(0, 0)[0], plate.node_dofs(nx, 0)[0], plate.node_dofs(0, ny)[0]]
    free = np.setdiff1d(np.arange(plate.n_dof), fixed)
    P = 1.0e4
    f = np.zeros(plate.n_dof)
    f[plate.node_dofs(nx, ny)[0]] = -P
    u = np.zeros(plate.n_dof)
    u[free] = splinalg.spsolve(K[free][:, free].tocsc(), f[free])
    for x, y in ((A, B), (1.3, 2.0), (4.0, 0.2)):
        assert plate.deflection(u, x, y) == pytest.approx(-P * x * y / (2 * plate.D * (1 - NU)),
                                                          rel=1e-9)
