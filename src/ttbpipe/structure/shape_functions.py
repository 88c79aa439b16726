"""Hermite cubic shape functions with slope DOFs: the one home of the beam interpolation.

N1..N4 at the local coordinate xi in [0, 1] of an element of length L interpolate a deflection
from the end displacements and slopes (w_a, w'_a, w_b, w'_b): N1 = 1 - 3 xi^2 + 2 xi^3,
N2 = L (xi - 2 xi^2 + xi^3), N3 = 3 xi^2 - 2 xi^3, N4 = L (xi^3 - xi^2) (Przemieniecki 1968; the
seed paper's N_Zr, N_Yr). The rails, the slab, the girder's FE mesh, the pads' seats and the
monitors all use this function, in numba kernels and in Python alike; the thin-plate element
(:mod:`ttbpipe.structure.plate`) is built from products of it and its derivatives.
"""

from __future__ import annotations

import numpy as np

from ..jit import kernel


@kernel(inline="always")
def hermite(xi, L):
    """(N1, N2, N3, N4) at local coordinate ``xi`` of an element of length ``L``."""
    xi2 = xi * xi
    xi3 = xi2 * xi
    return (1.0 - 3.0 * xi2 + 2.0 * xi3, L * (xi - 2.0 * xi2 + xi3),
            3.0 * xi2 - 2.0 * xi3, L * (xi3 - xi2))


def hermite_shape(xi: float, L: float) -> np.ndarray:
    """:func:`hermite` as an array (for the assembly's and the monitors' vector arithmetic)."""
    return np.array(hermite(float(xi), float(L)))


def hermite_slope_shape(xi: float, L: float) -> np.ndarray:
    """dN/dx of :func:`hermite` at ``xi``: the slope w' from (w_a, w'_a, w_b, w'_b)."""
    xi = float(xi)
    L = float(L)
    return np.array([(-6.0 * xi + 6.0 * xi * xi) / L, 1.0 - 4.0 * xi + 3.0 * xi * xi,
                     (6.0 * xi - 6.0 * xi * xi) / L, 3.0 * xi * xi - 2.0 * xi])


def hermite_curvature_shape(xi: float, L: float) -> np.ndarray:
    """d2N/dx2 of :func:`hermite` at ``xi``: the curvature w'' from (w_a, w'_a, w_b, w'_b)."""
    xi = float(xi)
    L = float(L)
    return np.array([(-6.0 + 12.0 * xi) / L ** 2, (-4.0 + 6.0 * xi) / L,
                     (6.0 - 12.0 * xi) / L ** 2, (-2.0 + 6.0 * xi) / L])
