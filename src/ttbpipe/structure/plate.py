"""Kirchhoff thin plates: the 16-DOF conforming rectangle of Bogner, Fox and Schmit.

The element (Bogner, Fox & Schmit 1965, "The generation of interelement-compatible stiffness and
mass matrices by the use of interpolation formulas", Proc. Conf. Matrix Methods in Structural
Mechanics, AFFDL-TR-66-80, pp. 397-443; Zienkiewicz & Taylor, The Finite Element Method, vol. 2,
5th ed., section 4.6) interpolates the deflection w(x, y) of a rectangle a x b by the products of
the 1-D Hermite cubics of :mod:`ttbpipe.structure.shape_functions` in x and in y; each node carries
w, dw/dx, dw/dy and d2w/dxdy. The interpolation is C1 across element edges (conforming), so the
stiffness and consistent mass give Rayleigh-Ritz upper bounds of the plate's frequencies.

Kirchhoff plate theory (Timoshenko & Woinowsky-Krieger 1959, Theory of Plates and Shells, ch. 4;
the seed paper's eq. 15): strain energy

    U = D/2 int [w_xx^2 + w_yy^2 + 2 nu w_xx w_yy + 2 (1 - nu) w_xy^2] dA,
    D = E t^3 / (12 (1 - nu^2)),

kinetic energy rho t / 2 int w_t^2 dA (no rotary inertia, the seed paper's eq. 14), and a Winkler
foundation k / 2 int w^2 dA. With tensor-product shape functions every element matrix is a sum of
Kronecker products of 1-D integrals (M = int N N^T, G = int N' N'^T, K = int N'' N''^T,
S = int N'' N^T over the element's length):

    K_e = D [K_x (x) M_y + M_x (x) K_y + nu (S_x (x) S_y^T + S_x^T (x) S_y)
             + 2 (1 - nu) G_x (x) G_y]
    M_e = rho t M_x (x) M_y,   foundation k M_x (x) M_y,

evaluated here exactly (4-point Gauss, exact for the degree-6 products). Element DOFs in Kronecker
order: index 4 p + q with p = 2 i + d_x (x-node i, x-derivative d_x) and q = 2 j + d_y.

Used by the measurement of the slab as a thin plate against the model's rigid-section slab beam
(docs/structure.md, "Slab: beam against thin plate"; benchmarks/slab_plate_vs_beam.py).
Validation: tests/test_structure_plate.py.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .shape_functions import hermite_curvature_shape, hermite_shape, hermite_slope_shape

#: 4-point Gauss-Legendre rule on [0, 1] (exact to degree 7): (points, weights)
_G4_X, _G4_W = np.polynomial.legendre.leggauss(4)
GAUSS4 = (0.5 * (_G4_X + 1.0), 0.5 * _G4_W)

#: DOFs per plate node: w, dw/dx, dw/dy, d2w/dxdy
NODE_DOFS = 4


def _shape(xi: float, L: float, order: int) -> np.ndarray:
    """Hermite shape functions (order 0), slopes (1) or curvatures (2) at ``xi``."""
    return (hermite_shape, hermite_slope_shape, hermite_curvature_shape)[order](xi, L)


def hermite_integrals(L: float) -> dict[str, np.ndarray]:
    """1-D integrals over an element of length L: M = int N N^T, G = int N' N'^T,
    K = int N'' N''^T, S = int N'' N^T, I = int N (4-point Gauss: exact)."""
    out = {k: np.zeros((4, 4)) for k in "MGKS"}
    out["I"] = np.zeros(4)
    for xi, w in zip(*GAUSS4):
        n0, n1, n2 = (_shape(xi, L, o) for o in range(3))
        out["M"] += w * L * np.outer(n0, n0)
        out["G"] += w * L * np.outer(n1, n1)
        out["K"] += w * L * np.outer(n2, n2)
        out["S"] += w * L * np.outer(n2, n0)
        out["I"] += w * L * n0
    return out


def element_stiffness(a: float, b: float, D: float, nu: float) -> np.ndarray:
    """Bending stiffness (16, 16) of an a x b element, Kronecker DOF order (module docstring)."""
    hx, hy = hermite_integrals(a), hermite_integrals(b)
    return D * (np.kron(hx["K"], hy["M"]) + np.kron(hx["M"], hy["K"])
                + nu * (np.kron(hx["S"], hy["S"].T) + np.kron(hx["S"].T, hy["S"]))
                + 2.0 * (1.0 - nu) * np.kron(hx["G"], hy["G"]))


def element_mass(a: float, b: float, mass_per_area: float) -> np.ndarray:
    """Consistent mass (16, 16) of an a x b element (also a Winkler foundation: pass k)."""
    return mass_per_area * np.kron(hermite_integrals(a)["M"], hermite_integrals(b)["M"])


class RectangularPlate:
    """A rectangular Kirchhoff plate meshed with Bogner-Fox-Schmit elements on a tensor grid.

    ``x_nodes``, ``y_nodes``: increasing node coordinates (m); node (i, j) at (x_i, y_j) has DOFs
    ``4 (i (ny + 1) + j) + (w, w_x, w_y, w_xy)`` (x-major: narrow band for a long plate).
    ``E`` (Pa), ``nu``, ``thickness`` (m), ``density`` (kg/m^3).
    """

    def __init__(self, x_nodes, y_nodes, E: float, nu: float, thickness: float,
                 density: float):
        self.x = np.asarray(x_nodes, dtype=float)
        self.y = np.asarray(y_nodes, dtype=float)
        if self.x.size < 2 or self.y.size < 2 or np.any(np.diff(self.x) <= 0) \
                or np.any(np.diff(self.y) <= 0):
            raise ValueError("plate node coordinates must be increasing, at least 2 per direction")
        self.E, self.nu, self.t, self.rho = float(E), float(nu), float(thickness), float(density)

    @property
    def D(self) -> float:
        """Flexural rigidity E t^3 / (12 (1 - nu^2)) (N m)."""
        return self.E * self.t ** 3 / (12.0 * (1.0 - self.nu ** 2))

    @property
    def mass_per_area(self) -> float:
        return self.rho * self.t

    @property
    def n_dof(self) -> int:
        return NODE_DOFS * self.x.size * self.y.size

    def node_dofs(self, i: int, j: int) -> np.ndarray:
        """(w, w_x, w_y, w_xy) DOFs of node (i, j)."""
        return NODE_DOFS * (i * self.y.size + j) + np.arange(NODE_DOFS)

    def element_dofs(self, ex: int, ey: int) -> np.ndarray:
        """Global DOFs (16,) of element (ex, ey) in Kronecker order."""
        p = np.arange(4)
        i, dx = ex + p // 2, p % 2
        q = np.arange(4)
        j, dy = ey + q // 2, q % 2
        node = i[:, None] * self.y.size + j[None, :]
        return (NODE_DOFS * node + dx[:, None] + 2 * dy[None, :]).ravel()

    def _assemble(self, element_matrix) -> sparse.csr_matrix:
        """Sum of ``element_matrix(a, b)`` over the grid (one evaluation per element size)."""
        ex, ey = np.meshgrid(np.arange(self.x.size - 1), np.arange(self.y.size - 1),
                             indexing="ij")
        ex, ey = ex.ravel(), ey.ravel()
        p = np.arange(4)
        i = ex[:, None, None] + (p // 2)[None, :, None]
        j = ey[:, None, None] + (p // 2)[None, None, :]
        dofs = (NODE_DOFS * (i * self.y.size + j) + (p % 2)[None, :, None]
                + 2 * (p % 2)[None, None, :]).reshape(-1, 16)
        a = np.round(np.diff(self.x)[ex], 12)
        b = np.round(np.diff(self.y)[ey], 12)
        vals = np.empty((ex.size, 256))
        for ab in set(zip(a.tolist(), b.tolist())):
            hit = (a == ab[0]) & (b == ab[1])
            vals[hit] = element_matrix(*ab).ravel()
        rows = np.repeat(dofs, 16, axis=1).ravel()
        cols = np.tile(dofs, (1, 16)).ravel()
        return sparse.coo_matrix((vals.ravel(), (rows, cols)),
                                 shape=(self.n_dof, self.n_dof)).tocsr()

    def stiffness_matrix(self) -> sparse.csr_matrix:
        return self._assemble(lambda a, b: element_stiffness(a, b, self.D, self.nu))

    def mass_matrix(self) -> sparse.csr_matrix:
        return self._assemble(lambda a, b: element_mass(a, b, self.mass_per_area))

    def foundation_matrix(self, k_per_area: float) -> sparse.csr_matrix:
        """Winkler foundation k int w^2 dA (k in N/m^3), consistent."""
        return self._assemble(lambda a, b: element_mass(a, b, k_per_area))

    def slope_y_foundation_matrix(self, k_per_area: float) -> sparse.csr_matrix:
        """k int (dw/dy)^2 dA: a distributed spring on the cross slope (N/m^3 x m^2 lever)."""
        return self._assemble(lambda a, b: k_per_area * np.kron(hermite_integrals(a)["M"],
                                                                hermite_integrals(b)["G"]))

    def _locate(self, nodes: np.ndarray, s: float) -> tuple[int, float, float]:
        """Element index, local coordinate in [0, 1] and length of the element containing s
        (clipped to the plate)."""
        s = float(np.clip(s, nodes[0], nodes[-1]))
        e = int(np.clip(np.searchsorted(nodes, s, side="right") - 1, 0, nodes.size - 2))
        L = float(nodes[e + 1] - nodes[e])
        return e, (s - nodes[e]) / L, L

    def point_row(self, x: float, y: float, dx: int = 0, dy: int = 0):
        """(dofs (16,), coef (16,)) with d^dx/dx^dx d^dy/dy^dy w(x, y) = coef . u[dofs]
        (a point outside the plate is clipped to its edge)."""
        ex, xi, a = self._locate(self.x, x)
        ey, eta, b = self._locate(self.y, y)
        return self.element_dofs(ex, ey), np.kron(_shape(xi, a, dx), _shape(eta, b, dy))

    def width_integral_rows(self, x: float, weights=(lambda y: np.ones_like(y),), dy: int = 0):
        """Rows of int w_(dy)(x, y) g(y) dy over the whole width, one per weight function g
        (polynomials up to degree 1 are integrated exactly): (dofs, coef (n_weights, n))."""
        ex, xi, a = self._locate(self.x, x)
        nx = _shape(xi, a, 0)
        dofs, coefs = [], []
        for ey, b in enumerate(np.diff(self.y)):
            ny = np.zeros((len(weights), 4))
            for eta, w in zip(*GAUSS4):
                yy = np.array([self.y[ey] + eta * b])
                g = np.array([float(fn(yy)[0]) for fn in weights])
                ny += w * b * np.outer(g, _shape(eta, b, dy))
            dofs.append(self.element_dofs(ex, ey))
            coefs.append(np.stack([np.kron(nx, row) for row in ny]))
        # neighbouring elements share nodes: sum duplicates
        d = np.concatenate(dofs)
        c = np.concatenate(coefs, axis=1)
        uniq, inv = np.unique(d, return_inverse=True)
        out = np.zeros((len(weights), uniq.size))
        for k in range(len(weights)):
            np.add.at(out[k], inv, c[k])
        return uniq, out

    def deflection(self, u: np.ndarray, x: float, y: float, dx: int = 0, dy: int = 0) -> float:
        dofs, coef = self.point_row(x, y, dx, dy)
        return float(coef @ np.asarray(u)[dofs])
