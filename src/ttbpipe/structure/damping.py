"""Girder damping: EN 1991-2 values and the damping matrix of a Craig-Bampton span.

**Values.** EN 1991-2:2003, 6.4.6.3.1, Table 6.6 gives the lower limit of the critical damping
ratio to assume in a dynamic analysis of a railway bridge, by span length L (m) and type of
construction (standards sheet, docs/reference/standards.md [V]):

========================================  =======================  ===========
construction                              L < 20 m                  L >= 20 m
========================================  =======================  ===========
steel and composite                       0.5 + 0.125 (20 - L) %    0.5 %
prestressed concrete                      1.0 + 0.07 (20 - L) %     1.0 %
filler beam and reinforced concrete       1.5 + 0.07 (20 - L) %     1.5 %
========================================  =======================  ===========

Below 30 m, 6.4.6.3.1(3) lets a moving-load analysis (no vehicle-bridge interaction) add
Delta zeta = (0.0187 L - 0.00064 L^2) / (1 - 0.0441 L - 0.0044 L^2 + 0.000255 L^3) % (eq. 6.13,
Figure 6.15 [M: formula as quoted in the UIC 776-2 background, not re-read in the standard]) for
the interaction it leaves out. The coupled train-track-bridge model carries that interaction
itself, so ``additional_damping`` is off by default and belongs to moving-load cases.

**Matrix.** ``damping_model: modal`` (default) gives every kept fixed-interface mode of a span
(the simply supported vertical, lateral and torsion modes) exactly the ratio zeta: in the span's
Craig-Bampton coordinates the modes are mass-normalised (phi^T M phi = I, phi^T K phi =
diag omega^2), so the block C_modes = diag(2 zeta omega_i) is modal damping (Clough & Penzien,
Dynamics of Structures, 2nd ed., s. 12-5); the six boundary coordinates (rigid and linear shapes
of the pinned span) carry no damping of their own, the bearings carry theirs. ``rayleigh`` is the
paper's eq. 18, C = alpha M + beta K matched at two frequencies: exact only at those two, and
with the default pair (the first two span modes: first vertical and first lateral) a nominal
2 % becomes 2.9 to 10 % on the second to fourth vertical modes, which is why it is not the
default.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

#: EN 1991-2 Table 6.6: construction -> (zeta at L >= 20 m [%], increase per metre below 20 m [%]).
TABLE_6_6 = {
    "steel_composite": (0.5, 0.125),
    "prestressed_concrete": (1.0, 0.07),
    "reinforced_concrete": (1.5, 0.07),
}
DAMPING_MODELS = ("modal", "rayleigh")


def table_6_6_damping_ratio(span_m: float, construction: str) -> float:
    """Lower-limit critical damping ratio (fraction) of EN 1991-2 Table 6.6."""
    if construction not in TABLE_6_6:
        raise ValueError(f"structure.girder.construction: {construction!r}; expected one of "
                         f"{sorted(TABLE_6_6)} (EN 1991-2 Table 6.6)")
    base, slope = TABLE_6_6[construction]
    return 0.01 * (base + slope * max(0.0, 20.0 - float(span_m)))


def additional_damping_ratio(span_m: float) -> float:
    """EN 1991-2 eq. 6.13 additional damping (fraction) for spans below 30 m, else 0."""
    L = float(span_m)
    if L >= 30.0:
        return 0.0
    percent = (0.0187 * L - 0.00064 * L * L) / (1 - 0.0441 * L - 0.0044 * L * L
                                                + 0.000255 * L ** 3)
    return 0.01 * max(0.0, percent)


def girder_damping_ratio(span_m: float, girder: Mapping[str, Any]) -> float:
    """The damping ratio of a span: ``girder.damping_ratio`` if given, else Table 6.6 for the
    span's length and ``girder.construction``; plus eq. 6.13 if ``additional_damping``."""
    if girder.get("damping_ratio") is not None:
        zeta = float(girder["damping_ratio"])
    else:
        zeta = table_6_6_damping_ratio(span_m, str(girder["construction"]))
    if girder.get("additional_damping"):
        zeta += additional_damping_ratio(span_m)
    return zeta


def span_damping_matrix(M: np.ndarray, K: np.ndarray, mode_frequencies_hz: list,
                        zeta: float, model: str, rayleigh_hz=None,
                        all_frequencies_hz: list | None = None):
    """Damping matrix of one span in its reduced coordinates (module docstring).

    ``mode_frequencies_hz``: per direction, the kept fixed-interface frequencies, whose
    coordinates follow the six boundary ones in that order. Returns (C, alpha, beta); alpha and
    beta are 0 for modal damping.
    """
    if model == "modal":
        omega = 2 * np.pi * np.concatenate([np.asarray(f, float) for f in mode_frequencies_hz])
        C = np.zeros_like(M)
        idx = 6 + np.arange(omega.size)
        C[idx, idx] = 2.0 * zeta * omega
        return C, 0.0, 0.0
    if model != "rayleigh":
        raise ValueError(f"structure.girder.damping_model: {model!r}; expected one of "
                         f"{list(DAMPING_MODELS)}")
    if rayleigh_hz is None:
        first = np.sort(np.concatenate(all_frequencies_hz or mode_frequencies_hz))[:2]
        w1, w2 = 2 * np.pi * first
    else:
        w1, w2 = 2 * np.pi * np.asarray(rayleigh_hz, dtype=float)
    alpha = 2 * zeta * w1 * w2 / (w1 + w2)   # paper eq. 18
    beta = 2 * zeta / (w1 + w2)
    return alpha * M + beta * K, alpha, beta
