"""Simply supported girder spans reduced by Craig-Bampton component mode synthesis.

Each span is meshed with 3-D Euler-Bernoulli beam elements (paper section 2.2.6, eqs. 16-17):
Hermite cubic bending in the vertical and lateral planes, linear torsion, consistent mass, per
element E, mass, I_y, I_z (so that random fields vary them along the span). The span is then
reduced to

* 6 boundary coordinates (z, y, roll at each end; their static "constraint modes" are the rigid
  and linear shapes of a beam with pinned ends), which connect to the bearings, and
* the fixed-interface normal modes of the span with pinned ends (the simply supported modes),
  kept up to ``max_mode_frequency_hz``.

(Craig & Bampton 1968, AIAA J 6:1313.) The damping is applied on the reduced matrices
(:mod:`ttbpipe.structure.damping`: modal damping of every kept mode, EN 1991-2 Table 6.6 values
by default, or the paper's Rayleigh eq. 18), so no high-frequency element mode exists to be
over-damped or to limit the explicit time step (the "stiffness-proportional damping trap" of a
finely meshed girder, see docs/structure.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg

from .damping import span_damping_matrix
from .shape_functions import hermite, hermite_shape  # noqa: F401  (girder users import it from here)
from .shape_functions import hermite_slope_shape


def hermite_beam_matrices(L: float, EI: float, m: float) -> tuple[np.ndarray, np.ndarray]:
    """Element stiffness and consistent mass of a Hermite beam, DOFs (w1, w1', w2, w2').

    Przemieniecki (1968), Theory of Matrix Structural Analysis, eqs. 5.115 and 11.27.
    """
    k = EI / L ** 3 * np.array([[12, 6 * L, -12, 6 * L],
                                [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                [-12, -6 * L, 12, -6 * L],
                                [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    mm = m * L / 420.0 * np.array([[156, 22 * L, 54, -13 * L],
                                   [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                   [54, 13 * L, 156, -22 * L],
                                   [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    return k, mm


@dataclass
class SpanReduction:
    """One span's reduced model.

    Reduced coordinates q (order n = 6 + n_modes): [z_A, y_A, roll_A, z_B, y_B, roll_B,
    vertical modes, lateral modes, torsion modes]. ``basis[d]`` maps q to the FE DOFs of direction
    d (0 vertical, 1 lateral, 2 torsion).
    """

    start_m: float
    length_m: float
    node_x: np.ndarray
    basis: list                     # per direction: (n_fe_dof_d, n) arrays
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    mode_frequencies_hz: list       # per direction: fixed-interface frequencies kept
    all_frequencies_hz: list        # per direction: all fixed-interface frequencies of the mesh
    damping_ratio: float            # zeta given to the kept modes (modal) or at the Rayleigh pair
    damping_model: str              # modal | rayleigh
    rayleigh_alpha: float           # 0 for modal damping
    rayleigh_beta: float

    @property
    def n(self) -> int:
        return self.M.shape[0]

    def rows_at(self, x_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows (n,) giving z, y and roll of the girder axis at global x from q."""
        rz, ry, rr = self.rows_at_many(np.array([float(x_m)]))
        return rz[0], ry[0], rr[0]

    def rows_at_many(self, x_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`rows_at` for an array of k positions: three (k, n) arrays (x clipped to the span)."""
        s = np.clip(np.asarray(x_m, dtype=float) - self.start_m, 0.0, self.length_m)
        n_el = self.node_x.size - 1
        h = self.length_m / n_el
        e = np.minimum((s / h).astype(np.int64), n_el - 1)
        xi = (s - e * h) / h
        N = np.stack(hermite.py_func(xi, h), axis=1)                  # (k, 4)
        hermite_dofs = 2 * e[:, None] + np.arange(4)
        rz = np.einsum("kj,kjn->kn", N, self.basis[0][hermite_dofs])
        ry = np.einsum("kj,kjn->kn", N, self.basis[1][hermite_dofs])
        lin = np.stack([1.0 - xi, xi], axis=1)
        rr = np.einsum("kj,kjn->kn", lin, self.basis[2][e[:, None] + np.arange(2)])
        return rz, ry, rr


def span_slope_row(red: "SpanReduction", x_m: float) -> np.ndarray:
    """Row (n,) giving the slope dz/dx of the girder axis at global x from q (+: rising with x)."""
    s = np.clip(x_m - red.start_m, 0.0, red.length_m)
    n_el = red.node_x.size - 1
    h = red.length_m / n_el
    e = min(int(s / h), n_el - 1)
    return hermite_slope_shape((s - e * h) / h, h) @ red.basis[0][2 * e:2 * e + 4]


def _craig_bampton(K: np.ndarray, M: np.ndarray, boundary: list[int], f_max_hz: float,
                   n_min: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Craig-Bampton basis [constraint modes | kept fixed-interface modes] of one direction.

    Returns (basis (n_dof, n_b + n_kept), kept frequencies Hz, all fixed-interface frequencies Hz).
    """
    n = K.shape[0]
    interior = np.setdiff1d(np.arange(n), boundary)
    Kii = K[np.ix_(interior, interior)]
    Mii = M[np.ix_(interior, interior)]
    Kib = K[np.ix_(interior, boundary)]
    psi_c = np.zeros((n, len(boundary)))
    psi_c[boundary, np.arange(len(boundary))] = 1.0
    psi_c[interior] = -linalg.solve(Kii, Kib, assume_a="pos")
    w2, phi = linalg.eigh(Kii, Mii)
    freq = np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi)
    keep = max(int(np.sum(freq <= f_max_hz)), n_min)
    modes = np.zeros((n, keep))
    modes[interior] = phi[:, :keep]
    return np.hstack([psi_c, modes]), freq[:keep], freq


