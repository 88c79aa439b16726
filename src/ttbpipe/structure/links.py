"""Accumulator of the spring-damper links of the structure while it is assembled.

A link is one spring and damper acting on a linear form of DOFs (``sum coef_j q_j``, CSR rows);
a link triple is three of them (vertical, lateral, roll) over one shared DOF list, the compact
form of the CA mortar and foundation links (docs/dev/structure_interface.md).
"""

from __future__ import annotations

import numpy as np


class LinkAccumulator:
    """Accumulates spring-damper links (CSR rows of (dof, coef), stiffness, damping)."""

    def __init__(self) -> None:
        self.dofs: list[np.ndarray] = []
        self.coefs: list[np.ndarray] = []
        self.k: list[float] = []
        self.c: list[float] = []
        self.kind: list[str] = []
        # triples in chunks of one or more: DOFs per triple, their DOFs and (n, 3) coefficients
        # one after the other, (k, 3) stiffnesses and dampings
        self.tri_counts: list[np.ndarray] = []
        self.tri_dofs: list[np.ndarray] = []
        self.tri_coefs: list[np.ndarray] = []
        self.tri_k: list[np.ndarray] = []
        self.tri_c: list[np.ndarray] = []
        self.tri_kind: list[str] = []

    def add(self, dofs, coefs, k: float, c: float, kind: str) -> None:
        dofs = np.asarray(dofs, dtype=np.int64)
        coefs = np.asarray(coefs, dtype=float)
        keep = coefs != 0.0
        self.dofs.append(dofs[keep]); self.coefs.append(coefs[keep])
        self.k.append(float(k)); self.c.append(float(c)); self.kind.append(kind)

    def add_triple(self, rows, k3, c3, kind: str) -> None:
        """Three links (vertical, lateral, roll), each (dofs, coefs), over one shared DOF list."""
        union: dict[int, int] = {}
        for dofs, _ in rows:
            for q in dofs:
                union.setdefault(int(q), len(union))
        coef = np.zeros((len(union), 3))
        for r, (dofs, coefs) in enumerate(rows):
            for q, c in zip(dofs, coefs):
                coef[union[int(q)], r] += c
        keep = np.any(coef != 0.0, axis=1)
        dofs = np.fromiter(union, dtype=np.int64)[keep]
        self.add_triples(np.array([dofs.size]), dofs, coef[keep], [k3], [c3], kind)

    def add_triples(self, counts, dofs, coefs, k3, c3, kind: str) -> None:
        """Several triples at once, in order: ``counts[i]`` DOFs of triple i, the triples' DOFs
        and (n, 3) coefficients one after the other (no zero rows), (len(counts), 3) stiffnesses
        and dampings."""
        counts = np.asarray(counts, dtype=np.int64)
        self.tri_counts.append(counts)
        self.tri_dofs.append(np.asarray(dofs, dtype=np.int64))
        self.tri_coefs.append(np.asarray(coefs, dtype=float).reshape(-1, 3))
        self.tri_k.append(np.asarray(k3, dtype=float).reshape(-1, 3))
        self.tri_c.append(np.asarray(c3, dtype=float).reshape(-1, 3))
        self.tri_kind.extend([kind] * counts.size)

    def triple_arrays(self):
        """(ptr, dof, coef (3 per dof, flattened), k (3 per triple), c (3 per triple))."""
        if not self.tri_kind:
            return (np.zeros(1, dtype=np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0),
                    np.zeros(0))
        ptr = np.zeros(len(self.tri_kind) + 1, dtype=np.int64)
        ptr[1:] = np.cumsum(np.concatenate(self.tri_counts))
        return (ptr, np.concatenate(self.tri_dofs), np.concatenate(self.tri_coefs).ravel(),
                np.concatenate(self.tri_k).ravel(), np.concatenate(self.tri_c).ravel())

    def arrays(self):
        """CSR arrays in insertion order (sorting by term count measured no faster)."""
        self.order = np.arange(len(self.k))
        ptr = np.zeros(len(self.k) + 1, dtype=np.int64)
        ptr[1:] = np.cumsum([d.size for d in self.dofs])
        dof = np.concatenate(self.dofs) if self.dofs else np.zeros(0, np.int64)
        coef = np.concatenate(self.coefs) if self.coefs else np.zeros(0)
        return ptr, dof.astype(np.int64), coef, np.array(self.k, float), np.array(self.c, float)
