"""Track-geometry channels, their file columns, and how rail inputs derive from them.

Sign conventions (looking in the direction of increasing chainage):

* ``vertical_left_mm``, ``vertical_right_mm``: vertical profile of each rail, positive **up**
  (rail head above its reference line).
* ``alignment_left_mm``, ``alignment_right_mm``: lateral alignment of each rail, positive to the
  **left**.
* ``cross_level_mm``: left rail height minus right rail height (positive: left rail higher).
* ``gauge_mm``: gauge deviation from nominal, positive when the gauge is **wider**, i.e. the left
  rail moved left and/or the right rail moved right: ``gauge = alignment_left - alignment_right``.

The four spectral channels of the standards (TB/T 3352, German, FRA) are

* ``vertical``  = (vertical_left + vertical_right) / 2   (mean vertical profile),
* ``alignment`` = (alignment_left + alignment_right) / 2 (mean alignment, centre-line),
* ``cross_level``, ``gauge`` as measured.

Rail inputs for the simulation derive from the four spectral channels as

    z_left  = vertical + cross_level / 2,   z_right = vertical - cross_level / 2,
    y_left  = alignment + gauge / 2,        y_right = alignment - gauge / 2.

These are the inverse of the definitions above, so per-rail channels and spectral channels
round-trip exactly.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

#: The four channels the standard spectra are given for, in a fixed order.
SPECTRAL_CHANNELS: tuple[str, ...] = ("vertical", "alignment", "cross_level", "gauge")

#: The per-rail channels an inspection file carries, in mm, besides ``chainage_m``.
INSPECTION_COLUMNS: tuple[str, ...] = (
    "vertical_left_mm", "vertical_right_mm",
    "alignment_left_mm", "alignment_right_mm",
    "cross_level_mm", "gauge_mm",
)


def spectral_from_inspection(cols: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Four spectral channels (mm) from the per-rail inspection columns (mm)."""
    return {
        "vertical": 0.5 * (np.asarray(cols["vertical_left_mm"]) + np.asarray(cols["vertical_right_mm"])),
        "alignment": 0.5 * (np.asarray(cols["alignment_left_mm"]) + np.asarray(cols["alignment_right_mm"])),
        "cross_level": np.asarray(cols["cross_level_mm"], dtype=float),
        "gauge": np.asarray(cols["gauge_mm"], dtype=float),
    }


def rails_from_spectral(vertical: np.ndarray, alignment: np.ndarray, cross_level: np.ndarray,
                        gauge: np.ndarray) -> dict[str, np.ndarray]:
    """Per-rail vertical (z, up) and lateral (y, left) inputs from the four spectral channels.

    Units are whatever the inputs are in; the simulation passes metres.
    """
    return {
        "z_left": vertical + 0.5 * cross_level,
        "z_right": vertical - 0.5 * cross_level,
        "y_left": alignment + 0.5 * gauge,
        "y_right": alignment - 0.5 * gauge,
    }


def inspection_columns_from_spectral(vertical: np.ndarray, alignment: np.ndarray,
                                     cross_level: np.ndarray, gauge: np.ndarray) -> dict[str, np.ndarray]:
    """The six per-rail inspection columns (``INSPECTION_COLUMNS``) from the four spectral channels.

    The inverse of :func:`spectral_from_inspection` for geometry without per-rail defects: the rail
    channels come from :func:`rails_from_spectral`, cross-level and gauge are copied.
    """
    rails = rails_from_spectral(vertical, alignment, cross_level, gauge)
    return {
        "vertical_left_mm": rails["z_left"], "vertical_right_mm": rails["z_right"],
        "alignment_left_mm": rails["y_left"], "alignment_right_mm": rails["y_right"],
        "cross_level_mm": np.asarray(cross_level, dtype=float),
        "gauge_mm": np.asarray(gauge, dtype=float),
    }
