"""Modal analysis of the structure: natural frequencies and mode shapes (scipy sparse eigsh).

The global M and K are assembled from the same packed arrays the time-loop kernels use
(:func:`~ttbpipe.structure.matrices.assemble_matrices`), restricted to the free DOFs, and solved
with ARPACK in shift-invert mode about sigma (lowest modes first). Each mode is classified by the
share of its kinetic energy in each component (rails, slab, sleepers/ballast, piers, girder
vertical/lateral/torsion), which is how "the first vertical / lateral girder mode" of the coupled
structure is identified. Each mode's damping ratio is the classical light-damping estimate
zeta_j = phi_j^T C phi_j / (2 omega_j) for mass-normalised phi_j (exact for classically damped
systems; Clough & Penzien, Dynamics of Structures, 2nd ed., s. 12-5): what the girder damping,
the bearings and the track's dampers give that mode together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import linalg as splinalg


@dataclass
class ModalResult:
    """Frequencies (Hz, ascending), mass-normalised shapes over all DOFs, kinetic-energy shares,
    damping ratios (module docstring)."""

    frequencies_hz: np.ndarray
    shapes: np.ndarray            # (n_dof, n_modes), fixed DOFs are 0
    shares: dict                  # component -> (n_modes,) share of kinetic energy
    damping_ratios: np.ndarray    # (n_modes,) phi^T C phi / (2 omega)

    def dominant(self) -> list[str]:
        """Component with the largest kinetic-energy share, per mode."""
        names = list(self.shares)
        table = np.vstack([self.shares[n] for n in names])
        return [names[i] for i in np.argmax(table, axis=0)]

    def first(self, component: str, min_share: float = 0.3) -> float:
        """Frequency (Hz) of the lowest mode with at least ``min_share`` in ``component``."""
        hit = np.flatnonzero(self.shares[component] >= min_share)
        if hit.size == 0:
            raise ValueError(f"no mode among the {self.frequencies_hz.size} computed has "
                             f">= {min_share:.0%} of its kinetic energy in {component}; compute "
                             "more modes")
        return float(self.frequencies_hz[hit[0]])


def component_index_sets(model) -> dict[str, np.ndarray]:
    """DOF indices of each component (girder coordinates split by direction)."""
    info = model.dof_info
    out = {"rail": np.arange(0, info["slab"]),
           "slab": np.arange(info["slab"], info["sleeper"]),
           "sleeper_ballast": np.arange(info["sleeper"], info["pier"]),
           "pier": np.concatenate([np.arange(info["pier"], info["span"])]
                                  + [np.arange(o, o + red.n) for o, red in
                                     zip(info["pier_top_dof0"], model.piers)]).astype(np.int64)}
    vert, lat, tor = [], [], []
    for o, red in zip(info["span_dof0"], model.spans):
        nv, nl, nt = (f.size for f in red.mode_frequencies_hz)
        vert += [o, o + 3, *range(o + 6, o + 6 + nv)]
        lat += [o + 1, o + 4, *range(o + 6 + nv, o + 6 + nv + nl)]
        tor += [o + 2, o + 5, *range(o + 6 + nv + nl, o + red.n)]
    out["girder_vertical"] = np.array(vert, dtype=np.int64)
    out["girder_lateral"] = np.array(lat, dtype=np.int64)
    out["girder_torsion"] = np.array(tor, dtype=np.int64)
    return out


#: Seed of the fixed ARPACK start vector of :func:`modal_analysis` (a numerical start, not a
#: random input of a study).
MODAL_START_SEED = 20240101


def modal_analysis(model, n_modes: int = 20, sigma_hz: float = 0.0,
                   matrices: tuple | None = None) -> ModalResult:
    """Lowest ``n_modes`` modes above ``sigma_hz`` of the undamped structure.

    ``matrices``: the model's ``(M, K, C)`` when the caller has them already (their assembly
    costs about a third of one analysis of a three-span bridge)."""
    M, K, C = model.matrices() if matrices is None else matrices
    free = np.flatnonzero(~model.fixed)
    Mf, Kf = M[free][:, free].tocsc(), K[free][:, free].tocsc()
    k = min(n_modes, free.size - 2)
    sigma = -1.0 if sigma_hz <= 0 else (2 * np.pi * sigma_hz) ** 2
    # ARPACK's own start vector comes from a generator whose state carries over from earlier
    # calls in the process, so the last digits of a sample's frequencies (1e-12 Hz measured)
    # depended on the analyses before it in its batch; a fixed start vector makes them depend
    # on the model alone
    start = np.random.default_rng(MODAL_START_SEED).standard_normal(free.size)
    w2, vec = splinalg.eigsh(Kf, k=k, M=Mf, sigma=sigma, which="LM", v0=start)
    order = np.argsort(w2)
    w2, vec = w2[order], vec[:, order]
    shapes = np.zeros((model.n_dof, k))
    shapes[free] = vec
    Mv = M @ shapes
    total = np.einsum("ij,ij->j", shapes, Mv)
    shares = {}
    for name, idx in component_index_sets(model).items():
        if idx.size == 0:
            shares[name] = np.zeros(k)
            continue
        # kinetic energy of a block: the girder's M couples only within a direction, so the
        # block-restricted quadratic forms add up to the total
        sub = M[idx][:, idx] @ shapes[idx]
        shares[name] = np.einsum("ij,ij->j", shapes[idx], sub) / total
    omega = np.sqrt(np.maximum(w2, 0))
    modal_c = np.einsum("ij,ij->j", shapes, C @ shapes)
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where(omega > 0, modal_c / (2 * omega), np.nan)
    return ModalResult(omega / (2 * np.pi), shapes, shares, zeta)
