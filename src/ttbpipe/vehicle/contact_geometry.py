"""Rigid wheelset on rigid rails: contact points from real wheel and rail profiles, EN 15302 conicity.

Method (docs/contact_geometry.md):

* **Mounting.** Each rail profile is inclined by its cant (1:20, 1:40 or none: its crown normal
  tilted towards the track centre) and placed so that its gauge point -- the innermost point of
  the head within ``gauge_height`` (14 mm, EN 13848-1) below the top of the inclined rail -- is at
  half the gauge from the track centre; the rail top is z = 0. The wheels sit on the axle with
  their flange backs ``flange_back_distance`` apart (1360 mm) and their taping lines at
  ``nominal_radius`` below the axle.
* **Planar contact.** At zero yaw the contact lies in the vertical plane through the axle, where
  each wheel's surface is its profile curve rotated with the wheelset roll; the search is exact
  in that plane (the minimum-distance and the vertical-gap methods coincide for a planar pair
  of curves touching at a point where both tangents agree; the vertical gap is used here).
* **Gap and roll.** For a lateral displacement y and roll phi the wheel profiles, sampled by arc
  length (``wheel_step``, default 0.02 mm), are placed in track coordinates and the vertical gap
  to the rail under each sample is taken; the smallest gap per wheel is refined by a parabola
  through its three samples. Both wheels touch when their smallest gaps are equal: phi solves
  g_L(phi) = g_R(phi) by a bracketed secant (Illinois) iteration, vectorised over all y, and the
  wheelset height follows. Quantities at the contact come from the profile splines: rolling
  radius r = r0 - z_w(s), contact angle from the rail tangent, and the principal transverse radii
  of wheel and rail for Hertz theory (the wheel's rolling-direction radius r / cos delta_w).
* **Two-point contact.** A second interior local minimum of the gap farther than
  ``min_separation`` (2 mm along the wheel) from the first, with a gap within ``two_point_tol``
  (0.05 mm by default), is a second contact point (tread + flange); its position, radius and
  angle are reported with its gap.

Sign conventions: track y positive to the LEFT, z up; the lateral displacement y of the wheelset
is positive to the left; wheelset roll positive when the left wheel rises; contact angles
positive when the normal on the wheel points up and towards the track centre (as
:mod:`ttbpipe.vehicle.contact`); lateral positions on the wheel (from its taping line) and rail
(from the upright rail's crown line) in profile coordinates, positive towards the field side.

Equivalent conicity (EN 15302:2008+A1:2010): :func:`equivalent_conicity` integrates the kinematic
(Klingel) equation of motion of the wheelset with the nonlinear Delta-r(y) function (the
standard's Annex B method: wavelength of the kinematic oscillation of amplitude y_hat, conicity
of the cone of the same wavelength, tan(gamma_e) = e0 r0 (2 pi / L)^2, in which e0 r0 cancels);
:func:`harmonic_conicity` is the describing-function (harmonic linearisation) value
(1 / pi y_hat) int_0^2pi Delta-r(y_hat sin t) / 2 sin t dt. Both equal lambda for a cone.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.interpolate import make_interp_spline, make_splprep
from scipy.optimize import brentq

from .profiles import MM, Profile

log = logging.getLogger(__name__)

#: Gauge measuring height below the top of the rail (m): EN 13848-1, standard gauge lines.
GAUGE_HEIGHT = 0.014
#: Nominal standard gauge (m) and the flange-back distance of standard wheelsets (m), the
#: Manchester benchmark set-up (Shackleton & Iwnicki 2008) and EN 15302's reference cases.
STANDARD_GAUGE = 1.435
STANDARD_FLANGE_BACK = 1.360
#: Wheel radius at the taping line of the Manchester benchmark wheelset (m): NOMRADW = 460 mm of
#: its CONTACT input (github.com/eve70a/CONTACT, examples/mbench_a22_left.inp).
BENCHMARK_WHEEL_RADIUS = 0.460


def parse_inclination(text: str | float) -> float:
    """Rail inclination as tan(angle): ``"1:40"`` -> 0.025, ``"none"``/``0`` -> 0."""
    if isinstance(text, (int, float)):
        value = float(text)
    else:
        t = text.strip().lower()
        if t in ("none", "0", "vertical", "upright"):
            return 0.0
        if ":" in t:
            a, b = t.split(":", 1)
            value = float(a) / float(b)
        else:
            value = float(t)
    if not 0.0 <= value < 0.2:
        raise ValueError(f"rail inclination {text!r}: expected 0 (none) up to 1:5, e.g. '1:40'")
    return value


# ---------------------------------------------------------------------------------------------
# Profile curves
# ---------------------------------------------------------------------------------------------
class ProfileCurve:
    """Cubic parametric spline (y(u), z(u)) through a profile's points, u = chord length (m).

    Gives points at a uniform arc-length step, the tangent slope dz/dy and the signed curvature
    (positive when z'' > 0 in the profile's own y-z axes). ``smoothing`` (m) > 0 fits a
    smoothing spline whose rms distance from the points is about ``smoothing`` (scipy
    make_splprep with s = n smoothing^2) -- for measured profiles, whose scatter (MiniProf-type
    devices: a few um) would otherwise dominate the second derivative and so the contact radii;
    0 interpolates (analytic profiles).
    """

    def __init__(self, profile: Profile, smoothing: float = 0.0):
        y, z = profile.lateral, profile.vertical
        keep = np.concatenate([[True], np.hypot(np.diff(y), np.diff(z)) > 1e-12])
        y, z = y[keep], z[keep]
        u = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))])
        self.profile = profile
        self.u = u
        if smoothing > 0:
            self.spline, _ = make_splprep([y, z], u=u, s=y.size * smoothing ** 2)
        else:
            self.spline = make_interp_spline(u, np.column_stack([y, z]), k=3)

    @property
    def length(self) -> float:
        return float(self.u[-1])

    def sample(self, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = max(int(np.ceil(self.length / step)) + 1, 10)
        u = np.linspace(0.0, self.length, n)
        yz = self._eval(u)
        return u, yz[:, 0], yz[:, 1]

    def _eval(self, u, nu=0):
        out = np.asarray(self.spline(u, nu))
        return out if out.shape[-1] == 2 and out.ndim == np.ndim(u) + 1 else np.moveaxis(out, 0, -1)

    def local(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """y, z, slope dz/dy and curvature at parameter(s) u."""
        yz = self._eval(u)
        d1 = self._eval(u, 1)
        d2 = self._eval(u, 2)
        speed2 = d1[..., 0] ** 2 + d1[..., 1] ** 2
        curv = (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]) / speed2 ** 1.5
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = d1[..., 1] / d1[..., 0]
        return yz[..., 0], yz[..., 1], slope, curv


@dataclass(frozen=True)
class RailSide:
    """One rail in side coordinates (lateral u towards this side's field side, track units)."""

    curve: ProfileCurve
    inclination: float                 # tan of the cant
    offset: float                      # u of the profile origin after inclination and placement
    top: float                         # z of the inclined profile's highest point (subtracted)
    u: np.ndarray                      # dense polyline, strictly increasing
    z: np.ndarray
    par: np.ndarray                    # spline parameter of the polyline points

    def profile_coordinate(self, u_track: np.ndarray) -> np.ndarray:
        """Lateral coordinate on the upright rail profile of a track-frame point on the rail."""
        par = np.interp(u_track, self.u, self.par)
        return self.curve.local(par)[0]

    def at(self, u_track: np.ndarray):
        """(profile y, track slope dz/du, convex curvature) of the rail at track lateral u."""
        par = np.interp(u_track, self.u, self.par)
        y, _, slope, curv = self.curve.local(par)
        beta = np.arctan(self.inclination)
        angle = np.arctan(slope) + beta            # tangent angle in the track frame
        return y, np.tan(angle), -curv             # rail convex: z'' < 0 in profile axes


def _place_rail(profile: Profile, inclination: float, gauge: float, gauge_height: float,
                step: float, smoothing: float = 0.0) -> RailSide:
    curve = ProfileCurve(profile, smoothing)
    par, y, z = curve.sample(step)
    beta = np.arctan(inclination)
    # rotate so that the crown normal tilts towards the track centre (the field side rises)
    yi = y * np.cos(beta) - z * np.sin(beta)
    zi = y * np.sin(beta) + z * np.cos(beta)
    itop = int(np.argmax(zi))
    # the longest strictly increasing run of yi through the top: the head seen from above
    lo = itop
    while lo > 0 and yi[lo - 1] < yi[lo]:
        lo -= 1
    hi = itop
    while hi < yi.size - 1 and yi[hi + 1] > yi[hi]:
        hi += 1
    yi, zi, par = yi[lo:hi + 1], zi[lo:hi + 1], par[lo:hi + 1]
    top = float(zi.max())
    zi = zi - top
    band = zi >= -gauge_height
    if zi[0] > -gauge_height:
        raise ValueError(f"rail profile {profile.name!r} does not reach {gauge_height / MM:g} mm below"
                         " its top on the gauge side: the gauge point cannot be found")
    # gauge point: innermost (smallest u) head point from the top down to the gauge height
    first = int(np.argmax(band))
    # interpolate the crossing of z = -gauge_height on the gauge side
    if first > 0:
        z0, z1 = zi[first - 1], zi[first]
        yg = yi[first - 1] + (yi[first] - yi[first - 1]) * (-gauge_height - z0) / (z1 - z0)
    else:
        yg = yi[0]
    yg = min(yg, float(yi[band].min()))
    offset = 0.5 * gauge - yg
    return RailSide(curve, inclination, offset, top, yi + offset, zi, par)


@dataclass(frozen=True)
class WheelSide:
    """One wheel: arc-length samples of its profile and its placement on the axle."""

    curve: ProfileCurve
    base: float                        # wheelset-frame lateral of the profile origin (taping line)
    par: np.ndarray
    s: np.ndarray                      # profile lateral (towards the field side)
    zw: np.ndarray                     # profile vertical (= -(r - r0))
    slope: np.ndarray                  # dzw/ds at the samples (+-inf where the profile is vertical)


def _place_wheel(profile: Profile, flange_back_distance: float, step: float,
                 smoothing: float = 0.0) -> WheelSide:
    if profile.kind != "wheel":
        raise ValueError(f"profile {profile.name!r} is a {profile.kind}, not a wheel")
    curve = ProfileCurve(profile, smoothing)
    par, s, zw = curve.sample(step)
    base = 0.5 * flange_back_distance - profile.flange_back
    slope = curve.local(par)[2]
    return WheelSide(curve, base, par, s, zw, slope)


def trace_line(base_u, radius, slope, yaw_side: float):
    """Points of a yawed wheel that can touch a straight rail (the trace line; Wang 1984, as in
    Shabana, Zaazaa & Sugiyama, Railroad Vehicle Dynamics, 2008, section 3.6).

    A wheel of revolution, its profile circle at axle coordinate u (towards its field side) of
    radius R(u), yawed by ``yaw_side`` (psi, about the vertical, in the wheel's side coordinates:
    the right wheel's mirrored axes take -psi): the surface normal at angle theta from the
    circle's lowest point is (sin theta, -R', -cos theta) in the wheelset axes, and its component
    along the rail, sin(theta) cos(psi) + R' sin(psi), vanishes for sin(theta) = -R' tan(psi).
    Only those points can carry the contact with a rail that is straight along x. Returns their
    track-frame (u, z, x) before roll: u = u cos(psi) + R sin(theta) sin(psi),
    z = -R cos(theta), x = -u sin(psi) + R sin(theta) cos(psi) (x the lead of the point ahead of
    the axle). ``slope`` = dz/du of the profile (= -R'); where |R' tan psi| > 1 (near-vertical
    flanks) the trace line has no point and the circle's side point (theta = +-90 deg, far above
    the rail) stands in. u and z are even in psi, x odd."""
    t = np.tan(yaw_side)
    with np.errstate(invalid="ignore"):
        sin_t = np.clip(np.nan_to_num(slope * t, nan=0.0, posinf=1.0, neginf=-1.0), -1.0, 1.0)
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    sp, cp = np.sin(yaw_side), np.cos(yaw_side)
    return (base_u * cp + radius * sin_t * sp, -radius * cos_t,
            -base_u * sp + radius * sin_t * cp)


# ---------------------------------------------------------------------------------------------
# The wheelset-track pair
# ---------------------------------------------------------------------------------------------
@dataclass
class ContactPair:
    """Wheel and rail profiles mounted as a wheelset on a track.

    Left and right may differ: ``wheel_right``/``rail_right`` (default: the left ones, mirrored)
    and ``nominal_radius_right`` (default: ``nominal_radius``) for measured wheel pairs.
    """

    wheel_left: Profile
    rail_left: Profile
    wheel_right: Profile | None = None
    rail_right: Profile | None = None
    inclination: float = 1.0 / 40.0
    gauge: float = STANDARD_GAUGE
    flange_back_distance: float = STANDARD_FLANGE_BACK
    nominal_radius: float = BENCHMARK_WHEEL_RADIUS
    nominal_radius_right: float | None = None   # a right wheel of another diameter (EN 15302 E5-E8)
    gauge_height: float = GAUGE_HEIGHT
    wheel_step: float = 0.02 * MM
    rail_step: float = 0.01 * MM
    two_point_tol: float = 0.05 * MM
    min_separation: float = 2.0 * MM
    smoothing: float = 0.0             # m; > 0 for measured profiles (see ProfileCurve)

    def __post_init__(self):
        wr = self.wheel_right or self.wheel_left
        rr = self.rail_right or self.rail_left
        for p, kind in ((self.wheel_left, "wheel"), (wr, "wheel"), (self.rail_left, "rail"), (rr, "rail")):
            if p.kind != kind:
                raise ValueError(f"profile {p.name!r} is a {p.kind}, expected a {kind}")
        self._wheels = tuple(_place_wheel(p, self.flange_back_distance, self.wheel_step,
                                          self.smoothing) for p in (self.wheel_left, wr))
        self._rails = tuple(_place_rail(p, self.inclination, self.gauge, self.gauge_height,
                                        self.rail_step, self.smoothing) for p in (self.rail_left, rr))

    def _radius(self, side: int) -> float:
        if side == 1 and self.nominal_radius_right is not None:
            return self.nominal_radius_right
        return self.nominal_radius

    # -- gaps -----------------------------------------------------------------------------------
    def _trace(self, side: int, yaw: float):
        """Wheel ``side``'s candidate contact points at wheelset yaw ``yaw`` (rad, track frame):
        side-coordinate lateral u, vertical z (zero roll, axle at z = 0) and lead x of each
        profile sample (:func:`trace_line`); at zero yaw the profile in the axle's plane."""
        w = self._wheels[side]
        big_u = w.base + w.s                                  # wheelset frame, side coordinates
        big_z = w.zw - self._radius(side)
        if yaw == 0.0:
            return big_u, big_z, np.zeros_like(big_u)
        sgn = 1.0 if side == 0 else -1.0
        return trace_line(big_u, -big_z, w.slope, sgn * yaw)

    def _gaps(self, side: int, y: np.ndarray, roll: np.ndarray, yaw: float = 0.0):
        """Vertical gaps (n_y, n_s) of wheel ``side`` (0 left, 1 right) at zero wheelset height,
        and the track-frame lateral u of each wheel sample; ``yaw`` (rad) turns the wheelset
        about the vertical (its trace line, :meth:`_trace`)."""
        sgn = 1.0 if side == 0 else -1.0
        rail = self._rails[side]
        big_u, big_z, _ = self._trace(side, float(yaw))
        ph = (sgn * roll)[:, None]
        c, s = np.cos(ph), np.sin(ph)
        u = (sgn * y)[:, None] + big_u[None, :] * c - big_z[None, :] * s
        z = big_u[None, :] * s + big_z[None, :] * c
        zr = np.interp(u, rail.u, rail.z, left=np.nan, right=np.nan)
        gap = z - zr
        return np.where(np.isfinite(gap), gap, np.inf), u

    def _min_gap(self, side: int, y: np.ndarray, roll: np.ndarray, yaw: float = 0.0) -> np.ndarray:
        gap, _ = self._gaps(side, y, roll, yaw)
        return gap.min(axis=1)

    def _solve_roll(self, y: np.ndarray, tol: float = 1e-12, maxit: int = 80,
                    yaw: float = 0.0) -> np.ndarray:
        """Roll angles at which both wheels touch: g_L(phi) - g_R(phi) = 0 (Illinois method)."""
        def f(phi):
            return self._min_gap(0, y, phi, yaw) - self._min_gap(1, y, phi, yaw)

        a = np.full(y.shape, -0.05)
        b = np.full(y.shape, 0.05)
        fa, fb = f(a), f(b)
        if np.any(fa * fb > 0):
            bad = y[fa * fb > 0]
            raise ValueError(f"no roll angle within +-0.05 rad makes both wheels touch at y = "
                             f"{bad[:3] / MM} mm: the profiles do not form a wheelset on this track")
        side = np.zeros(y.shape, int)
        c = b.copy()
        for _ in range(maxit):
            c = (a * fb - b * fa) / (fb - fa)
            fc = f(c)
            left = fc * fa > 0                               # root in [c, b]
            # Illinois: halve the retained end's value when the same end is kept twice
            fb = np.where(left & (side == -1), fb / 2, fb)
            fa = np.where(~left & (side == 1), fa / 2, fa)
            a, fa = np.where(left, c, a), np.where(left, fc, fa)
            b, fb = np.where(left, b, c), np.where(left, fb, fc)
            side = np.where(left, -1, 1)
            if np.all(np.abs(fc) < tol) or np.all(np.abs(b - a) < 1e-13):
                break
        worst = float(np.max(np.abs(fc)))
        if worst > 1e-9:
            log.warning("roll iteration: wheel gaps still differ by %.3g mm after %d steps", worst / MM, maxit)
        return c

    # -- contact quantities ----------------------------------------------------------------------
    def _contact(self, side: int, y: np.ndarray, roll: np.ndarray, lift: np.ndarray,
                 yaw: float = 0.0) -> dict:
        sgn = 1.0 if side == 0 else -1.0
        gap, u = self._gaps(side, y, roll, yaw)
        gap = gap + lift[:, None]
        w = self._wheels[side]
        rows = np.arange(gap.shape[0])

        def refine(idx):
            return self._refine(side, gap, u, idx)

        i1 = np.argmin(gap, axis=1)
        par1, u1, g1 = refine(i1)
        out = self._quantities(side, sgn, par1, u1, yaw)
        # second contact: interior local minima far enough from the first along the wheel
        interior = np.zeros_like(gap, bool)
        interior[:, 1:-1] = (gap[:, 1:-1] < gap[:, :-2]) & (gap[:, 1:-1] <= gap[:, 2:]) \
            & np.isfinite(gap[:, :-2]) & np.isfinite(gap[:, 2:])
        far = np.abs(w.s[None, :] - w.s[i1][:, None]) > self.min_separation
        cand = np.where(interior & far, gap, np.inf)
        i2 = np.argmin(cand, axis=1)
        has2 = np.isfinite(cand[rows, i2])
        par2, u2, g2 = refine(i2)
        second = self._quantities(side, sgn, par2, u2, yaw)
        out["second_gap"] = np.where(has2, g2, np.nan)
        out["two_point"] = has2 & (g2 <= self.two_point_tol)
        for k in ("rolling_radius", "angle", "wheel_position", "rail_position", "track_position",
                  "wheel_transverse_radius", "rail_transverse_radius"):
            out["second_" + k] = np.where(has2, second[k], np.nan)
        out["gap"] = g1
        return out

    def _refine(self, side: int, gap: np.ndarray, u: np.ndarray, idx: np.ndarray,
                lo: int = 0, hi: int | None = None):
        """Parabola through the three samples around each minimum ``idx`` (one per row of
        ``gap``): spline parameter, track lateral u and gap. Only samples ``lo`` .. ``hi - 1``
        count: a minimum on the first or last of them is kept as it is (no parabola)."""
        w = self._wheels[side]
        n = gap.shape[1]
        zone = hi is not None
        rows = np.arange(gap.shape[0])
        if zone:
            idx = np.asarray(idx)
            edge = (idx <= lo) | (idx >= hi - 1)
        i = np.clip(idx, 1, n - 2)
        g0, g1, g2 = gap[rows, i - 1], gap[rows, i], gap[rows, i + 1]
        ok = np.isfinite(g0) & np.isfinite(g1) & np.isfinite(g2)
        if zone:
            ok &= ~edge
            i = np.where(edge, idx, i)
            g1 = gap[rows, i]
        g0, g2 = np.where(ok, g0, 0.0), np.where(ok, g2, 0.0)
        den = g0 - 2 * g1 + g2
        ok &= den > 0
        t = np.where(ok, 0.5 * (g0 - g2) / np.where(ok, den, 1.0), 0.0)
        t = np.clip(t, -1.0, 1.0)
        gmin = g1 - 0.25 * (g0 - g2) * t
        par = np.interp(i + t, np.arange(n), w.par)
        if zone:
            u_c = u[rows, i] + t * 0.5 * (u[rows, np.minimum(i + 1, n - 1)]
                                          - u[rows, np.maximum(i - 1, 0)])
        else:
            u_c = u[rows, i] + t * 0.5 * (u[rows, i + 1] - u[rows, i - 1])
        return par, u_c, np.where(ok, gmin, g1)

    def zone_contacts(self, side: int, y: np.ndarray, roll: np.ndarray,
                      splits: list[float] | tuple[float, ...], spread: float = 0.0,
                      yaw: float = 0.0) -> list[dict]:
        """Contact of each zone of wheel ``side``'s profile (0 left, 1 right) on its rail.

        The wheel profile is cut at the lateral profile coordinates ``splits`` (m, towards the
        field side; e.g. one cut between the tread and the flange) into zones; in each zone the
        smallest vertical gap to the rail is its contact point (refined by a parabola when it is
        interior to the zone). The smallest gap over a fixed zone is a continuous function of y
        and roll, so each zone's normal force is continuous when the contact jumps within it or
        from one zone to another. Returns one dict per zone, from the flange side to the field
        side, with ``gap`` (m, at zero wheelset height, the reference of :meth:`_min_gap`) and
        the quantities of :meth:`_quantities`.

        Where a zone's smallest gap lies on one of its ends (the zone's part of the wheel
        approaches the rail only towards the neighbouring zone: no contact point of its own),
        the quantities are those of the zone's best interior local minimum of the gap if it has
        one, else of that end point (``interior`` False); the gap stays the zone's smallest.

        ``spread`` > 0 (m): ``track_position_centroid`` and ``rail_offset_centroid`` are the
        centroid of the zone's wheel points whose gap is within ``spread`` of its smallest,
        weighted by (spread - excess)^1.5 (the Hertz law of a virtual penetration ``spread``:
        where the contact is conformal, e.g. S1002's tread on 60E1 near the centred position
        with two rigid contact points 10 mm apart and 0.01 mm in gap, the load's position moves
        continuously with y instead of jumping from one point to the other), and
        ``longitudinal_centroid`` the same centroid of the points' lead x (:meth:`_trace`).

        ``yaw`` (rad): the wheelset's yaw relative to the track; the contact lies on the
        wheel's trace line (:func:`trace_line`).
        """
        y = np.atleast_1d(np.asarray(y, float))
        roll = np.broadcast_to(np.asarray(roll, float), y.shape)
        sgn = 1.0 if side == 0 else -1.0
        gap, u = self._gaps(side, y, roll, yaw)
        lead = self._trace(side, float(yaw))[2]
        s = self._wheels[side].s
        edges = np.concatenate([[0], np.searchsorted(s, np.sort(np.asarray(splits, float))),
                                [s.size]])
        local = np.zeros_like(gap, bool)
        local[:, 1:-1] = (gap[:, 1:-1] < gap[:, :-2]) & (gap[:, 1:-1] <= gap[:, 2:]) \
            & np.isfinite(gap[:, :-2]) & np.isfinite(gap[:, 2:])
        out = []
        for lo, hi in zip(edges[:-1], edges[1:]):
            if hi - lo < 3:
                raise ValueError(f"wheel zone between samples {lo} and {hi} is empty: the cuts "
                                 f"{np.asarray(splits) / MM} mm lie outside the wheel profile or "
                                 "too close together")
            idx = lo + np.argmin(gap[:, lo:hi], axis=1)
            _, _, g = self._refine(side, gap, u, idx, lo, hi)
            inner = np.zeros_like(local)
            inner[:, lo + 1:hi - 1] = local[:, lo + 1:hi - 1]
            cand = np.where(inner, gap, np.inf)
            i_in = np.argmin(cand, axis=1)
            rows = np.arange(y.size)
            has = np.isfinite(cand[rows, i_in])
            at_end = (idx == lo) | (idx == hi - 1)
            use = np.where(at_end & has, i_in, idx)
            par, u_c, _ = self._refine(side, gap, u, use, lo, hi)
            q = self._quantities(side, sgn, par, u_c, yaw)
            q["gap"] = g
            q["interior"] = ~at_end | has
            if spread > 0.0:
                with np.errstate(invalid="ignore"):
                    excess = gap[:, lo:hi] - g[:, None]
                    weight = np.where(np.isfinite(excess),
                                      np.clip(spread - excess, 0.0, None) ** 1.5, 0.0)
                total = weight.sum(axis=1)
                centroid = np.where(total > 0.0, (weight * np.where(np.isfinite(u[:, lo:hi]),
                                                                   u[:, lo:hi], 0.0)).sum(axis=1)
                                    / np.where(total > 0.0, total, 1.0), u_c)
                q["track_position_centroid"] = sgn * centroid
                q["rail_offset_centroid"] = centroid - self._rails[side].offset
                q["longitudinal_centroid"] = np.where(
                    total > 0.0, (weight * lead[None, lo:hi]).sum(axis=1)
                    / np.where(total > 0.0, total, 1.0), q["longitudinal_position"])
            out.append(q)
        return out

    def _quantities(self, side, sgn, par, u_c, yaw: float = 0.0):
        """Contact quantities at wheel spline parameters ``par`` and track lateral ``u_c``
        (``yaw``: the wheelset's, for the lead of the point on the trace line)."""
        w, rail = self._wheels[side], self._rails[side]
        s, zw, wslope, wcurv = w.curve.local(par)
        y_rail, rslope_track, rcurv = rail.at(u_c)
        delta = np.arctan(rslope_track)
        delta_w = np.arctan(wslope)                       # in the wheelset frame
        radius = self._radius(side) - zw
        lead = (trace_line(w.base + s, radius, wslope, sgn * yaw)[2] if yaw != 0.0
                else np.zeros_like(radius))
        with np.errstate(divide="ignore"):
            return {
                "rolling_radius": radius,
                "angle": delta,
                "wheel_position": s,
                "rail_position": y_rail,
                "track_position": sgn * u_c,
                "wheel_transverse_radius": 1.0 / wcurv,
                "rail_transverse_radius": 1.0 / rcurv,
                "wheel_longitudinal_radius": radius / np.cos(delta_w),
                "wheel_angle_in_wheelset": delta_w,
                # lateral distance (track frame, towards the field side) of the contact from
                # the inclined rail's crown point, the origin of its profile
                "rail_offset": u_c - rail.offset,
                # lead of the contact point ahead of the axle (m, track x; zero without yaw)
                "longitudinal_position": lead,
            }

    def solve(self, y: np.ndarray, yaw: float = 0.0) -> pd.DataFrame:
        """Contact table for wheelset lateral displacements ``y`` (m, + left), one row each, at
        wheelset yaw ``yaw`` (rad, relative to the track; the contact on the trace line)."""
        y = np.atleast_1d(np.asarray(y, float))
        yy = np.concatenate([[0.0], y])
        yaw = float(yaw)
        roll = self._solve_roll(yy, yaw=yaw)
        lift = -self._min_gap(0, yy, roll, yaw)          # wheelset height above the reference
        res = [self._contact(k, yy, roll, lift, yaw) for k in (0, 1)]
        z_c = lift - lift[0]
        cols = {"lateral_displacement_mm": yy / MM, "wheelset_roll_rad": roll,
                "wheelset_vertical_displacement_mm": z_c / MM}
        for k, name in ((0, "left"), (1, "right")):
            r = res[k]
            cols[f"rolling_radius_{name}_mm"] = r["rolling_radius"] / MM
            cols[f"contact_angle_{name}_rad"] = r["angle"]
            cols[f"contact_position_wheel_{name}_mm"] = r["wheel_position"] / MM
            cols[f"contact_position_rail_{name}_mm"] = r["rail_position"] / MM
            cols[f"contact_position_track_{name}_mm"] = r["track_position"] / MM
            cols[f"contact_lead_{name}_mm"] = r["longitudinal_position"] / MM
            cols[f"wheel_transverse_radius_{name}_mm"] = r["wheel_transverse_radius"] / MM
            cols[f"rail_transverse_radius_{name}_mm"] = r["rail_transverse_radius"] / MM
            cols[f"wheel_longitudinal_radius_{name}_mm"] = r["wheel_longitudinal_radius"] / MM
            cols[f"two_point_contact_{name}"] = r["two_point"]
            cols[f"second_contact_gap_{name}_mm"] = r["second_gap"] / MM
            cols[f"second_contact_position_wheel_{name}_mm"] = r["second_wheel_position"] / MM
            cols[f"second_contact_position_rail_{name}_mm"] = r["second_rail_position"] / MM
            cols[f"second_contact_angle_{name}_rad"] = r["second_angle"]
            cols[f"second_rolling_radius_{name}_mm"] = r["second_rolling_radius"] / MM
            cols[f"second_wheel_transverse_radius_{name}_mm"] = r["second_wheel_transverse_radius"] / MM
            cols[f"second_rail_transverse_radius_{name}_mm"] = r["second_rail_transverse_radius"] / MM
        cols["rolling_radius_difference_mm"] = cols["rolling_radius_left_mm"] - cols["rolling_radius_right_mm"]
        df = pd.DataFrame(cols)
        centre = df.iloc[0]
        df = df.iloc[1:].reset_index(drop=True)
        df.attrs["centred"] = centre.to_dict()
        return df


# ---------------------------------------------------------------------------------------------
# Equivalent conicity
# ---------------------------------------------------------------------------------------------
def _check_amplitude(y: np.ndarray, amplitude: float) -> None:
    if amplitude <= 0:
        raise ValueError(f"amplitude must be positive, got {amplitude}")
    if y.min() > -amplitude - 1e-12 or y.max() < amplitude + 1e-12:
        raise ValueError(f"the Delta-r function covers y in [{y.min() / MM:g}, {y.max() / MM:g}] mm,"
                         f" not the amplitude +-{amplitude / MM:g} mm")


def harmonic_conicity(y: np.ndarray, delta_r: np.ndarray, amplitude: float, n: int = 4096) -> float:
    """Harmonic linearisation: (1 / (pi A)) int_0^2pi Delta-r(A sin t)/2 sin t dt (y, Delta-r in m)."""
    y = np.asarray(y, float)
    _check_amplitude(y, amplitude)
    t = (np.arange(n) + 0.5) * 2 * np.pi / n
    dr = np.interp(amplitude * np.sin(t), y, delta_r)
    return float(np.sum(0.5 * dr * np.sin(t)) * (2 * np.pi / n) / (np.pi * amplitude))


def equivalent_conicity(y: np.ndarray, delta_r: np.ndarray, amplitude: float, n: int = 4000) -> float:
    """EN 15302 Annex B equivalent conicity at amplitude ``amplitude`` (half peak-to-peak, m).

    The kinematic (Klingel) motion y'' = -Delta-r(y) / (2 e0 r0) conserves
    y'^2 / 2 + V(y), V' = Delta-r / (2 e0 r0), so the wavelength of the oscillation between the
    turning points y- < y+ with V(y-) = V(y+) and y+ - y- = 2 amplitude is
    L = 2 int dy / sqrt(2 (V(y+) - V(y))); the equivalent cone has the same wavelength,
    tan(gamma_e) = e0 r0 (2 pi / L)^2 (e0 r0 cancels: it is not needed). Delta-r is
    interpolated linearly in the tabulated (y, Delta-r); its zero sets the centre of the motion
    (asymmetric pairs oscillate about it).
    """
    y = np.asarray(y, float)
    dr = np.asarray(delta_r, float)
    _check_amplitude(y, amplitude)
    if np.any(np.diff(y) <= 0):
        raise ValueError("lateral displacements must be strictly increasing")
    # potential W = int Delta-r dy (the factor 1/(2 e0 r0) cancels)
    w = np.concatenate([[0.0], np.cumsum(0.5 * (dr[1:] + dr[:-1]) * np.diff(y))])

    def pot(v):
        # exact integral of the piecewise-linear Delta-r
        i = np.clip(np.searchsorted(y, v) - 1, 0, y.size - 2)
        h = v - y[i]
        slope = (dr[i + 1] - dr[i]) / (y[i + 1] - y[i])
        return w[i] + dr[i] * h + 0.5 * slope * h * h

    # the lower turning point for an upper one yp: pot(ym) = pot(yp), ym < centre
    zero = np.nonzero(np.diff(np.sign(dr)))[0]
    if dr[0] >= 0 or dr[-1] <= 0:
        raise ValueError("Delta-r must change sign from negative to positive over the table")
    i0 = zero[np.argmin(np.abs(y[zero]))]
    centre = brentq(lambda v: np.interp(v, y, dr), y[i0], y[i0 + 1]) if dr[i0] != 0 else y[i0]

    w_first = pot(y[0])

    def spread(yp):
        """(y+ - y-) - 2 amplitude; large when y- would lie beyond the table's first point."""
        target = pot(yp)
        if w_first <= target:
            return 1.0
        if pot(centre) >= target:                  # y+ still in the well's flat bottom
            return yp - centre - 2 * amplitude
        return yp - brentq(lambda v: pot(v) - target, y[0], centre, xtol=1e-15) - 2 * amplitude

    hi = min(centre + 2 * amplitude, y[-1])
    if spread(hi) < 0:
        raise ValueError(f"the Delta-r table is too short for the amplitude {amplitude / MM:g} mm")
    yp = brentq(spread, centre + 1e-12, hi, xtol=1e-15)
    ym = yp - 2 * amplitude
    if ym < y[0] - 1e-9 or yp > y[-1] + 1e-9:
        raise ValueError(f"the Delta-r table [{y[0] / MM:g}, {y[-1] / MM:g}] mm is too short for the"
                         f" amplitude {amplitude / MM:g} mm (turning points {ym / MM:.3f},"
                         f" {yp / MM:.3f} mm)")
    mid = 0.5 * (yp + ym)
    theta = (np.arange(n) + 0.5) * np.pi / n - 0.5 * np.pi
    v = mid + amplitude * np.sin(theta)
    energy = 2.0 * (pot(yp) - pot(v))
    integrand = amplitude * np.cos(theta) / np.sqrt(np.maximum(energy, 1e-300))
    half = np.sum(integrand) * np.pi / n            # int_{y-}^{y+} dy / sqrt(2 (W(y+) - W(y)))
    # with V = W / (2 e0 r0): L = 2 half sqrt(2 e0 r0); tan = e0 r0 (2 pi / L)^2
    return float((np.pi / half) ** 2 / 2.0)