def reduce_span(start_m: float, length_m: float, n_el: int, E: np.ndarray, G: np.ndarray,
                mass: np.ndarray, Iy: np.ndarray, Iz: np.ndarray, J: np.ndarray,
                roll_inertia: np.ndarray, zeta: float, damping_model: str, rayleigh_hz,
                f_max_hz: float, n_min: int) -> SpanReduction:
    """Mesh, assemble and reduce one span; per-element arrays have length n_el; damping
    ``zeta`` by ``damping_model`` (:func:`ttbpipe.structure.damping.span_damping_matrix`)."""
    h = length_m / n_el
    nn = n_el + 1
    Kv = np.zeros((2 * nn, 2 * nn)); Mv = np.zeros_like(Kv)
    Kl = np.zeros_like(Kv); Ml = np.zeros_like(Kv)
    Kt = np.zeros((nn, nn)); Mt = np.zeros_like(Kt)
    for e in range(n_el):
        sl = slice(2 * e, 2 * e + 4)
        k, m = hermite_beam_matrices(h, E[e] * Iy[e], mass[e])
        Kv[sl, sl] += k; Mv[sl, sl] += m
        k, m = hermite_beam_matrices(h, E[e] * Iz[e], mass[e])
        Kl[sl, sl] += k; Ml[sl, sl] += m
        st = slice(e, e + 2)
        Kt[st, st] += G[e] * J[e] / h * np.array([[1, -1], [-1, 1]])
        # mean of consistent and lumped mass: cancels the O(h^2) frequency error of linear
        # elements (Hughes 1987, The Finite Element Method, section 9.2; "higher-order mass")
        Mt[st, st] += roll_inertia[e] * h / 12 * np.array([[5, 1], [1, 5]])
    bv, fv, av = _craig_bampton(Kv, Mv, [0, 2 * n_el], f_max_hz, n_min)
    bl, fl, al = _craig_bampton(Kl, Ml, [0, 2 * n_el], f_max_hz, n_min)
    bt, ft, at = _craig_bampton(Kt, Mt, [0, n_el], f_max_hz, n_min)
    nv, nl, nt = fv.size, fl.size, ft.size
    n = 6 + nv + nl + nt
    cols = [np.r_[0, 3, 6:6 + nv], np.r_[1, 4, 6 + nv:6 + nv + nl],
            np.r_[2, 5, 6 + nv + nl:n]]
    basis = []
    M = np.zeros((n, n)); K = np.zeros((n, n))
    for (Kd, Md, bd), c in zip([(Kv, Mv, bv), (Kl, Ml, bl), (Kt, Mt, bt)], cols):
        full = np.zeros((bd.shape[0], n))
        full[:, c] = bd
        basis.append(full)
        M += full.T @ Md @ full
        K += full.T @ Kd @ full
    K = 0.5 * (K + K.T); M = 0.5 * (M + M.T)
    C, alpha, beta = span_damping_matrix(M, K, [fv, fl, ft], zeta, damping_model, rayleigh_hz,
                                         all_frequencies_hz=[av, al, at])
    return SpanReduction(start_m=start_m, length_m=length_m, node_x=start_m + h * np.arange(nn),
                         basis=basis, M=M, K=K, C=C,
                         mode_frequencies_hz=[fv, fl, ft], all_frequencies_hz=[av, al, at],
                         damping_ratio=zeta, damping_model=damping_model,
                         rayleigh_alpha=alpha, rayleigh_beta=beta)
