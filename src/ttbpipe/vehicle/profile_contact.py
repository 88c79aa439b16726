"""The coupled model's contact-geometry table from real wheel and rail profiles.

The coupled loop looks each wheel's contact up in a table over its lateral displacement
relative to its rail, y_rel (:mod:`ttbpipe.vehicle.contact`: rolling radius r, gap change dz,
contact angle delta, Hertz ellipse and Kalker coefficients; the right wheel reads the same
table at -y_rel). ``train.contact.profile: profiles`` builds that table from a profile pair
(``wheel_profile``, ``rail_profile``: shipped names as ``ttbpipe contact-geometry`` takes them,
or measured point files; ``rail_inclination``, ``gauge_m``, ``flange_back_m``), by the
contact-point search of :class:`ttbpipe.vehicle.contact_geometry.ContactPair` for one wheel on
its rail, the wheelset held level (the loop adds the wheelset's own roll and the rails' motion
to the looked-up values, as it does for the cone):

* dz(y) = g(0) - g(y), with g the smallest vertical gap between the wheel and its rail at
  lateral shift y and zero roll (positive: the contact point lies lower, more penetration);
* r(y) the wheel's radius at the contact point, shifted so that r(0) is the nominal radius
  (``wheel_radius``: the wheelset rolls at V / r0 in the centred position);
* delta(y) the contact angle; the transverse radii of wheel and rail at the contact point for
  Hertz's ellipse.

Where the flange touches, the table's contact angle reaches the flange angle (about 70 degrees
for S1002 on 60E1) and its normal force carries the lateral load, so the flange spring of the
cone model is switched off. One contact point per wheel (the smallest gap): at a tread-to-flange
jump the table interpolates between the two points over one grid step; two simultaneous points
with forces of their own are not modelled yet. The table is built before the run and is
interpolated in the loop (the same kernel as every table), so the step costs the same.
"""

from __future__ import annotations

import numpy as np

from .contact_geometry import ContactPair, parse_inclination
from .profiles import profile_by_name_or_path

__all__ = ["profile_pair", "profile_table", "TABLE_HALF_RANGE_M", "TABLE_STEP_M"]

#: Lateral range (+-) and step of the table (m): the flange of S1002 on 60E1 at 1435/1360 mm is
#: reached near 6-7 mm; 15 mm covers flange climbing; 0.1 mm resolves the tread-flange jump.
TABLE_HALF_RANGE_M = 0.015
TABLE_STEP_M = 1.0e-4


def profile_pair(p) -> ContactPair:
    """The wheelset on its track from ``train.contact`` (ContactParameters ``p``)."""
    return ContactPair(profile_by_name_or_path(p.wheel_profile, "wheel"),
                       profile_by_name_or_path(p.rail_profile, "rail"),
                       inclination=parse_inclination(p.rail_inclination), gauge=float(p.gauge_m),
                       flange_back_distance=float(p.flange_back_m),
                       nominal_radius=float(p.wheel_radius))


def profile_table(p, half_range_m: float = TABLE_HALF_RANGE_M,
                  step_m: float = TABLE_STEP_M) -> tuple[np.ndarray, ContactPair]:
    """Columns y_rel, r, dz, delta, wheel transverse radius, rail transverse radius (m, rad) of
    the LEFT wheel, and the pair (module docstring)."""
    pair = profile_pair(p)
    n = int(round(half_range_m / step_m))
    y = np.arange(-n, n + 1) * step_m
    zero = np.zeros_like(y)
    gap = pair._min_gap(0, y, zero)
    centre = pair._min_gap(0, np.zeros(1), np.zeros(1))[0]
    contact = pair._contact(0, y, zero, zero)
    radius = contact["rolling_radius"] - contact["rolling_radius"][n] + float(p.wheel_radius)
    table = np.column_stack([y, radius, centre - gap, contact["angle"],
                             contact["wheel_transverse_radius"], contact["rail_transverse_radius"]])
    # a straight generator has an infinite transverse radius (zero curvature): allowed
    invalid = np.isnan(table)
    invalid[:, :4] |= ~np.isfinite(table[:, :4])
    bad = np.argwhere(invalid)
    if bad.size:
        i, j = bad[0]
        raise ValueError(f"train.contact: profiles {p.wheel_profile!r} on {p.rail_profile!r}: no "
                         f"contact point at y_rel = {y[i] * 1e3:.2f} mm (column {j}): the wheel "
                         "leaves the rail head within the table's range; check the gauge and the "
                         "flange-back distance")
    return table, pair
