"""Piers as cantilevers of a given height and section, reduced by Craig-Bampton at their top.

Each pier is a column fixed at its foundation and free at its top, where the two bearings of the
spans on either side sit. It is meshed with Euler-Bernoulli elements along its height: Hermite
cubic bending in the lateral plane (EI about the longitudinal axis, the sway that carries the
bridge's lateral modes) and linear axial elements (EA), consistent mass, plus the pier cap as a
rigid mass with its roll inertia at the top. The mesh is reduced (Craig & Bampton 1968, AIAA J
6:1313, as the girder spans in :mod:`ttbpipe.structure.girder`) to

* 3 boundary coordinates at the top, in the order the bearings use them: lateral ``y``,
  vertical ``z`` and roll (rotation about the track axis, + lifting the left side, so the
  column's slope is dy/dz = -roll), and
* the fixed-interface modes of the column (fixed at both ends) up to ``max_mode_frequency_hz``.

The top coordinates of a cantilever couple lateral and roll: the top stiffness is
EI/h^3 [[12, 6h], [6h, 4h^2]] in (y, roll), not two separate springs. Damping: modal, the same
ratio for every mode of the free-topped reduced column (its eigenvectors from (K, M)).

Without ``pier.height_m`` the pier stays the 3-DOF mass-spring-damper of
:data:`ttbpipe.structure.properties.PIER` (a 10 m pier's equivalent values).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from scipy import linalg

from .girder import _craig_bampton, hermite_beam_matrices

__all__ = ["PierReduction", "reduce_pier", "pier_from_config"]


@dataclass
class PierReduction:
    """One pier's reduced model: coordinates [y_top, z_top, roll_top, lateral modes, axial
    modes]; M, K, C dense; the fixed-interface frequencies kept per direction."""

    height_m: float
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    mode_frequencies_hz: list       # [lateral, axial]
    damping_ratio: float

    @property
    def n(self) -> int:
        return self.M.shape[0]

    def frequencies_hz(self) -> np.ndarray:
        """Natural frequencies of the free-topped pier (cap included), ascending."""
        w2 = linalg.eigh(self.K, self.M, eigvals_only=True)
        return np.sqrt(np.maximum(w2, 0.0)) / (2.0 * np.pi)


def _bar_matrices(L: float, EA: float, m: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear axial element: stiffness EA/L [[1,-1],[-1,1]], consistent mass m L/6 [[2,1],[1,2]]."""
    return (EA / L * np.array([[1.0, -1.0], [-1.0, 1.0]]),
            m * L / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]]))


def reduce_pier(height_m: float, E_Pa: float, I_lateral_m4: float, area_m2: float,
                mass_kg_m: float, cap_mass_kg: float, cap_roll_inertia_kgm2: float,
                damping_ratio: float, element_length_m: float = 1.0,
                max_mode_frequency_hz: float = 120.0, min_modes: int = 1) -> PierReduction:
    """Mesh, assemble and reduce one pier (module docstring)."""
    h = float(height_m)
    if not h > 0.0:
        raise ValueError(f"pier.height_m must be > 0, got {height_m!r}")
    n_el = max(2, int(np.ceil(h / float(element_length_m) - 1e-9)))
    le = h / n_el
    nn = n_el + 1
    # lateral bending, DOFs (y, dy/dz) per node from the foundation (node 0) up
    Kl = np.zeros((2 * nn, 2 * nn)); Ml = np.zeros_like(Kl)
    Ka = np.zeros((nn, nn)); Ma = np.zeros_like(Ka)
    for e in range(n_el):
        sl = slice(2 * e, 2 * e + 4)
        k, m = hermite_beam_matrices(le, E_Pa * I_lateral_m4, mass_kg_m)
        Kl[sl, sl] += k; Ml[sl, sl] += m
        k, m = _bar_matrices(le, E_Pa * area_m2, mass_kg_m)
        Ka[e:e + 2, e:e + 2] += k; Ma[e:e + 2, e:e + 2] += m
    # the foundation is fixed: drop node 0's DOFs
    Kl, Ml = Kl[2:, 2:], Ml[2:, 2:]
    Ka, Ma = Ka[1:, 1:], Ma[1:, 1:]
    top_l = [Kl.shape[0] - 2, Kl.shape[0] - 1]          # y, dy/dz at the top
    top_a = [Ka.shape[0] - 1]
    bl, fl, _ = _craig_bampton(Kl, Ml, top_l, max_mode_frequency_hz, min_modes)
    ba, fa, _ = _craig_bampton(Ka, Ma, top_a, max_mode_frequency_hz, min_modes)
    nl, na = fl.size, fa.size
    n = 3 + nl + na
    # coordinates: y, z, roll, lateral modes, axial modes; dy/dz = -roll
    Tl = np.zeros((bl.shape[1], n))
    Tl[0, 0] = 1.0
    Tl[1, 2] = -1.0
    Tl[2:, 3:3 + nl] = np.eye(nl)
    Ta = np.zeros((ba.shape[1], n))
    Ta[0, 1] = 1.0
    Ta[1:, 3 + nl:] = np.eye(na)
    Bl, Ba = bl @ Tl, ba @ Ta
    K = Bl.T @ Kl @ Bl + Ba.T @ Ka @ Ba
    M = Bl.T @ Ml @ Bl + Ba.T @ Ma @ Ba
    M[0, 0] += cap_mass_kg
    M[1, 1] += cap_mass_kg
    M[2, 2] += cap_roll_inertia_kgm2
    K = 0.5 * (K + K.T); M = 0.5 * (M + M.T)
    # modal damping of the free-topped column: C = M Phi diag(2 zeta w) Phi^T M (Phi M-normal)
    w2, phi = linalg.eigh(K, M)
    w = np.sqrt(np.maximum(w2, 0.0))
    C = M @ phi @ np.diag(2.0 * damping_ratio * w) @ phi.T @ M
    C = 0.5 * (C + C.T)
    return PierReduction(height_m=h, M=M, K=K, C=C, mode_frequencies_hz=[fl, fa],
                         damping_ratio=float(damping_ratio))


def pier_from_config(pier: Mapping[str, Any]) -> PierReduction:
    """:func:`reduce_pier` from a ``structure.pier`` section that has ``height_m``."""
    return reduce_pier(float(pier["height_m"]), float(pier["E_Pa"]), float(pier["I_lateral_m4"]),
                       float(pier["area_m2"]), float(pier["mass_kg_m"]),
                       float(pier["cap_mass_kg"]), float(pier["cap_roll_inertia_kgm2"]),
                       float(pier["damping_ratio"]), float(pier["element_length_m"]),
                       float(pier["max_mode_frequency_hz"]))
