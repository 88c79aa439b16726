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
cone model is switched off. With ``contact_points: 1`` one contact point per wheel (the smallest
gap): at a tread-to-flange jump the table interpolates between the two points over one grid
step. With ``contact_points: 2`` (the default) :func:`zone_tables` cuts the wheel into a tread
and a flange zone, each with a contact point and forces of its own
(:func:`ttbpipe.vehicle.contact.zone_geometry`, docs/contact_geometry.md section 7). The tables
are built before the run and interpolated in the loop.
"""

from __future__ import annotations

import numpy as np

from .contact_geometry import ContactPair, parse_inclination
from .profiles import profile_by_name_or_path

__all__ = ["profile_pair", "profile_table", "flange_split", "zone_tables", "TABLE_HALF_RANGE_M",
           "TABLE_STEP_M"]

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


def flange_split(pair: ContactPair, y: np.ndarray) -> float | None:
    """Where to cut the left wheel's profile into a tread and a flange zone (profile lateral
    coordinate, m), or None when the contact moves continuously onto the flange.

    The single contact point of the rigid pair (smallest gap, zero roll) is followed over the
    wheelset displacements ``y`` >= 0 (towards the left rail's flange). Where it jumps along the
    wheel by more than the pair's ``min_separation`` (2 mm) to a point that was already a
    second local minimum of the gap one step before (or the point it leaves stays one), two
    separate parts of the wheel touch the rail: a two-point contact. A fast but continuous
    sweep of the contact over a conformal part of the profile (S1002's root arc on the rail's
    gauge corner) is not a jump. Of the two-point jumps, the one with the largest change of
    contact angle is the one from the tread to the flange; the cut lies halfway between its two
    contact points, on wheel points that never carry the contact of the rigid pair.
    """
    y = np.asarray(y, float)
    y = y[y >= 0.0]
    contact = pair._contact(0, y, np.zeros_like(y), np.zeros_like(y))
    s, angle = contact["wheel_position"], contact["angle"]
    second = contact["second_wheel_position"]
    near = 0.5 * pair.min_separation
    with np.errstate(invalid="ignore"):
        jump = (np.abs(np.diff(s)) > pair.min_separation) & (
            (np.abs(second[:-1] - s[1:]) < near) | (np.abs(second[1:] - s[:-1]) < near))
    if not np.any(jump):
        return None
    k = np.flatnonzero(jump)[np.argmax(np.abs(np.diff(angle))[jump])]
    return float(0.5 * (s[k] + s[k + 1]))


#: A zone whose gap exceeds the contact's by this much (m) is far from any elastic approach
#: (about 0.1 mm at the static wheel load): rows where it has no point above the rail hold it.
OPEN_ZONE_GAP_M = 1.0e-3

#: Virtual penetration (m) for the position of a zone's load: about half the elastic approach at
#: the static wheel load (0.1 mm), the share of the rigid overlap that the Hertz patch covers
#: (Piotrowski & Kik, Vehicle System Dynamics 46 (2008) 27-48: 0.55).
CONTACT_SPREAD_M = 5.0e-5

#: Columns of :func:`zone_tables` per zone.
ZONE_TABLE_COLUMNS = ("y_rel_m", "rolling_radius_m", "gap_change_m", "contact_angle_rad",
                      "wheel_transverse_radius_m", "rail_transverse_radius_m",
                      "contact_lateral_m", "rail_offset_m", "wheel_longitudinal_radius_m",
                      "contact_lead_m")


def zone_tables(p, half_range_m: float = TABLE_HALF_RANGE_M, step_m: float = TABLE_STEP_M,
                pair: ContactPair | None = None, yaw: float = 0.0,
                split: float | None | str = "find") -> tuple[np.ndarray, float | None, ContactPair]:
    """Per zone of the LEFT wheel (tread and flange, :func:`flange_split`; one zone when the
    contact never jumps), on the y_rel grid of :func:`profile_table`, the columns
    :data:`ZONE_TABLE_COLUMNS`: y_rel, rolling radius r (shifted by the same amount as the
    one-point table, so that the centred contact rolls on the nominal radius), gap change
    dz = g(0) - g_zone(y) (the same reference g(0), the smallest gap of the centred wheel, for
    every zone: a zone whose dz falls short of the other's by more than the elastic approach is
    open), contact angle, transverse radii of wheel and rail, the lateral distance of the zone's
    load from the wheelset centre (track frame, zero roll) and from the inclined rail's crown
    point (the origin of the rail profile; track frame, towards the field side) -- both the
    centroid of the zone's overlap at the virtual penetration :data:`CONTACT_SPREAD_M`
    (:meth:`ContactPair.zone_contacts`), so that the load moves continuously over a conformal
    tread -- and the wheel's
    principal radius in the rolling direction r / cos(delta_w) (delta_w the profile's angle in
    the wheelset frame: the normal section of a surface of revolution), and the lead of the
    load ahead of the axle (the same centroid; zero without yaw). Returns (array
    (n_zones, n, 10), the cut or None, the pair); zones ordered flange first.

    ``yaw`` (rad): the wheelset's yaw relative to the track, the contact on the wheel's trace
    line (:func:`ttbpipe.vehicle.contact_geometry.trace_line`); the reference gap g(0) stays the
    centred, unyawed wheel's, so that dz carries the drop or rise that yaw brings. ``split``:
    the tread/flange cut to use (a float or None), by default found at zero yaw
    (:func:`flange_split`; the zones are parts of the wheel and do not move with yaw)."""
    pair = profile_pair(p) if pair is None else pair
    n = int(round(half_range_m / step_m))
    y = np.arange(-n, n + 1) * step_m
    zero = np.zeros_like(y)
    centre = pair._min_gap(0, np.zeros(1), np.zeros(1))[0]
    one = pair._contact(0, np.zeros(1), np.zeros(1), np.zeros(1))
    shift = float(p.wheel_radius) - float(one["rolling_radius"][0])
    if isinstance(split, str):
        split = flange_split(pair, y)
    zones = pair.zone_contacts(0, y, zero, [] if split is None else [split],
                               spread=CONTACT_SPREAD_M, yaw=float(yaw))
    out = np.empty((len(zones), y.size, len(ZONE_TABLE_COLUMNS)))
    for k, z in enumerate(zones):
        out[k] = np.column_stack([y, z["rolling_radius"] + shift, centre - z["gap"], z["angle"],
                                  z["wheel_transverse_radius"], z["rail_transverse_radius"],
                                  z["track_position_centroid"] - y, z["rail_offset_centroid"],
                                  (z["rolling_radius"] + shift) / np.cos(z["wheel_angle_in_wheelset"]),
                                  z["longitudinal_centroid"]])
        # rows where no point of the zone lies above the rail head (the flange inside the
        # rail when the wheel moves far towards the track centre): the zone is open there;
        # hold the nearest row that has a point, which must then be far from contact
        bad = ~np.all(np.isfinite(out[k][:, [1, 2, 3, 6, 7, 8, 9]]), axis=1)
        if bad.all():
            raise ValueError(f"train.contact: profiles {p.wheel_profile!r} on {p.rail_profile!r}: "
                             f"zone {k} of the wheel never lies above the rail")
        if bad.any():
            good = np.flatnonzero(~bad)
            near = good[np.clip(np.searchsorted(good, np.flatnonzero(bad)), 0, good.size - 1)]
            near = np.where(np.abs(good[np.clip(np.searchsorted(good, np.flatnonzero(bad)) - 1, 0,
                                                 good.size - 1)] - np.flatnonzero(bad))
                            < np.abs(near - np.flatnonzero(bad)),
                            good[np.clip(np.searchsorted(good, np.flatnonzero(bad)) - 1, 0,
                                         good.size - 1)], near)
            if np.max(out[k][near, 2]) > -OPEN_ZONE_GAP_M:
                i = int(np.flatnonzero(bad)[0])
                raise ValueError(f"train.contact: profiles {p.wheel_profile!r} on "
                                 f"{p.rail_profile!r}: zone {k} of the wheel leaves the rail head "
                                 f"near contact at y_rel = {y[i] * 1e3:.2f} mm; check the gauge "
                                 "and the flange-back distance")
            out[k][bad, 1:] = out[k][near, 1:]
    return out, split, pair
