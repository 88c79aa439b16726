"""Wheel-rail contact: Hertz normal law, contact geometry, Kalker creep, Shen-Hedrick-Elkins, flange.

Formulas and sources (physics.md section 4 unless stated):

* Hertz normal force P = (dZ/G)^1.5 for dZ > 0, else 0 (loss of contact), with
  G = 4.57 R^-0.149 1e-8 (conical tread) or 3.86 R^-0.115 1e-8 (worn/LM tread), R the wheel
  radius in m, G in m/N^(2/3) (Zhai's empirical fit of Hertz theory).
* Contact ellipse (Hertz theory; Johnson, Contact Mechanics, 1985, eqs. 4.36-4.40): with
  relative curvatures A (rolling direction x) and B (lateral y), A + B = 1/2 sum 1/R, the
  eccentricity e solves B/A = [E(e)/(1-e^2) - K(e)] / [K(e) - E(e)] (A < B; swap otherwise), and
  a_x = m c, b_y = n c with c = [3 N (1 - nu^2) / (2 E (A + B))]^(1/3),
  m^3 = 2 (K - E)(A + B) / (pi A e^2) for the major axis. Elliptic integrals from scipy (table
  building only); the run-time kernels use the tabulated m, n.
* Kalker linear theory: G_s = E / 2(1 + nu); f11 = G_s ab C11, f22 = G_s ab C22,
  f23 = G_s (ab)^1.5 C23, f33 = G_s (ab)^2 C33; F_x = -f11 xi_x, F_y = -f22 xi_y - f23 xi_sp,
  M_z = f23 xi_y - f33 xi_sp (spin in rad/m). Coefficients: Kalker's table for nu = 0.25
  (CONTACT ``linrol`` / Kalker 1967 Table E.3); the C23 value at a/b = 0.8 is printed 1.15 in
  physics.md and is corrected to 1.25 here (the printed value breaks the monotone trend of its
  neighbours 1.14 and 1.36).
* Shen-Hedrick-Elkins (1983) saturation: beta = |F| / (mu N); F' = mu N (beta - beta^2/3 +
  beta^3/27) for beta <= 3, else mu N; F_x, F_y and M_z are scaled by F'/|F|.
  This is creep law ``kalker_she`` (``train.contact.creep_law``, the default).
* Creep law ``polach``: O. Polach, "A fast wheel-rail forces calculation computer code", Vehicle
  System Dynamics 33 Suppl. (1999) 728-739, with the adhesion fall-off of O. Polach, "Creep
  forces in simulations of traction vehicles running on adhesion limit", Wear 258 (2005)
  992-1000: the tangential force from Kalker's coefficients and the ellipse's semi-axes, large
  spin through the equivalent creepage s_yC = xi_y + xi_sp a and Polach's lateral spin force,
  mu = mu0 [(1 - A) exp(-B w) + A] with the slip velocity w (:func:`_polach_forces`); the spin
  moment is Kalker's linear one scaled with the force (:func:`_polach_creep_forces`).
* Flange contact: a stiff lateral spring beyond the flange clearance,
  F = -k_f (y_rel - delta_f) for y_rel > delta_f (Knudsen, Feldberg & True 1991, "Bifurcations
  and chaos in a model of a rolling railway wheelset", Phil. Trans. R. Soc. A 338: delta_f =
  9.1 mm, k_f = 1.823e7 N/m [M]).

* Hertz flexibility from the curvatures (two-point profile contact): delta = G N^(2/3) with
  G = 3 K(e) (1 - nu^2) / (pi E m c_1), the major semi-axis m c_1 N^(1/3) (Johnson eqs.
  4.36-4.40: delta = 3 N K(e) / (2 pi a E*), 1/E* = 2 (1 - nu^2)/E for wheel and rail of one
  steel); circular limit delta = a^2 / R (Johnson eq. 4.23).

Geometry tables: a contact-geometry table gives, for the LEFT wheel as a function of the
relative lateral displacement y_rel = y_wheelset - y_rail (m, + left), the rolling radius r, the
change dz of the rigid wheel-rail gap (how much the wheel's contact point drops below its nominal
height: positive means more penetration), the contact angle delta (positive: the normal on the
wheel points up and towards the track centre), the ellipse coefficients m, n, the curvature sum
A + B and the four Kalker coefficients. The right wheel uses the same table at -y_rel (left/right
mirror symmetry of the profile pair). A conical tread gives r = r0 + lambda y, dz = lambda y,
delta = atan(lambda).

Two-point contact (``profile: profiles``, ``contact_points: 2``): the wheel's profile is cut into
a tread and a flange zone (:func:`ttbpipe.vehicle.profile_contact.zone_tables`); each zone has
its own table (``ContactGeometry.zones``, columns :data:`COL_G` .. :data:`COL_E` added: the
Hertz flexibility of the row, the contact's lateral distance from the wheelset centre and its
lateral position on the rail profile), its own penetration, normal force, creepages and creep
forces (:func:`_wheel_contact_points`).
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from ..jit import kernel
from .parameters import CREEP_LAWS, ContactParameters, check_creep_law

log = logging.getLogger(__name__)

# ---------------------------------------------------------------------------------------------
# Kalker coefficients, nu = 0.25, vs t: t = a/b for a/b <= 1, t = 2 - b/a for a/b > 1.
# ---------------------------------------------------------------------------------------------
_AB = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
_BA = np.array([0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1])
KALKER_T = np.concatenate([_AB, 2.0 - _BA])
KALKER_C11 = np.array([3.31, 3.37, 3.44, 3.53, 3.62, 3.72, 3.81, 3.91, 4.01, 4.12,
                       4.22, 4.36, 4.54, 4.78, 5.10, 5.57, 6.34, 7.78, 11.7])
KALKER_C22 = np.array([2.52, 2.63, 2.75, 2.88, 3.01, 3.14, 3.28, 3.41, 3.54, 3.67,
                       3.81, 3.99, 4.21, 4.50, 4.90, 5.48, 6.40, 8.14, 12.8])
KALKER_C23 = np.array([0.473, 0.603, 0.715, 0.823, 0.929, 1.03, 1.14, 1.25, 1.36, 1.47,
                       1.59, 1.75, 1.95, 2.23, 2.62, 3.24, 4.32, 6.63, 14.6])  # 1.25: typo fix
KALKER_C33 = np.array([8.28, 4.27, 2.96, 2.32, 1.93, 1.68, 1.50, 1.37, 1.27, 1.19,
                       1.11, 1.04, 0.965, 0.892, 0.819, 0.747, 0.674, 0.601, 0.526])


def kalker_coefficients(a_over_b: float) -> tuple[float, float, float, float]:
    """C11, C22, C23, C33 (nu = 0.25) at semi-axis ratio a/b (a along the rolling direction).

    Linear interpolation in t (t = a/b up to 1, 2 - b/a beyond), clamped to the tabulated range
    0.1 <= a/b <= 10 (an ellipse outside it is logged by the caller).
    """
    t = a_over_b if a_over_b <= 1.0 else 2.0 - 1.0 / a_over_b
    t = float(np.clip(t, KALKER_T[0], KALKER_T[-1]))
    return tuple(float(np.interp(t, KALKER_T, c)) for c in (KALKER_C11, KALKER_C22, KALKER_C23, KALKER_C33))


# ---------------------------------------------------------------------------------------------
# Hertz
# ---------------------------------------------------------------------------------------------
def hertz_g(wheel_radius: float, tread: str = "cone") -> float:
    """Hertz flexibility constant G (m/N^(2/3)) for a conical or worn (LM) tread (Zhai)."""
    if tread == "cone":
        return 4.57e-8 * wheel_radius ** -0.149
    if tread == "worn":
        return 3.86e-8 * wheel_radius ** -0.115
    raise ValueError(f"tread must be 'cone' or 'worn', got {tread!r}")


@kernel
def _hertz_force(penetration: float, g: float) -> float:
    """Hertz normal force (N) for a penetration (m); 0 when the wheel has left the rail."""
    if penetration <= 0.0:
        return 0.0
    ratio = penetration / g
    return ratio * np.sqrt(ratio)


@kernel(inline="always")
def _contact_ellipse(normal, poisson, youngs_modulus, curvature_sum, m, n):
    """Hertz contact ellipse at normal load N: (c, ab, (ab)^1.5), the semi-axes a = m c and
    b = n c with c = (3 N (1 - nu^2) / (2 E (A + B)))^(1/3) (Hertz; Johnson, Contact Mechanics,
    1985, section 4.2). The one home of the Kalker coefficients' load dependence, for the
    kernels and :func:`creep_coefficients`: a cube and a square root, not libm's ``pow``
    (which cost the reference case's step 3 %, docs/performance.md)."""
    c = np.cbrt(3.0 * normal * (1.0 - poisson * poisson) / (2.0 * youngs_modulus * curvature_sum))
    ab = m * n * c * c
    return c, ab, ab * np.sqrt(ab)


def hertz_stiffness(load: float, g: float) -> float:
    """Linearised Hertz stiffness dP/d(dZ) = 1.5 P^(1/3) / G (N/m) at normal load P (N)."""
    return 1.5 * load ** (1.0 / 3.0) / g


def hertz_ellipse_mn(curv_a: float, curv_b: float) -> tuple[float, float]:
    """Hertz coefficients (m_x, n_y) of the semi-axes along x (curvature A) and y (curvature B).

    Semi-axes are m_x c and n_y c with c = [3 N (1 - nu^2) / (2 E (A + B))]^(1/3). Johnson eqs.
    4.36-4.40; the elliptic integrals use scipy's parameter m = e^2.
    """
    if curv_a <= 0 or curv_b <= 0:
        raise ValueError(f"relative curvatures must be positive, got A={curv_a}, B={curv_b}")
    small, large = min(curv_a, curv_b), max(curv_a, curv_b)
    ratio = large / small
    if abs(ratio - 1.0) < 1e-10:
        return 1.0, 1.0

    def residual(e2: float) -> float:
        k, e = ellipk(e2), ellipe(e2)
        return (e / (1.0 - e2) - k) / (k - e) - ratio

    e2 = brentq(residual, 1e-12, 1.0 - 1e-14, xtol=1e-15, rtol=1e-14, maxiter=500)
    k, e = ellipk(e2), ellipe(e2)
    major = (2.0 * (k - e) * (small + large) / (np.pi * small * e2)) ** (1.0 / 3.0)
    minor = major * np.sqrt(1.0 - e2)
    # the major semi-axis lies along the direction of the smaller curvature
    return (major, minor) if curv_a <= curv_b else (minor, major)


# ---------------------------------------------------------------------------------------------
# Geometry tables
# ---------------------------------------------------------------------------------------------
# The column indices are numpy integers: a plain int module constant is a literal type to
# numba, which then compiles a separate copy of a kernel for each column it is called with
# (``_lerp2`` had 14 copies).
(COL_Y, COL_R, COL_DZ, COL_DELTA, COL_M, COL_N, COL_ABSUM, COL_C11, COL_C22, COL_C23,
 COL_C33) = (np.int64(k) for k in range(11))
N_COLS = 11


#: Two-point (zone) tables: the one-point columns, then the Hertz flexibility G of the row
#: (m/N^(2/3)), the contact point's lateral distance from the wheelset centre a (m, zero roll)
#: and from the rail's crown point e (m, track frame, towards the field side), the square of
#: the wheelset yaw of the row's layer (rad^2) and the lead of the point ahead of the axle (m,
#: track x, for positive yaw of the left wheel; odd in yaw).
COL_G, COL_A, COL_E, COL_YAW2, COL_LEAD = (np.int64(k) for k in range(11, 16))
N_ZCOLS = 16
#: Per-wheel results of both contact kernels (:func:`_wheel_contact`,
#: :func:`_wheel_contact_points`): F_x, F_y, F_z, M_spin, N, y_rel, penetration, then the
#: generalised moments of the wheel's contact forces about the wheelset centre (roll, spin,
#: yaw; N m) and the moment of its vertical forces about the rail's shear-centre line (N m,
#: about x; 0 for the one-point contact, which acts on that line).
N_POINT_OUT = 11
#: Columns of the two-point kernel's per-point scratch ``pts`` (:func:`_wheel_contact_points`).
N_PTS_COLS = 13
#: Conformal contact: a lateral relative curvature B below this fraction of the rolling-direction
#: curvature A (wheel hollow nearly as tight as the rail head, e.g. S1002's flange root on the
#: gauge corner of 60E1) is held at it, where Hertz's half-space assumption fails anyway.
CONFORMAL_CURVATURE_RATIO = 0.05
#: A zone whose gap is within this of the wheel's contact (m; about half the static elastic
#: approach) counts for the scalar Hertz flexibility of the step limits.
REACH_GAP_M = 5.0e-5


@dataclass
class ContactGeometry:
    """Left-wheel contact-geometry table on a uniform y_rel grid plus the scalar contact constants."""

    table: np.ndarray          # (n, 11), columns COL_*
    hertz_g: float
    shear_modulus: float
    youngs_modulus: float
    poisson: float
    friction: float
    wheel_radius: float
    contact_half_distance: float
    flange_clearance: float
    flange_stiffness: float
    rail_head_height: float
    description: str
    zones: np.ndarray | None = None   # (n_zones, n, N_ZCOLS): two-point contact (flange first)
    #                                   at zero yaw
    zone_layers: np.ndarray | None = None  # (n_zones, n_yaw, n, N_ZCOLS): the same over yaw
    #                                   layers from zero yaw (layer 0 = ``zones``)
    flange_cut: float | None = None   # wheel profile coordinate of the tread/flange cut (m)
    rail_cant: float = 0.0            # sin of the rail inclination (two-point: the shear centre
    #                                   lies rail_head_height sin(beta) field-side of the crown)
    creep_law: str = "kalker_she"     # CREEP_LAWS of ttbpipe.vehicle.parameters
    polach: tuple = (1.0, 1.0, 1.0, 0.0)  # Polach's kA, kS, A = mu_inf/mu0, B (s/m)

    def zone_array(self) -> np.ndarray:
        """The zone tables for the kernels, (n_zones, n_yaw, n, N_ZCOLS): the yaw layers, or the
        zero-yaw tables as one layer; (0, 1, 2, N_ZCOLS) when there are none (one point)."""
        if self.zone_layers is not None:
            return self.zone_layers
        if self.zones is None:
            return np.zeros((0, 1, 2, N_ZCOLS))
        return np.ascontiguousarray(self.zones[:, None])

    @property
    def y_grid(self) -> np.ndarray:
        return self.table[:, COL_Y]

    def scalars(self) -> np.ndarray:
        """Scalar constants packed for the kernels (order fixed by :data:`SCALAR_NAMES`)."""
        return np.array([self.hertz_g, self.shear_modulus, self.youngs_modulus, self.poisson,
                         self.friction, self.wheel_radius, self.contact_half_distance,
                         self.flange_clearance, self.flange_stiffness, self.rail_head_height,
                         self.rail_cant, float(CREEP_LAWS.index(self.creep_law)), *self.polach])


SCALAR_NAMES = ("hertz_g", "shear_modulus", "youngs_modulus", "poisson", "friction", "wheel_radius",
                "contact_half_distance", "flange_clearance", "flange_stiffness", "rail_head_height",
                "rail_cant", "creep_law", "polach_k_a", "polach_k_s", "polach_a", "polach_b_s_m")
#: Index of the creep law's code in :meth:`ContactGeometry.scalars` (0 Kalker +
#: Shen-Hedrick-Elkins, 1 Polach; :data:`ttbpipe.vehicle.parameters.CREEP_LAWS`), followed by
#: Polach's kA, kS, A and B.
SCAL_CREEP_LAW = 11


def hertz_constant(curv_a: float, curv_b: float, youngs_modulus: float, poisson: float) -> float:
    """Hertz flexibility G (m/N^(2/3)): normal approach delta = G N^(2/3) of two bodies of one
    material with relative curvatures A (rolling direction) and B (lateral).

    Johnson, Contact Mechanics (1985), eqs. 4.36-4.40: delta = 3 N K(e) / (2 pi a E*) with a the
    major semi-axis, e the eccentricity and 1/E* = 2 (1 - nu^2)/E; with a = m c_1 N^(1/3),
    c_1 = [3 (1 - nu^2) / (2 E (A + B))]^(1/3) (:func:`hertz_ellipse_mn`):
    G = 3 K(e) (1 - nu^2) / (pi E m c_1). Equal curvatures give delta = a^2 / R (eq. 4.23).
    """
    m, n = hertz_ellipse_mn(curv_a, curv_b)
    return _hertz_constant_mn(m, n, curv_a + curv_b, youngs_modulus, poisson)


def _hertz_constant_mn(m: float, n: float, curv_sum: float, youngs_modulus: float,
                       poisson: float) -> float:
    """:func:`hertz_constant` from the ellipse coefficients m, n and A + B."""
    major, minor = max(m, n), min(m, n)
    e2 = 1.0 - (minor / major) ** 2
    c1 = (3.0 * (1.0 - poisson ** 2) / (2.0 * youngs_modulus * curv_sum)) ** (1.0 / 3.0)
    return float(3.0 * ellipk(e2) * (1.0 - poisson ** 2) / (np.pi * youngs_modulus * major * c1))


def _fill_ellipse_and_kalker(table: np.ndarray, wheel_transverse_radius: np.ndarray,
                             rail_head_radius) -> None:
    """Columns m, n, A+B and C11..C33 from the rolling radius and the transverse radii
    (``rail_head_radius``: one value, or one per row)."""
    rail_radius = np.broadcast_to(np.asarray(rail_head_radius, dtype=float), table.shape[:1])
    for i in range(table.shape[0]):
        curv_a = 0.5 / table[i, COL_R]                           # wheel rolling, rail straight
        curv_b = 0.5 * (1.0 / rail_radius[i] + 1.0 / wheel_transverse_radius[i])
        if curv_b <= 0:
            raise ValueError(f"contact table row {i}: non-positive lateral curvature sum {curv_b}"
                             " (wheel hollow tighter than the rail head: conformal contact)")
        m, n = hertz_ellipse_mn(curv_a, curv_b)
        table[i, COL_M], table[i, COL_N], table[i, COL_ABSUM] = m, n, curv_a + curv_b
        table[i, COL_C11:COL_C33 + 1] = kalker_coefficients(m / n)


def conical_geometry(p: ContactParameters, half_range: float = 0.03, n: int = 61) -> ContactGeometry:
    """Geometry table of a conical tread with conicity lambda on a rail head of radius R_r."""
    table = _conical_table(float(p.wheel_radius), float(p.conicity),
                           float(p.wheel_transverse_radius), float(p.rail_head_radius),
                           float(half_range), int(n)).copy()
    tread = "cone" if p.hertz_law in ("auto", "cone") else "worn"
    return _geometry(table, p, tread, f"conical tread, conicity {p.conicity}")


@functools.lru_cache(maxsize=16)
def _conical_table(wheel_radius: float, conicity: float, wheel_transverse_radius: float,
                   rail_head_radius: float, half_range: float, n: int) -> np.ndarray:
    # filled once per process and geometry (every sample of a study builds the same cone;
    # the Hertz ellipse and Kalker coefficients take a root search per row)
    y = np.linspace(-half_range, half_range, n)
    table = np.zeros((n, N_COLS))
    table[:, COL_Y] = y
    table[:, COL_R] = wheel_radius + conicity * y
    table[:, COL_DZ] = conicity * y
    table[:, COL_DELTA] = np.arctan(conicity)
    _fill_ellipse_and_kalker(table, np.full(n, wheel_transverse_radius), rail_head_radius)
    return table


def demo_worn_table(p: ContactParameters, half_range: float = 0.03, n: int = 121,
                    hollow_radius: float = 0.50, nominal_angle: float = 1.0 / 40.0) -> np.ndarray:
    """Demonstration geometry of a worn (hollow) tread on a crowned rail head, by exact circles.

    Not a measured profile pair: the wheel tread is a concave circular arc of radius
    R_w = ``hollow_radius`` (a worn, hollow tread) and the rail head a convex arc of radius
    R_r = ``p.rail_head_radius``; at y_rel = 0 they touch with contact angle ``nominal_angle``
    (1:40 rail cant). Two arcs in internal tangency touch on the line through both centres
    (distance D = R_w - R_r), so for a lateral shift y of the wheel

        sin delta = sin delta0 + y / D,
        rolling radius r = r0 + R_w (cos delta0 - cos delta)   (contact point moves on the tread),
        gap change dz = D (cos delta0 - cos delta)              (= dr minus the drop on the crown).

    The equivalent conicity is about delta0 R_w / D = 0.0625 for the defaults, that of a
    moderately worn wheel (EN 15302 range for worn wheels 0.05-0.4 [M]). Returns the columns
    y, r, dz, delta, wheel transverse radius (negative: concave).
    """
    rw, rr, r0 = hollow_radius, p.rail_head_radius, p.wheel_radius
    if rw <= rr:
        raise ValueError("hollow_radius must exceed the rail head radius (non-conformal contact)")
    y = np.linspace(-half_range, half_range, n)
    d = rw - rr
    sin_d = np.sin(nominal_angle) + y / d
    if np.any(np.abs(sin_d) >= 1):
        raise ValueError("demo table range too wide for the chosen radii")
    delta = np.arcsin(sin_d)
    r = r0 + rw * (np.cos(nominal_angle) - np.cos(delta))
    dz = d * (np.cos(nominal_angle) - np.cos(delta))
    return np.column_stack([y, r, dz, delta, np.full(n, -rw)])


def table_geometry(p: ContactParameters) -> ContactGeometry:
    """Geometry from a tabulated profile pair (CSV/Parquet) or the demonstration worn table.

    File columns: ``y_rel_m``, ``rolling_radius_m``, ``gap_change_m``, ``contact_angle_rad``,
    ``wheel_transverse_radius_m`` (negative for a concave tread), for the LEFT wheel, on a uniform
    increasing grid.
    """
    if p.profile_table:
        import pandas as pd
        path = Path(p.profile_table)
        df = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
        cols = ["y_rel_m", "rolling_radius_m", "gap_change_m", "contact_angle_rad",
                "wheel_transverse_radius_m"]
        missing = [c for c in cols if c not in df.columns]
        if missing:
            raise ValueError(f"{path}: missing column(s) {missing}")
        raw = df[cols].to_numpy(float)
        bad = np.argwhere(~np.isfinite(raw))
        if bad.size:
            raise ValueError(f"{path}: non-finite value at row {bad[0, 0]}, column {cols[bad[0, 1]]}")
        steps = np.diff(raw[:, 0])
        if np.any(steps <= 0) or np.ptp(steps) > 1e-9 * max(1.0, abs(steps.mean())) + 1e-12:
            raise ValueError(f"{path}: column y_rel_m must be uniform and increasing")
        desc = f"profile table {path}"
    else:
        raw = demo_worn_table(p)
        desc = "demonstration worn-tread table (hollow arc R 0.5 m on rail head R 0.3 m)"
    n = raw.shape[0]
    table = np.zeros((n, N_COLS))
    table[:, COL_Y], table[:, COL_R], table[:, COL_DZ], table[:, COL_DELTA] = raw[:, 0], raw[:, 1], raw[:, 2], raw[:, 3]
    _fill_ellipse_and_kalker(table, raw[:, 4], p.rail_head_radius)
    tread = "worn" if p.hertz_law in ("auto", "worn") else "cone"
    return _geometry(table, p, tread, desc)


def _geometry(table: np.ndarray, p: ContactParameters, tread: str, desc: str) -> ContactGeometry:
    return ContactGeometry(
        table=np.ascontiguousarray(table), hertz_g=hertz_g(p.wheel_radius, tread),
        shear_modulus=p.youngs_modulus / (2.0 * (1.0 + p.poisson)), youngs_modulus=p.youngs_modulus,
        poisson=p.poisson, friction=p.friction, wheel_radius=p.wheel_radius,
        contact_half_distance=p.contact_half_distance, flange_clearance=p.flange_clearance,
        flange_stiffness=p.flange_stiffness, rail_head_height=p.rail_head_height,
        **_creep_law_fields(p, desc))


def _creep_law_fields(p: ContactParameters, description: str) -> dict:
    """The creep law of ``p`` as :class:`ContactGeometry` fields (checked); a law other than the
    default is named in the description (run summaries carry it)."""
    check_creep_law(p)
    polach = (float(p.polach_k_a), float(p.polach_k_s), float(p.polach_a), float(p.polach_b_s_m))
    if p.creep_law != "kalker_she":
        description += (f"; creep law {p.creep_law} (kA {polach[0]:g}, kS {polach[1]:g}, "
                        f"A {polach[2]:g}, B {polach[3]:g} s/m)")
    return {"creep_law": p.creep_law, "polach": polach, "description": description}


def profiles_geometry(p: ContactParameters) -> ContactGeometry:
    """One-point geometry from a real wheel and rail profile pair
    (:mod:`ttbpipe.vehicle.profile_contact`): the flange is part of the table, so the flange
    spring is off; the worn-tread Hertz law (two-point contact: :func:`zone_geometry`)."""
    import dataclasses

    from .profile_contact import profile_table

    raw, pair = profile_table(p)
    n = raw.shape[0]
    table = np.zeros((n, N_COLS))
    table[:, COL_Y], table[:, COL_R], table[:, COL_DZ], table[:, COL_DELTA] = raw[:, :4].T
    _fill_ellipse_and_kalker(table, raw[:, 4], raw[:, 5])
    tread = "worn" if p.hertz_law in ("auto", "worn") else "cone"
    desc = (f"profiles {p.wheel_profile} on {p.rail_profile} at {p.rail_inclination}, gauge "
            f"{1e3 * p.gauge_m:g} mm, flange back {1e3 * p.flange_back_m:g} mm")
    return _geometry(table, dataclasses.replace(p, flange_stiffness=0.0), tread, desc)


def zone_geometry(p: ContactParameters, one: ContactGeometry | None = None) -> ContactGeometry:
    """Two-point contact geometry of a profile pair: the one-point geometry of
    :func:`profiles_geometry` (its table serves the step limits, the linearised vehicle and the
    conicity) with the tread and flange zone tables (:func:`ttbpipe.vehicle.profile_contact.zone_tables`)
    over ``yaw_layers`` layers of wheelset yaw, uniform from 0 to ``yaw_max_rad`` (the contact
    on the wheel's trace line; the kernel interpolates linearly in yaw^2 between layers, exact
    for the leading quadratic dependence of the even quantities, and holds the last layer
    beyond it). Measured on S1002/60E1 (tests/test_contact_yaw.py): with 5 mrad between layers
    the contact's gap change is interpolated to 0.4 um at 7 mrad and 4 um at 27 mrad, against
    a yaw effect of 40 and 600 um in flange contact; layers uniform in yaw^2 (0, 18, 25 ...
    mrad) missed by 3.5 um at 7 mrad, the flange's gap change not being quadratic in yaw there.

    Per zone row: Hertz ellipse and Kalker coefficients from the relative curvatures
    A = 1/(2 R_x), R_x = r / cos(delta_w) the wheel's rolling-direction principal radius (the
    rail is straight), B = (1/R_wheel + 1/R_rail)/2 (conformal rows held at
    :data:`CONFORMAL_CURVATURE_RATIO` A); the Hertz flexibility G from those curvatures
    (:func:`hertz_constant`; ``hertz_law`` auto or hertz) or Zhai's law of the tread (worn, cone).
    The scalar ``hertz_g`` (static start and step limits) becomes the smallest G of a zero-yaw
    row whose zone lies within :data:`REACH_GAP_M` of the contact (the stiffest contact the
    wheel meets with a substantial share of its load).
    """
    import dataclasses

    from .contact_geometry import parse_inclination
    from .profile_contact import profile_pair, zone_tables

    if p.hertz_law not in ("auto", "hertz", "worn", "cone"):
        raise ValueError(f"train.contact.hertz_law: {p.hertz_law!r}; expected auto | hertz | worn | cone")
    n_yaw = int(p.yaw_layers)
    if n_yaw < 1 or (n_yaw > 1 and not 0.0 < float(p.yaw_max_rad) <= 0.1):
        raise ValueError(f"train.contact.yaw_layers, yaw_max_rad: {p.yaw_layers}, {p.yaw_max_rad}; "
                         "expected at least one layer and a largest yaw in (0, 0.1] rad")
    one = profiles_geometry(p) if one is None else one
    pair = profile_pair(p)
    raw, cut, _ = zone_tables(p, pair=pair)
    yaws = float(p.yaw_max_rad) * np.arange(n_yaw) / max(n_yaw - 1, 1)
    curvature_law = p.hertz_law in ("auto", "hertz")
    zhai = hertz_g(p.wheel_radius, "cone" if p.hertz_law == "cone" else "worn")
    layers = []
    for j, yaw in enumerate(yaws):
        layer_raw = raw if j == 0 else zone_tables(p, pair=pair, yaw=float(yaw), split=cut)[0]
        layer, reach, held = _zone_layer(layer_raw, p, curvature_law, zhai, float(yaw))
        if j == 0:
            zones, reach0, held0 = layer, reach, held
        layers.append(layer)
    if held0:
        log.info("two-point contact: %d table rows near contact are conformal (B < %.2g A) and "
                 "held at that ratio", held0, CONFORMAL_CURVATURE_RATIO)
    g_min = float(zones[:, :, COL_G][reach0].min())
    law = "Hertz from the curvatures" if curvature_law else f"Zhai's {p.hertz_law} law"
    where = ("no tread-flange jump: one zone" if cut is None
             else f"tread and flange cut at {1e3 * cut:.2f} mm on the wheel")
    yaw_text = (f"{n_yaw} yaw layers to {1e3 * yaws[-1]:g} mrad" if n_yaw > 1
                else "contact at zero yaw")
    return dataclasses.replace(one, zones=np.ascontiguousarray(zones),
                               zone_layers=np.ascontiguousarray(np.stack(layers, axis=1)),
                               flange_cut=cut, hertz_g=g_min,
                               rail_cant=float(np.sin(np.arctan(parse_inclination(p.rail_inclination)))),
                               description=f"{one.description}; two-point contact ({where}; {law}; "
                                           f"{yaw_text})")


def _zone_layer(raw: np.ndarray, p: ContactParameters, curvature_law: bool, zhai: float,
                yaw: float) -> tuple[np.ndarray, np.ndarray, int]:
    """One yaw layer of the kernels' zone tables from :func:`zone_tables`' columns: (tables
    (n_zones, n, N_ZCOLS), the rows within :data:`REACH_GAP_M` of the contact, how many of
    those were held conformal)."""
    n_z, n, _ = raw.shape
    zones = np.zeros((n_z, n, N_ZCOLS))
    held = 0
    reach = raw[:, :, 2] >= raw[:, :, 2].max(axis=0) - REACH_GAP_M
    for k in range(n_z):
        zones[k, :, COL_Y] = raw[k, :, 0]
        zones[k, :, COL_R] = raw[k, :, 1]
        zones[k, :, COL_DZ] = raw[k, :, 2]
        zones[k, :, COL_DELTA] = raw[k, :, 3]
        zones[k, :, COL_A] = raw[k, :, 6]
        zones[k, :, COL_E] = raw[k, :, 7]
        zones[k, :, COL_YAW2] = yaw * yaw
        zones[k, :, COL_LEAD] = raw[k, :, 9]
        for i in range(n):
            curv_a = 0.5 / raw[k, i, 8]
            curv_b = 0.5 * (1.0 / raw[k, i, 5] + 1.0 / raw[k, i, 4])
            if curv_b < CONFORMAL_CURVATURE_RATIO * curv_a:
                curv_b = CONFORMAL_CURVATURE_RATIO * curv_a
                held += int(reach[k, i])
            m, n_ = hertz_ellipse_mn(curv_a, curv_b)
            zones[k, i, COL_M], zones[k, i, COL_N], zones[k, i, COL_ABSUM] = m, n_, curv_a + curv_b
            zones[k, i, COL_C11:COL_C33 + 1] = kalker_coefficients(m / n_)
            zones[k, i, COL_G] = (_hertz_constant_mn(m, n_, curv_a + curv_b, p.youngs_modulus,
                                                     p.poisson) if curvature_law else zhai)
    return zones, reach, held


#: Profile-pair geometries built in this process, by their parameters (a study builds the same
#: pair for every sample; the geometry's arrays are not modified after building).
_PROFILE_GEOMETRIES: dict[str, ContactGeometry] = {}


def _file_stamp(name: str) -> str:
    """Size and modification time of a profile given as a file (a changed file is rebuilt)."""
    path = Path(str(name))
    if path.is_file():
        st = path.stat()
        return f"|{st.st_size}:{st.st_mtime_ns}"
    return ""


def build_geometry(p: ContactParameters) -> ContactGeometry:
    """Contact geometry for the configured profile (conical, table or profiles; profiles with
    ``contact_points`` 2 adds the tread and flange zone tables) with the configured creep law.
    A profile pair is built once per process and set of geometric parameters."""
    if p.hertz_law == "hertz" and p.profile != "profiles":
        raise ValueError("train.contact.hertz_law: hertz needs profile: profiles")
    if p.profile == "conical":
        return conical_geometry(p)
    if p.profile == "profiles":
        points = int(p.contact_points)
        if points not in (1, 2):
            raise ValueError(f"train.contact.contact_points: {p.contact_points!r}; expected 1 or 2")
        if points == 1 and p.hertz_law == "hertz":
            raise ValueError("train.contact.hertz_law: hertz needs contact_points: 2")
        import dataclasses

        shape = dataclasses.replace(p, **{f.name: f.default for f in dataclasses.fields(p)
                                          if f.name == "creep_law" or f.name.startswith("polach_")})
        key = repr(shape) + "".join(_file_stamp(name) for name in (p.wheel_profile, p.rail_profile))
        if key not in _PROFILE_GEOMETRIES:
            _PROFILE_GEOMETRIES[key] = zone_geometry(shape) if points == 2 else profiles_geometry(shape)
        geom = _PROFILE_GEOMETRIES[key]
        return dataclasses.replace(geom, **_creep_law_fields(p, geom.description))
    return table_geometry(p)


def creep_coefficients(geom: "ContactGeometry", load: float,
                       row: np.ndarray | None = None) -> tuple[float, float, float, float]:
    """Kalker coefficients f11, f22, f23, f33 at normal load ``load`` (N) on table row ``row``
    (default: the centre row, y_rel = 0), as :func:`_wheel_contact` computes them."""
    tab = geom.table[geom.table.shape[0] // 2] if row is None else row
    _, ab, ab_15 = _contact_ellipse(float(load), geom.poisson, geom.youngs_modulus,
                                    float(tab[COL_ABSUM]), float(tab[COL_M]), float(tab[COL_N]))
    g = geom.shear_modulus
    return g * ab * tab[COL_C11], g * ab * tab[COL_C22], g * ab_15 * tab[COL_C23], \
        g * ab * ab * tab[COL_C33]


def equivalent_conicity(geom: ContactGeometry, amplitude: float = 0.003) -> float:
    """(r_L - r_R) / (2 y) at y = amplitude, the quasi-linear equivalent conicity (simplified EN 15302)."""
    y, r = geom.table[:, COL_Y], geom.table[:, COL_R]
    return float((np.interp(amplitude, y, r) - np.interp(-amplitude, y, r)) / (2 * amplitude))


# ---------------------------------------------------------------------------------------------
# Kernels
# ---------------------------------------------------------------------------------------------
@kernel
def _she_factor(creep_x: float, creep_y: float, friction: float, normal: float) -> float:
    """Shen-Hedrick-Elkins scale factor F'/F for the linear creep force (F_x, F_y)."""
    total = np.sqrt(creep_x * creep_x + creep_y * creep_y)
    limit = friction * normal
    if total <= 0.0 or limit <= 0.0:
        return 0.0 if limit <= 0.0 else 1.0
    beta = total / limit
    if beta <= 3.0:
        return limit * (beta - beta * beta / 3.0 + beta * beta * beta / 27.0) / total
    return limit / total


@kernel
def _point_creepages(side, radius, a, cos_d, sin_d, r0, speed, ws_vyaw, ws_vpitch):
    """Longitudinal and spin creepage of a contact point at rolling radius ``radius`` and lateral
    distance ``a`` from the wheelset centre with contact angle delta (cos, sin):
    xi_x = -(r - r0)/r0 - s a yaw'/V - r pitch'/V, xi_sp = yaw' cos(delta)/V - s sin(delta)/r0
    (spin in rad/m; module docstring)."""
    xi_x = -(radius - r0) / r0 - side * a * ws_vyaw / speed - radius * ws_vpitch / speed
    xi_sp = ws_vyaw * cos_d / speed - side * sin_d / r0
    return xi_x, xi_sp


@kernel
def _point_creep_forces(side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22, f23, f33, r0, mu,
                        speed, ws_vyaw, ws_vpitch):
    """Creep forces (F_x, F_y in the contact plane, spin moment M_z) of one contact point with
    normal force ``normal`` > 0, rolling radius ``radius`` at lateral distance ``a`` from the
    wheelset centre, contact angle delta (cos, sin) and the lateral creepage ``xi_y`` (after the
    semi-implicit relaxation, if any): the creepages xi_x, xi_sp of :func:`_point_creepages`,
    Kalker's linear law F_x = -f11 xi_x, F_y = -f22 xi_y - f23 xi_sp, M_z = f23 xi_y - f33 xi_sp,
    scaled by Shen-Hedrick-Elkins (:func:`_she_factor`). Creep law ``kalker_she`` of the
    one-point and the two-point kernels (module docstring for the sources)."""
    xi_x, xi_sp = _point_creepages(side, radius, a, cos_d, sin_d, r0, speed, ws_vyaw, ws_vpitch)
    tx, ty, tm = _kalker_linear(xi_x, xi_y, xi_sp, f11, f22, f23, f33)
    k = _she_factor(tx, ty, mu, normal)
    return k * tx, k * ty, k * tm


@kernel
def _kalker_linear(xi_x, xi_y, xi_sp, f11, f22, f23, f33):
    """Kalker's linear creep forces F_x = -f11 xi_x, F_y = -f22 xi_y - f23 xi_sp and spin moment
    M_z = f23 xi_y - f33 xi_sp (module docstring)."""
    return -f11 * xi_x, -f22 * xi_y - f23 * xi_sp, f23 * xi_y - f33 * xi_sp


@kernel(creates_arrays=False)
def _creep_forces(scal, side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22, f23, f33, r0,
                  mu, speed, ws_vyaw, ws_vpitch, semi_a, semi_b):
    """F_x, F_y, M_z of one contact point by the creep law ``scal[SCAL_CREEP_LAW]`` (0
    Kalker + Shen-Hedrick-Elkins, :func:`_point_creep_forces`; 1 Polach,
    :func:`_polach_creep_forces`, which also needs the ellipse's semi-axes): the one dispatch
    of the one-point and the two-point kernels."""
    if scal[SCAL_CREEP_LAW] == 0.0:
        return _point_creep_forces(side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22, f23,
                                   f33, r0, mu, speed, ws_vyaw, ws_vpitch)
    return _polach_creep_forces(side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22, f23, f33,
                                r0, mu, speed, ws_vyaw, ws_vpitch, semi_a, semi_b,
                                scal[SCAL_CREEP_LAW + 1:SCAL_CREEP_LAW + 5])


@kernel
def _polach_spin_factor(eps_m):
    """Polach's spin function (O. Polach, Vehicle System Dynamics 33 Suppl. (1999) 728-739):
    K_M = |eps_M| (delta^3/3 - delta^2/2 + 1/6) - sqrt((1 - delta^2)^3)/3 with
    delta = (eps_M^2 - 1)/(eps_M^2 + 1), the normalised boundary of the area of adhesion.
    Evaluated with u = 1 - delta = 2/(eps_M^2 + 1), for which the bracket is exactly
    u^2/2 - u^3/3 and 1 - delta^2 = u (2 - u) (no cancellation as delta -> 1). K_M <= 0;
    K_M -> -2/3 |eps_M| for small eps_M (Kalker's linear spin term) and -2/(3 eps_M^3) for large
    ones: the spin acts on the lateral force through the area of adhesion only, so the lateral
    force of pure spin vanishes at full slip."""
    e = abs(eps_m)
    u = 2.0 / (e * e + 1.0)
    w = u * (2.0 - u)
    return e * u * u * (0.5 - u / 3.0) - w * np.sqrt(w) / 3.0


@kernel
def _polach_forces(normal, xi_x, xi_y, xi_sp, f11, f22, f23, semi_a, semi_b, mu0, speed,
                   k_a, k_s, fall_a, fall_b):
    """Polach's creep forces (F_x, F_y; Kalker's sign: against the creepage) and the friction
    coefficient used, of one contact with normal force ``normal``, creepages xi_x, xi_y, spin
    xi_sp (rad/m), Kalker's f11 = G a b C11, f22 = G a b C22, f23 = G (ab)^1.5 C23 and the
    ellipse's semi-axes a (rolling direction), b.

    Sources: O. Polach, "A fast wheel-rail forces calculation computer code", Vehicle System
    Dynamics 33 Suppl. (1999) 728-739 [P99]; O. Polach, "Creep forces in simulations of traction
    vehicles running on adhesion limit", Wear 258 (2005) 992-1000 [P05].

    * Equivalent creepage with spin [P99]: s_yC = xi_y + xi_sp a if |xi_y + xi_sp a| > |xi_y|,
      else xi_y; s_C = sqrt(xi_x^2 + s_yC^2).
    * Friction falling with the slip velocity w = s_C V [P05]: mu = mu0 [(1 - A) exp(-B w) + A].
    * Tangential force of the translational creepages [P99; reduction factors kA, kS P05]:
      F = (2 Q mu / pi) [kA eps/(1 + (kA eps)^2) + arctan(kS eps)],
      eps = (2/3) C pi a^2 b s_C / (Q mu) = pi G a b c_jj s_C / (4 Q mu),
      c_jj = sqrt((C11 xi_x/s)^2 + (C22 xi_y/s)^2), s = sqrt(xi_x^2 + xi_y^2); written here with
      G a b c_jj s = sqrt((f11 xi_x)^2 + (f22 xi_y)^2); F_x = -F xi_x/s_C, F_y = -F xi_y/s_C.
    * Lateral force of the spin [P99]: F_yS = (9/16) a Q mu K_M k_M xi_sp / s_C (Kalker's sign;
      K_M <= 0, :func:`_polach_spin_factor`), k_M = 1 + 6.3 (1 - exp(-a/b)),
      eps_M = (8/3) G b sqrt(ab) C23 |s_yC| / (Q mu k_M) = (8/3) f23 |s_yC| / (a Q mu k_M).

    With kA = kS = 1 and the creepages -> 0 this tends to Kalker's linear law (F_x = -f11 xi_x,
    F_y = -f22 xi_y - f23 xi_sp; exactly when xi_x = 0 or xi_y = 0, otherwise the force lies
    along the creepage with Kalker's magnitude); the translational force is at most mu Q
    (kS <= kA: x/(1 + x^2) + arctan(r x), r <= 1, stays below pi/2). kA, kS < 1 lower its
    initial slope to (kA + kS)/2 of Kalker's; the spin term is [P99]'s, not reduced."""
    s_yc = xi_y
    if abs(xi_y + xi_sp * semi_a) > abs(xi_y):
        s_yc = xi_y + xi_sp * semi_a
    s_c = np.sqrt(xi_x * xi_x + s_yc * s_yc)
    mu = mu0 * ((1.0 - fall_a) * np.exp(-fall_b * s_c * speed) + fall_a)
    limit = mu * normal
    if s_c <= 0.0 or limit <= 0.0:
        return 0.0, 0.0, mu
    eps = 0.25 * np.pi * np.sqrt((f11 * xi_x) ** 2 + (f22 * xi_y) ** 2) / limit
    if xi_x != 0.0 or xi_y != 0.0:
        eps *= s_c / np.sqrt(xi_x * xi_x + xi_y * xi_y)
    ka_eps = k_a * eps
    force = 2.0 * limit / np.pi * (ka_eps / (1.0 + ka_eps * ka_eps) + np.arctan(k_s * eps))
    fx = -force * xi_x / s_c
    fy = -force * xi_y / s_c
    if xi_sp != 0.0:
        k_m = 1.0 + 6.3 * (1.0 - np.exp(-semi_a / semi_b))
        eps_m = 8.0 * f23 * abs(s_yc) / (3.0 * semi_a * limit * k_m)
        fy += 0.5625 * semi_a * limit * _polach_spin_factor(eps_m) * k_m * xi_sp / s_c
    return fx, fy, mu


@kernel
def _polach_creep_forces(side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22, f23, f33, r0,
                         mu, speed, ws_vyaw, ws_vpitch, semi_a, semi_b, polach):
    """Creep law ``polach``: :func:`_point_creep_forces`'s arguments (the point's kinematics, its
    normal force and Kalker coefficients) plus the ellipse's semi-axes ``semi_a`` (rolling
    direction) and ``semi_b`` and ``polach`` = (kA, kS, A, B) -> F_x, F_y, M_z. The forces are
    Polach's (:func:`_polach_forces`). Polach's method gives no spin moment: M_z is Kalker's
    linear f23 xi_y - f33 xi_sp scaled by the ratio of Polach's tangential force to Kalker's
    linear one, |F| / |F_lin| (as Shen-Hedrick-Elkins scales all three by one factor)."""
    xi_x, xi_sp = _point_creepages(side, radius, a, cos_d, sin_d, r0, speed, ws_vyaw, ws_vpitch)
    fx, fy, _ = _polach_forces(normal, xi_x, xi_y, xi_sp, f11, f22, f23, semi_a, semi_b, mu,
                               speed, polach[0], polach[1], polach[2], polach[3])
    tx, ty, tm = _kalker_linear(xi_x, xi_y, xi_sp, f11, f22, f23, f33)
    lin = np.sqrt(tx * tx + ty * ty)
    if lin > 0.0:
        tm *= np.sqrt(fx * fx + fy * fy) / lin
    return fx, fy, tm


@kernel
def _grid_cell(y0: float, y1: float, n: int, y: float):
    """(i, w) of y on the uniform grid y0, y1, ... of n points: the cell [i, i + 1] and the
    weight w of point i + 1 (w < 0 before the first point, w > 1 after the last: linear
    extrapolation from the end cells)."""
    s = (y - y0) / (y1 - y0)
    if s < 0.0:
        return 0, s
    if s >= n - 1:
        return n - 2, s - (n - 2)
    i = int(s)
    return i, s - i


@kernel(creates_arrays=False)
def _table_row(table: np.ndarray, y_rel: float, out: np.ndarray) -> None:
    """Linear interpolation of all table columns at y_rel (uniform grid; linear extrapolation
    of r and dz beyond the ends, other columns held)."""
    n = table.shape[0]
    i, w = _grid_cell(table[0, 0], table[1, 0], n, y_rel)
    for c in range(table.shape[1]):
        out[c] = table[i, c] * (1.0 - w) + table[i + 1, c] * w
    if w < 0.0 or w > 1.0:  # hold the non-geometric columns at the end values
        j = 0 if w < 0.0 else n - 1
        for c in range(COL_DELTA, table.shape[1]):
            out[c] = table[j, c]


@kernel(creates_arrays=False)
def _wheel_contact(side: float, table: np.ndarray, scal: np.ndarray, speed: float,
                   wheelset, rail, row: np.ndarray, out: np.ndarray, creep_y_prev: float = 0.0,
                   creep_relax: float = 0.0) -> float:
    """Contact forces on one wheel (side +1 left, -1 right) in track axes.

    ``wheelset`` = (y, z, roll, yaw, dy/dt, dz/dt, droll/dt, dpitch/dt (spin), dyaw/dt) of the
    wheelset; ``rail`` = (z, y, dz/dt, dy/dt) of the rail head at the contact (structure plus
    irregularity). Writes ``out`` (:data:`N_POINT_OUT`, as :func:`_wheel_contact_points`):
    [F_x, F_y, F_z, M_spin_z, N, y_rel, penetration] where F is the force of the rail on the
    wheel (contact + flange) and M_spin_z the spin moment about the contact normal, then the
    generalised moments about the wheelset centre of the force at (0, s a0, -r): roll
    s a0 F_z + r F_y, spin -r F_x, yaw -s a0 F_x + M_spin_z cos d, and 0 (the point lies on the
    rail's centre line: no moment about it). Kinematics (small angles): penetration
    dZ = z_rail - (z_w + s a0 roll_w) + dz(y_rel); creepages
    xi_x = -(r - r0)/r0 - s a0 yaw'/V - r pitch'/V,
    xi_y = [(y_w' + r roll_w' - V yaw_w - y_rail') cos d + s (z_w' + s a0 roll_w' - z_rail') sin d]/V,
    xi_sp = yaw_w' cos d / V - s sin d / r0.

    Semi-implicit lateral creepage (``creep_relax`` > 0, the coupled loop; docs/performance.md):
    the lateral creep force is a stiff damper c = f22/V between the wheel and the light rail head
    (explicit Zhai limit c dt m_eff^-1 ~ 1). The creepage used is
    xi_y* = (xi_y + g xi_y*_prev) / (1 + g), g = f22 ``creep_relax`` = (f22/V) m_eff^-1 dt,
    the backward-Euler estimate of the relative velocity after the step's own creep impulse,
    taken as an increment on the previous step's value so that a steady creepage (yaw angle,
    constant slip) gives exactly the Kalker force. Unconditionally stable for the damper; g -> 0
    recovers the explicit law. Returns xi_y* (the raw xi_y when there is no contact), the state
    for the next step. ``creep_relax`` = 0 (default: statics, tests) is the explicit law.
    """
    g_hertz, g_shear, e_mod, nu, mu, r0, a0, flange_gap, flange_k = (
        scal[0], scal[1], scal[2], scal[3], scal[4], scal[5], scal[6], scal[7], scal[8])
    ws_y, ws_z, ws_roll, ws_yaw, ws_vy, ws_vz, ws_vroll, ws_vpitch, ws_vyaw = wheelset
    rail_z, rail_y, rail_vz, rail_vy = rail
    y_rel = ws_y - rail_y
    _table_row(table, side * y_rel, row)
    radius, dz, delta = row[1], row[2], row[3]
    cos_d, sin_d = np.cos(delta), np.sin(delta)
    penetration = rail_z - (ws_z + side * a0 * ws_roll) + dz
    normal = _hertz_force(penetration * cos_d, g_hertz)
    fx = 0.0
    fy = 0.0
    mz = 0.0
    v_lat = ws_vy + radius * ws_vroll - speed * ws_yaw - rail_vy
    v_ver = ws_vz + side * a0 * ws_vroll - rail_vz
    xi_y = (v_lat * cos_d + side * v_ver * sin_d) / speed
    xi_y_state = xi_y
    if normal > 0.0:
        c, ab, ab_15 = _contact_ellipse(normal, nu, e_mod, row[6], row[4], row[5])
        f11 = g_shear * ab * row[7]
        f22 = g_shear * ab * row[8]
        f23 = g_shear * ab_15 * row[9]
        f33 = g_shear * ab * ab * row[10]
        if creep_relax > 0.0:
            g = f22 * creep_relax
            xi_y = (xi_y + g * creep_y_prev) / (1.0 + g)
            xi_y_state = xi_y
        fx, fy, mz = _creep_forces(scal, side, normal, radius, a0, cos_d, sin_d, xi_y, f11, f22,
                                   f23, f33, r0, mu, speed, ws_vyaw, ws_vpitch, row[4] * c,
                                   row[5] * c)
    force_y = -side * normal * sin_d + fy * cos_d
    force_z = normal * cos_d + side * fy * sin_d
    # flange: stiff lateral spring beyond the clearance (left flange touches when y_rel > gap)
    flange_pen = side * y_rel - flange_gap
    if flange_pen > 0.0:
        force_y -= side * flange_k * flange_pen
    out[0] = fx
    out[1] = force_y
    out[2] = force_z
    out[3] = mz
    out[4] = normal
    out[5] = y_rel
    out[6] = penetration
    out[7] = side * a0 * force_z + radius * force_y
    out[8] = -radius * fx
    out[9] = -side * a0 * fx + mz * cos_d
    out[10] = 0.0
    return xi_y_state


@kernel(creates_arrays=False)
def _lerp2(zk: np.ndarray, j: int, j1: int, wy: float, i: int, w: float, c: int) -> float:
    """Column ``c`` of one zone's tables (n_yaw, n, N_ZCOLS) at weight ``w`` between rows i and
    i + 1 and weight ``wy`` between yaw layers j and j1 (bilinear)."""
    lo = zk[j, i, c] * (1.0 - w) + zk[j, i + 1, c] * w
    if wy == 0.0:
        return lo
    return lo * (1.0 - wy) + (zk[j1, i, c] * (1.0 - w) + zk[j1, i + 1, c] * w) * wy


@kernel(creates_arrays=False)
def _wheel_contact_points(side: float, zones: np.ndarray, scal: np.ndarray, speed: float,
                          wheelset, rail, pts: np.ndarray, out: np.ndarray,
                          creep_prev: np.ndarray, creep_relax: float) -> None:
    """Two-point contact of one wheel (side +1 left, -1 right): every zone of ``zones`` (tread,
    flange; :class:`ContactGeometry`) is a contact point with its own penetration, Hertz normal
    force, creepages and Kalker + Shen-Hedrick-Elkins creep forces, as :func:`_wheel_contact`
    computes them for its one point, but at the point's own lateral distance a from the
    wheelset centre (table column :data:`COL_A`) and with the row's own Hertz flexibility G:

    dZ_k = z_rail + s l_k theta_rail - (z_w + s a_k roll_w) + dz_k(y_rel),
    N_k = (dZ_k cos(delta_k) / G_k)^1.5,
    xi_x = -(r_k - r0)/r0 - s a_k yaw'/V - r_k pitch'/V,
    xi_y = [(y_w' + r_k roll_w' - V yaw_w - y_rail') cos d_k
            + s (z_w' + s a_k roll_w' - z_rail' - s l_k theta_rail') sin d_k]/V,
    xi_sp = yaw_w' cos d_k / V - s sin d_k / r0,

    (plus yaw_w' x_k in xi_y) with l_k = e_k - h sin(beta) the point's lateral distance (towards the field side) from the
    rail's shear-centre line: e_k from the crown point (:data:`COL_E`), the shear centre h
    (``rail_head_height``, scalar 9) below the crown on the rail's axis inclined by beta
    (``rail_cant`` = sin beta, scalar 10). ``rail`` = (z, y, dz/dt, dy/dt[, theta, dtheta/dt]):
    the rail head as for :func:`_wheel_contact` and, when given, the rail's roll (torsion) at
    the contact: the rail's vertical motion at the point follows it (seed paper eq. 31: the
    vertical load at l_h twists the rail; its transpose in the kinematics).

    Yaw: every column is interpolated bilinearly in (y_rel, yaw_w^2) between the zone tables'
    yaw layers (:func:`zone_geometry`: the contact on the yawed wheel's trace line; the last
    layer held beyond the largest yaw), and the point lies x_k ahead of the axle (:data:`COL_LEAD`,
    odd in yaw).

    Writes ``out`` (:data:`N_POINT_OUT`): the wheel's summed [F_x, F_y, F_z, M_spin, N], y_rel,
    the largest penetration, then the generalised moments about the wheelset centre of the
    points' forces at (x_k, s a_k, -r_k): roll sum(s a_k F_z + r_k F_y), spin sum(-r_k F_x), yaw
    sum(-s a_k F_x + x_k F_y + M_k cos d_k), and sum(s l_k F_z), the moment about x of the vertical
    forces on the wheel about the rail's shear-centre line (the rail carries its negative).

    Semi-implicit lateral creep (``creep_relax`` > 0, as :func:`_wheel_contact`): the points'
    lateral creep dampers f22_k / V act in parallel between the wheelset and the rail head, so
    each point's creepage is relaxed with the wheel's total g = creep_relax sum(f22_k):
    xi_y*_k = (xi_y_k + g xi_y*_k,prev) / (1 + g) (the backward-Euler value for parallel dampers
    on one velocity; exact in steady state). ``creep_prev[k]`` holds each point's xi_y* (NaN out
    of contact: a point coming into contact starts from the explicit law). ``pts`` is scratch
    (n_zones, :data:`N_PTS_COLS`).

    Creep law (``scal[SCAL_CREEP_LAW]``): 0 Kalker + Shen-Hedrick-Elkins
    (:func:`_point_creep_forces`), 1 Polach (:func:`_polach_creep_forces`), for every point.
    """
    g_shear, e_mod, nu, mu, r0 = scal[1], scal[2], scal[3], scal[4], scal[5]
    axis = scal[9] * scal[10]
    ws_y, ws_z, ws_roll, ws_yaw, ws_vy, ws_vz, ws_vroll, ws_vpitch, ws_vyaw = wheelset
    rail_z, rail_y, rail_vz, rail_vy, rail_roll, rail_vroll = rail
    y_rel = ws_y - rail_y
    n_z = zones.shape[0]
    n_yaw = zones.shape[1]
    n = zones.shape[2]
    i, w = _grid_cell(zones[0, 0, 0, 0], zones[0, 0, 1, 0], n, side * y_rel)
    # r and dz extrapolate linearly beyond the table; the other columns hold their end values
    if w < 0.0:
        ih, wh = 0, 0.0
    elif w > 1.0:
        ih, wh = n - 2, 1.0
    else:
        ih, wh = i, w
    # yaw layers: linear in yaw^2 between two layers (the even quantities' leading term), the
    # last layer held beyond the table
    if n_yaw > 1:
        yaw2 = ws_yaw * ws_yaw
        j = 0
        while j < n_yaw - 2 and zones[0, j + 1, 0, COL_YAW2] < yaw2:
            j += 1
        j1 = j + 1
        wy = (yaw2 - zones[0, j, 0, COL_YAW2]) / (zones[0, j1, 0, COL_YAW2] - zones[0, j, 0, COL_YAW2])
        if wy > 1.0:
            wy = 1.0
    else:
        j, j1, wy = 0, 0, 0.0
    # the lead is odd in yaw; the right wheel's mirrored axes see -yaw
    lead_sign = 1.0 if side * ws_yaw >= 0.0 else -1.0
    f22_sum = 0.0
    pen_max = -np.inf
    for k in range(n_z):
        zk = zones[k]
        a = _lerp2(zk, j, j1, wy, ih, wh, COL_A)
        lever = _lerp2(zk, j, j1, wy, ih, wh, COL_E) - axis
        pen = (rail_z + side * lever * rail_roll - (ws_z + side * a * ws_roll)
               + _lerp2(zk, j, j1, wy, i, w, COL_DZ))
        if pen > pen_max:
            pen_max = pen
        pts[k, 0] = 0.0
        if pen <= 0.0:
            continue
        delta = _lerp2(zk, j, j1, wy, ih, wh, COL_DELTA)
        g_k = _lerp2(zk, j, j1, wy, ih, wh, COL_G)
        cos_d = np.cos(delta)
        normal = _hertz_force(pen * cos_d, g_k)
        if normal <= 0.0:
            continue
        absum = _lerp2(zk, j, j1, wy, ih, wh, COL_ABSUM)
        m_k = _lerp2(zk, j, j1, wy, ih, wh, COL_M)
        n_k = _lerp2(zk, j, j1, wy, ih, wh, COL_N)
        c, ab, ab_15 = _contact_ellipse(normal, nu, e_mod, absum, m_k, n_k)
        pts[k, 10] = m_k * c
        pts[k, 11] = n_k * c
        f22 = g_shear * ab * _lerp2(zk, j, j1, wy, ih, wh, COL_C22)
        pts[k, 0] = normal
        pts[k, 1] = _lerp2(zk, j, j1, wy, i, w, COL_R)
        pts[k, 2] = delta
        pts[k, 3] = a
        pts[k, 4] = lever
        pts[k, 5] = g_shear * ab * _lerp2(zk, j, j1, wy, ih, wh, COL_C11)
        pts[k, 6] = f22
        pts[k, 7] = g_shear * ab_15 * _lerp2(zk, j, j1, wy, ih, wh, COL_C23)
        pts[k, 8] = g_shear * ab * ab * _lerp2(zk, j, j1, wy, ih, wh, COL_C33)
        pts[k, 9] = cos_d
        pts[k, 12] = lead_sign * _lerp2(zk, j, j1, wy, ih, wh, COL_LEAD)
        f22_sum += f22
    g = f22_sum * creep_relax
    fx_sum = 0.0
    fy_sum = 0.0
    fz_sum = 0.0
    mz_sum = 0.0
    n_sum = 0.0
    m_roll = 0.0
    m_spin = 0.0
    m_yaw = 0.0
    m_rail = 0.0
    for k in range(n_z):
        normal = pts[k, 0]
        if normal <= 0.0:
            creep_prev[k] = np.nan
            continue
        radius, delta, a, lever = pts[k, 1], pts[k, 2], pts[k, 3], pts[k, 4]
        f11, f22, f23, f33, cos_d = pts[k, 5], pts[k, 6], pts[k, 7], pts[k, 8], pts[k, 9]
        lead = pts[k, 12]
        sin_d = np.sin(delta)
        v_lat = ws_vy + radius * ws_vroll - speed * ws_yaw - rail_vy + ws_vyaw * lead
        v_ver = ws_vz + side * a * ws_vroll - rail_vz - side * lever * rail_vroll
        xi_y = (v_lat * cos_d + side * v_ver * sin_d) / speed
        if creep_relax > 0.0 and creep_prev[k] == creep_prev[k]:
            xi_y = (xi_y + g * creep_prev[k]) / (1.0 + g)
        creep_prev[k] = xi_y
        fx, fy, mz = _creep_forces(scal, side, normal, radius, a, cos_d, sin_d, xi_y, f11, f22,
                                   f23, f33, r0, mu, speed, ws_vyaw, ws_vpitch, pts[k, 10],
                                   pts[k, 11])
        force_y = -side * normal * sin_d + fy * cos_d
        force_z = normal * cos_d + side * fy * sin_d
        fx_sum += fx
        fy_sum += force_y
        fz_sum += force_z
        mz_sum += mz
        n_sum += normal
        m_roll += side * a * force_z + radius * force_y
        m_spin -= radius * fx
        m_yaw += -side * a * fx + lead * force_y + mz * cos_d
        m_rail += side * lever * force_z
    out[0] = fx_sum
    out[1] = fy_sum
    out[2] = fz_sum
    out[3] = mz_sum
    out[4] = n_sum
    out[5] = y_rel
    out[6] = pen_max
    out[7] = m_roll
    out[8] = m_spin
    out[9] = m_yaw
    out[10] = m_rail


def yaw_table_limit(geom: ContactGeometry) -> float | None:
    """The largest wheelset yaw (rad) the two-point tables cover (the last layer is held
    beyond it), or None when the geometry has no yaw layers."""
    layers = geom.zone_array()
    if layers.shape[0] == 0 or layers.shape[1] < 2:
        return None
    return float(np.sqrt(layers[0, -1, 0, COL_YAW2]))


def zone_columns(geom: ContactGeometry, y_rel: float, yaw: float = 0.0) -> np.ndarray:
    """The left wheel's zone-table columns (n_zones, :data:`N_ZCOLS`) at ``y_rel`` (within the
    table) and wheelset yaw ``yaw`` as :func:`_wheel_contact_points` interpolates them: linear in
    y_rel, linear in yaw^2 between the yaw layers, the last layer held beyond; the lead takes
    the sign of the yaw. For analysis and tests."""
    layers = geom.zone_array()
    if layers.shape[0] == 0:
        raise ValueError("zone_columns: the geometry has no two-point zone tables")
    y_grid = layers[0, 0, :, COL_Y]
    per_layer = np.array([[[np.interp(y_rel, y_grid, layers[k, j, :, c]) for c in range(N_ZCOLS)]
                           for j in range(layers.shape[1])] for k in range(layers.shape[0])])
    yaw2 = layers[0, :, 0, COL_YAW2]
    out = np.array([[np.interp(yaw * yaw, yaw2, per_layer[k, :, c]) if yaw2.size > 1
                     else per_layer[k, 0, c] for c in range(N_ZCOLS)]
                    for k in range(layers.shape[0])])
    out[:, COL_LEAD] *= 1.0 if yaw >= 0.0 else -1.0
    return out


def wheel_contact_points(side: float, geom: ContactGeometry, speed: float, ws: dict,
                         rail: dict, points: bool = False):
    """Python wrapper of :func:`_wheel_contact_points` for tests (explicit creep law): the
    wheel's results, and with ``points`` also each zone's normal force (flange first)."""
    zones = geom.zone_array()
    if zones.shape[0] == 0:
        raise ValueError("wheel_contact_points: the geometry has no two-point zone tables")
    out = np.zeros(N_POINT_OUT)
    pts = np.zeros((zones.shape[0], N_PTS_COLS))
    wheelset = tuple(float(ws.get(k, 0.0)) for k in ("y", "z", "roll", "yaw", "vy", "vz", "vroll",
                                                     "vpitch", "vyaw"))
    rails = tuple(float(rail.get(k, 0.0)) for k in ("z", "y", "vz", "vy", "roll", "vroll"))
    _wheel_contact_points(side, zones, geom.scalars(), speed, wheelset, rails, pts, out,
                          np.full(zones.shape[0], np.nan), 0.0)
    return (out, pts[:, 0].copy()) if points else out


def wheel_contact(side: float, geom: ContactGeometry, speed: float, ws: dict, rail: dict) -> np.ndarray:
    """Python wrapper of :func:`_wheel_contact` for tests: ``ws``/``rail`` give the kinematics."""
    row = np.zeros(N_COLS)
    out = np.zeros(N_POINT_OUT)
    wheelset = tuple(float(ws.get(k, 0.0)) for k in ("y", "z", "roll", "yaw", "vy", "vz", "vroll",
                                                     "vpitch", "vyaw"))
    rails = tuple(float(rail.get(k, 0.0)) for k in ("z", "y", "vz", "vy"))
    _wheel_contact(side, geom.table, geom.scalars(), speed, wheelset, rails, row, out)
    return out[:7]      # forces, normal load, y_rel, penetration: N_POINT_OUT less the moments
