"""Linear hunting stability on rigid straight track: eigenvalues against speed, critical speed.

The linear system is the coupled model's own vehicle linearised about its static state on a
perfect rigid track (rails fixed, no irregularity):

    M x'' + (C_s - J_v(V)) x' + (K_s - J_q(V)) x = 0,

with M, K_s, C_s the suspension of :mod:`ttbpipe.vehicle.model` (35 DOF per car: y, z, roll,
pitch/spin, yaw of the car body, two bogie frames and four wheelsets) and J_q, J_v the
derivatives of the wheel-rail generalised forces of :mod:`ttbpipe.vehicle.kernels` (the kernel
:func:`ttbpipe.vehicle.contact._wheel_contact`) with respect to the wheelsets' displacements and
velocities, written out term by term (:func:`wheel_jacobian`):

* Hertz: dN = k_H (cos delta0 dp - p0 sin delta0 d delta), k_H = 1.5 N0^(1/3) / G, with the
  penetration p = z_rail - (z + s a0 roll) + dz(s y): the roll coupling (the wheelset rolls by
  (dz(y) - dz(-y)) / 2 a0 to keep both wheels loaded) comes from the table's slope dz'(0);
* contact angle: the lateral components -s N sin(delta) of both normal forces change by
  -N0 cos(delta0) delta'(0) y each (the gravitational stiffness) and by the load difference;
* creepages (the kernel's formulas): d xi_x = -r'(0) s y / r0 - s a0 yaw' / V - r0 spin' / V,
  d xi_y = [cos delta0 (y' + r0 roll' - V yaw) + s sin delta0 (z' + s a0 roll')] / V,
  d xi_sp = cos delta0 yaw' / V - s cos delta0 d delta / r0; the rolling-radius slope r'(0) is
  the conicity lambda (Delta r = 2 lambda y);
* Kalker's linear coefficients f11, f22, f23, f33 (:func:`ttbpipe.vehicle.contact.
  creep_coefficients`) at the static load, with their change with N (ab ~ N^(2/3)) and with the
  table's ellipse columns (they multiply the static spin creepage -s sin(delta0) / r0);
* Shen-Hedrick-Elkins: at the static state the spin creepage already gives a lateral creep force
  -f23 xi_sp0, so the saturation factor k(beta) = 1 - beta/3 + beta^2/27 (beta <= 3) is
  linearised about beta0 = |F0| / (mu N0) instead of taken as 1.

The table's slopes at y = 0 (``amplitude=None``: central differences over one table step, the
derivative the kernel's piecewise-linear interpolation has there) give the tangent
linearisation; with an ``amplitude`` the slopes are the quasi-linear (describing-function)
values of a harmonic motion of that amplitude: the rolling-radius slope is the EN 15302
equivalent conicity (:func:`ttbpipe.vehicle.contact_geometry.equivalent_conicity`, Annex B
method) and every other column's slope the harmonic linearisation of its odd part
(1 / (pi A)) int_0^2pi f(A sin t) sin t dt. For a cone both are the cone's exact slopes.

First-order form, with the wheelsets' spin angles dropped (nothing depends on them, only on the
spin rates): states (q without spins, v), A = [[0, P], [-M^-1 K P^T, -M^-1 C]] (P picks the
kept displacements). The critical speed is the lowest speed at which the largest real part of
A's eigenvalues crosses zero (:func:`critical_speed`: a scan and Brent's method); the mode that
crosses is the hunting mode (its frequency and the bodies that carry it are reported).

Closed forms for the tests (:func:`klingel_frequency`, :func:`wheelset_critical_speed`): the
kinematic oscillation of a free wheelset (Klingel 1883; Wickens, Fundamentals of Rail Vehicle
Dynamics, 2003; Iwnicki (ed.), Handbook of Railway Vehicle Dynamics, 2006) and the Routh-Hurwitz
critical speed of Wickens' linear wheelset with lateral and yaw springs to a fixed frame.

Not in the model, so not here either: the gyroscopic terms of the wheelsets' spin on tangent
track, the contact's yaw geometry (the contact point's longitudinal shift), the rails' motion.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from .contact import (COL_ABSUM, COL_C11, COL_C23, COL_C33, COL_DELTA, COL_DZ, COL_M,
                      COL_N, COL_R, COL_Y, N_COLS, ContactGeometry, creep_coefficients,
                      hertz_stiffness)
from .model import (BODY_NAMES, DOF_NAMES, DOF_PER_BODY, DOF_PER_CAR, PITCH, WHEELSETS, TrainModel)

log = logging.getLogger(__name__)

# the linearisation's variables: displacements then velocities of one wheelset (model order)
_Q = 0
_V = 5


# ---------------------------------------------------------------------------------------------
# Closed forms
# ---------------------------------------------------------------------------------------------
def klingel_frequency(speed: float, conicity: float, wheel_radius: float,
                      contact_half_distance: float, contact_angle: float | None = None) -> float:
    """Kinematic frequency (Hz) of a free coned wheelset, f = V / (2 pi) sqrt(lambda / (r0 a0)).

    Klingel (1883): pure rolling of radii r0 +- lambda y gives the yaw rate -V lambda y / (r0 a0)
    and the lateral speed V yaw, a harmonic motion of wavelength 2 pi sqrt(r0 a0 / lambda)
    (Wickens 2003; Iwnicki 2006). It is the low-speed limit of the free wheelset's creep
    dynamics (the inertia terms vanish as V -> 0, the creepages with them).

    ``contact_angle`` delta0 (a cone on the model's contact: gap change dz = lambda y like the
    radius): the wheelset then also rolls, by roll = lambda y / a0 (both wheels keep their
    load), and the kernel's lateral creepage, [cos delta0 (y' + r0 roll') + sin delta0 a0 roll']
    / V - yaw cos delta0, vanishes for y' (1 + lambda r0 / a0 + lambda tan delta0) = V yaw:
    the frequency is divided by sqrt(1 + lambda r0 / a0 + lambda tan delta0) (a 1.2 % lower
    frequency for lambda = 0.04, 7 % for 0.2)."""
    f = speed / (2.0 * np.pi) * np.sqrt(conicity / (wheel_radius * contact_half_distance))
    if contact_angle is not None:
        f /= np.sqrt(1.0 + conicity * wheel_radius / contact_half_distance
                     + conicity * np.tan(contact_angle))
    return float(f)


def wheelset_critical_speed(mass: float, yaw_inertia: float, lateral_stiffness: float,
                            yaw_stiffness: float, f11: float, f22: float, conicity: float,
                            wheel_radius: float, contact_half_distance: float
                            ) -> tuple[float, float]:
    """Critical speed (m/s) and frequency (Hz) of Wickens' linear wheelset with a lateral and a
    yaw spring to a fixed frame (Kalker's f11, f22 per wheel; no spin creep, no gravitational
    stiffness, no roll):

        m y'' + 2 f22 (y'/V - psi) + k_y y = 0,
        I psi'' + 2 f11 a0^2 psi'/V + 2 f11 a0 lambda y / r0 + k_psi psi = 0

    (Wickens, Fundamentals of Rail Vehicle Dynamics, 2003, ch. 2-3; Iwnicki (ed.), Handbook of
    Railway Vehicle Dynamics, 2006). The characteristic quartic a4 s^4 + a3 s^3 + a2 s^2 + a1 s
    + a0 has a4 = m I, a3 = P/V, a2 = Q + R/V^2, a1 = S/V, a0 = U with P = m F1 a0^2 + I F2,
    Q = m k_psi + I k_y, R = F1 F2 a0^2, S = F2 k_psi + F1 a0^2 k_y,
    U = k_y k_psi + F1 F2 a0 lambda / r0 (F1 = 2 f11, F2 = 2 f22). By the Routh-Hurwitz
    criterion it is stable while a3 a2 a1 > a4 a1^2 + a3^2 a0, i.e. for
    1/V^2 > (m I S^2 + P^2 U - P S Q) / (P S R); on the boundary s = i omega with
    omega^2 = a1 / a3 = S / P (derived here from the criterion). Returns (0, nan) when the
    wheelset is unstable at every speed (no springs) and (inf, nan) when it is stable at all."""
    f1, f2 = 2.0 * f11, 2.0 * f22
    a0, r0 = contact_half_distance, wheel_radius
    p = mass * f1 * a0 ** 2 + yaw_inertia * f2
    q = mass * yaw_stiffness + yaw_inertia * lateral_stiffness
    r = f1 * f2 * a0 ** 2
    s = f2 * yaw_stiffness + f1 * a0 ** 2 * lateral_stiffness
    u = lateral_stiffness * yaw_stiffness + f1 * f2 * a0 * conicity / r0
    if s <= 0.0:
        return 0.0, float("nan")
    inv_v2 = (mass * yaw_inertia * s * s + p * p * u - p * s * q) / (p * s * r)
    if inv_v2 <= 0.0:
        return float("inf"), float("nan")
    return float(1.0 / np.sqrt(inv_v2)), float(np.sqrt(s / p) / (2.0 * np.pi))


# ---------------------------------------------------------------------------------------------
# The contact table's slopes
# ---------------------------------------------------------------------------------------------
@dataclass
class ContactSlopes:
    """The left wheel's table at y_rel = 0 (``row0``) and the slopes d(column)/d(y_rel) used by
    the linearisation (``slopes``; column order of :mod:`ttbpipe.vehicle.contact`)."""

    row0: np.ndarray
    slopes: np.ndarray
    amplitude: float | None      # None: tangent at y = 0; else the harmonic amplitude (m)

    @property
    def conicity(self) -> float:
        """The rolling-radius slope lambda (Delta r = 2 lambda y)."""
        return float(self.slopes[COL_R])

    @property
    def contact_angle_slope(self) -> float:
        """d delta / dy (rad/m): the gravitational stiffness is -2 N cos(delta0) times it."""
        return float(self.slopes[COL_DELTA])


def _column(geom: ContactGeometry, col: int, y: np.ndarray) -> np.ndarray:
    """Column ``col`` of the table at y_rel (the kernel's linear interpolation inside)."""
    return np.interp(y, geom.table[:, COL_Y], geom.table[:, col])


def contact_slopes(geom: ContactGeometry, amplitude: float | None = None,
                   conicity: float | None = None) -> ContactSlopes:
    """The table's value and slopes at y_rel = 0 (module docstring).

    ``amplitude`` None: central differences over one table step (what the kernel's interpolation
    gives for a small motion about 0); a number (m): quasi-linear slopes for a harmonic motion
    of that amplitude, the rolling radius by EN 15302 Annex B. ``conicity`` overrides the
    rolling-radius slope."""
    from .contact_geometry import equivalent_conicity

    y = geom.table[:, COL_Y]
    step = float(y[1] - y[0])
    row0 = np.array([_column(geom, c, np.array([0.0]))[0] for c in range(N_COLS)])
    slopes = np.zeros(N_COLS)
    if amplitude is None:
        for c in range(N_COLS):
            hi, lo = _column(geom, c, np.array([step, -step]))
            slopes[c] = (hi - lo) / (2.0 * step)
    else:
        if not 0.0 < amplitude <= min(-y[0], y[-1]):
            raise ValueError(f"amplitude {amplitude} m outside the table's range "
                             f"[{y[0]}, {y[-1]}] m")
        n = 4096
        t = (np.arange(n) + 0.5) * 2.0 * np.pi / n
        s = np.sin(t)
        for c in range(N_COLS):
            f = _column(geom, c, amplitude * s)
            slopes[c] = np.sum(f * s) * (2.0 / n) / amplitude
        half = min(-y[0], y[-1])
        sym = np.linspace(-half, half, 2 * int(round(half / step)) + 1)
        delta_r = _column(geom, COL_R, sym) - _column(geom, COL_R, -sym)
        slopes[COL_R] = equivalent_conicity(sym, delta_r, amplitude)
    slopes[COL_Y] = 1.0
    if conicity is not None:
        slopes[COL_R] = float(conicity)
    return ContactSlopes(row0=row0, slopes=slopes, amplitude=amplitude)


# ---------------------------------------------------------------------------------------------
# One wheel's linearised contact
# ---------------------------------------------------------------------------------------------
def _she(beta: float) -> tuple[float, float]:
    """Shen-Hedrick-Elkins factor F'/F = k(beta) and dk/dbeta (contact._she_factor)."""
    if beta <= 3.0:
        return 1.0 - beta / 3.0 + beta * beta / 27.0, -1.0 / 3.0 + 2.0 * beta / 27.0
    return 3.0 / beta, -3.0 / (beta * beta)


def wheel_jacobian(geom: ContactGeometry, slopes: ContactSlopes, side: float, speed: float,
                   normal: float) -> np.ndarray:
    """(5, 10) derivatives of the generalised contact forces of one wheel (``side`` +1 left,
    -1 right) on its wheelset's DOFs (y, z, roll, spin, yaw) with respect to the wheelset's
    displacements (columns 0-4) and velocities (5-9), at the static state on a fixed rail: the
    wheelset centred (y = 0, yaw 0, spin rate 0) under the normal load ``normal`` (N).

    The terms follow :func:`ttbpipe.vehicle.contact._wheel_contact` and
    :func:`ttbpipe.vehicle.kernels.train_contact` (module docstring); the flange is out of
    contact. Tested against central differences of the kernel itself.
    """
    s = float(side)
    sc = geom.scalars()
    g_hertz, mu, r0, a0 = sc[0], sc[4], sc[5], sc[6]
    row, sl = slopes.row0, slopes.slopes
    delta0 = row[COL_DELTA]
    cd, sd = np.cos(delta0), np.sin(delta0)
    v = float(speed)
    n0 = float(normal)
    p0 = g_hertz * n0 ** (2.0 / 3.0) / cd           # penetration of the static load
    e = np.eye(10)
    du = s * e[_Q + 0]                              # the table's argument s y_rel
    dr = sl[COL_R] * du
    ddelta = sl[COL_DELTA] * du
    dp = -e[_Q + 1] - s * a0 * e[_Q + 2] + sl[COL_DZ] * du
    k_h = hertz_stiffness(n0, g_hertz)
    dn = k_h * (cd * dp - p0 * sd * ddelta)
    # Kalker coefficients at the static load and their changes (ab ~ m n (N / (A+B))^(2/3))
    f11, f22, f23, f33 = creep_coefficients(geom, n0, row)
    unit = row.copy()
    unit[COL_C11:COL_C33 + 1] = 1.0
    _, _, g23, g33 = creep_coefficients(geom, n0, unit)     # G ab^1.5, G ab^2
    dln_ab = (sl[COL_M] / row[COL_M] * du + sl[COL_N] / row[COL_N] * du
              + (2.0 / 3.0) * (dn / n0 - sl[COL_ABSUM] / row[COL_ABSUM] * du))
    df23 = 1.5 * f23 * dln_ab + g23 * sl[COL_C23] * du
    df33 = 2.0 * f33 * dln_ab + g33 * sl[COL_C33] * du
    # creepages: all zero at the static state except the spin
    xi_sp0 = -s * sd / r0
    dxi_x = -dr / r0 - s * a0 * e[_V + 4] / v - r0 * e[_V + 3] / v
    dxi_y = (cd * (e[_V + 0] + r0 * e[_V + 2] - v * e[_Q + 4])
             + s * sd * (e[_V + 1] + s * a0 * e[_V + 2])) / v
    dxi_sp = cd * e[_V + 4] / v - s * cd * ddelta / r0
    # linear creep forces and their static values
    ty0 = -f23 * xi_sp0
    tm0 = -f33 * xi_sp0
    dtx = -f11 * dxi_x
    dty = -f22 * dxi_y - df23 * xi_sp0 - f23 * dxi_sp
    dtm = f23 * dxi_y - df33 * xi_sp0 - f33 * dxi_sp
    # Shen-Hedrick-Elkins about the static creep force (|T0| = |ty0|, tx0 = 0)
    beta0 = abs(ty0) / (mu * n0)
    k0, dk_dbeta = _she(beta0)
    if ty0 != 0.0:
        dbeta = np.sign(ty0) * dty / (mu * n0) - beta0 * dn / n0
        dk = dk_dbeta * dbeta
    else:   # |T| has a kink at 0; the saturation is of second order there
        dk = np.zeros(10)
    dfx = k0 * dtx
    dfy = k0 * dty + ty0 * dk
    dmz = k0 * dtm + tm0 * dk
    fy0, mz0 = k0 * ty0, k0 * tm0
    # forces of the rail on the wheel in track axes
    d_force_y = -s * (sd * dn + n0 * cd * ddelta) + cd * dfy - fy0 * sd * ddelta
    d_force_z = cd * dn - n0 * sd * ddelta + s * (sd * dfy + fy0 * cd * ddelta)
    force_y0 = -s * n0 * sd + fy0 * cd
    jac = np.zeros((5, 10))
    jac[0] = d_force_y
    jac[1] = d_force_z
    jac[2] = s * a0 * d_force_z + r0 * d_force_y + force_y0 * dr
    jac[3] = -r0 * dfx
    jac[4] = -s * a0 * dfx + cd * dmz - mz0 * sd * ddelta
    return jac


# ---------------------------------------------------------------------------------------------
# Linear systems
# ---------------------------------------------------------------------------------------------
@dataclass
class LinearSystem:
    """M x'' + C x' + K x = 0 of a vehicle on rigid straight track at one speed."""

    mass: np.ndarray            # (n,)
    stiffness: np.ndarray       # (n, n) suspension minus contact J_q
    damping: np.ndarray         # (n, n) suspension minus contact J_v
    labels: list[str]
    spin: np.ndarray            # (n,) bool: wheelset spin DOFs (angle dropped from the state)
    speed: float

    def state_matrix(self) -> np.ndarray:
        """A of x' = A x, x = (q without spin angles, v)."""
        n = self.mass.size
        keep = np.flatnonzero(~self.spin)
        if np.any(self.stiffness[:, self.spin] != 0.0):
            raise ValueError("a spin angle carries stiffness: it cannot be dropped")
        inv_m = 1.0 / self.mass
        m = keep.size
        a = np.zeros((m + n, m + n))
        a[np.arange(m), m + keep] = 1.0
        a[m:, :m] = -inv_m[:, None] * self.stiffness[:, keep]
        a[m:, m:] = -inv_m[:, None] * self.damping
        return a

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues (sorted by decreasing real part) and the velocity parts of their
        eigenvectors (n, k) (velocities carry every DOF, the spins too)."""
        a = self.state_matrix()
        w, vec = np.linalg.eig(a)
        order = np.argsort(-w.real)
        m = a.shape[0] - self.mass.size
        return w[order], vec[m:, order]


def linear_system(mass: np.ndarray, stiffness: np.ndarray, damping: np.ndarray,
                  wheelset_dofs: np.ndarray, geom: ContactGeometry, slopes: ContactSlopes,
                  speed: float, normal: np.ndarray, labels: list[str] | None = None
                  ) -> LinearSystem:
    """Suspension (M diagonal, K, C dense) plus the linearised contact of every wheel.

    ``wheelset_dofs`` (n_ws, 5) the wheelsets' DOF indices (y, z, roll, spin, yaw);
    ``normal`` (n_ws, 2) the static normal loads of the left and right wheels (N). The
    linearisation is that of one contact point per wheel (:func:`ttbpipe.vehicle.contact.
    _wheel_contact`): a profile pair's two-point geometry (``contact_points: 2``) and a creep law
    other than ``kalker_she`` are refused."""
    if getattr(geom, "zones", None) is not None:
        raise ValueError("linear hunting analysis: the contact geometry has two points per wheel "
                         "(train.contact.contact_points: 2); it linearises one point per wheel, "
                         "so set contact_points: 1")
    if getattr(geom, "creep_law", "kalker_she") != "kalker_she":
        raise ValueError("linear hunting analysis: it linearises Kalker + Shen-Hedrick-Elkins "
                         f"(train.contact.creep_law: kalker_she), not {geom.creep_law!r}")
    k = np.array(stiffness, dtype=float, copy=True)
    c = np.array(damping, dtype=float, copy=True)
    spin = np.zeros(k.shape[0], dtype=bool)
    for w, dofs in enumerate(np.asarray(wheelset_dofs)):
        spin[dofs[PITCH]] = True
        for k_side, side in enumerate((1.0, -1.0)):
            jac = wheel_jacobian(geom, slopes, side, speed, float(normal[w][k_side]))
            k[np.ix_(dofs, dofs)] -= jac[:, :5]
            c[np.ix_(dofs, dofs)] -= jac[:, 5:]
    if labels is None:
        labels = [f"dof{i}" for i in range(k.shape[0])]
    return LinearSystem(np.asarray(mass, float), k, c, list(labels), spin, float(speed))


@dataclass
class CarStatics:
    """A car's static state on rigid straight track (the linearisation point)."""

    model: TrainModel
    geom: ContactGeometry
    q: np.ndarray
    normal: np.ndarray           # (n_ws, 2)
    lateral_offset_m: float      # largest |y| of a wheelset (0 by symmetry)


def car_statics(model: TrainModel, geom: ContactGeometry) -> CarStatics:
    """Static state of the train ``model`` on perfect rigid track
    (:func:`ttbpipe.vehicle.static.solve_vehicle_static`, the loop's own start)."""
    from .static import solve_vehicle_static

    q, wheel, _ = solve_vehicle_static(model, geom, speed=1.0)
    offset = float(np.abs(q[model.wheelset_dofs[:, 0]]).max())
    return CarStatics(model, geom, q, wheel[:, :, 4].copy(), offset)


def car_system(statics: CarStatics, slopes: ContactSlopes, speed: float, car: int = 0,
               bodies: tuple[int, ...] | None = None) -> LinearSystem:
    """Linear system of car ``car`` of the model at ``speed`` (m/s).

    ``bodies``: the bodies kept free (0 car body, 1-2 bogie frames, 3-6 wheelsets; default all
    seven); the others are held fixed, their suspension elements acting as springs and dampers
    to ground (e.g. ``(1, 3, 4)``: the front bogie with its wheelsets under a fixed car body)."""
    model = statics.model
    if abs(statics.lateral_offset_m) > 1e-9:
        log.warning("static wheelset offset %.3g m: the linearisation assumes a centred wheelset",
                    statics.lateral_offset_m)
    dofs = DOF_PER_CAR * car + np.arange(DOF_PER_CAR)
    keep_bodies = tuple(range(7)) if bodies is None else tuple(sorted(bodies))
    local = np.concatenate([DOF_PER_BODY * b + np.arange(DOF_PER_BODY) for b in keep_bodies])
    sel = dofs[local]
    mass = model.mass[sel]
    k = model.stiffness[sel][:, sel].toarray()
    c = model.damping[sel][:, sel].toarray()
    labels = [f"{BODY_NAMES[b]}_{d}" for b in keep_bodies for d in DOF_NAMES]
    ws_local, normals = [], []
    car_ws = np.flatnonzero(model.wheelset_car == car)
    for j, body in enumerate(WHEELSETS):
        if body in keep_bodies:
            pos = keep_bodies.index(body)
            ws_local.append(DOF_PER_BODY * pos + np.arange(DOF_PER_BODY))
            normals.append(statics.normal[car_ws[j]])
    return linear_system(mass, k, c, np.asarray(ws_local).reshape(-1, 5), statics.geom, slopes,
                         speed, np.asarray(normals).reshape(-1, 2), labels)


# ---------------------------------------------------------------------------------------------
# Critical speed
# ---------------------------------------------------------------------------------------------
def least_damped(system: LinearSystem, min_frequency_hz: float = 0.0) -> dict:
    """The eigenvalue with the largest real part (oscillatory ones above ``min_frequency_hz``
    only, when given): real part (1/s), frequency (Hz), damping ratio and the three DOFs with
    the largest share of the mode's kinetic energy."""
    w, vel = system.modes()
    tol = 2.0 * np.pi * min_frequency_hz
    idx = [i for i in range(w.size) if abs(w[i].imag) > tol or min_frequency_hz <= 0.0]
    i = idx[0]
    energy = system.mass * np.abs(vel[:, i]) ** 2
    top = np.argsort(-energy)[:3]
    lam = w[i]
    return {"real_1_s": float(lam.real), "frequency_hz": float(abs(lam.imag) / (2 * np.pi)),
            "damping_ratio": float(-lam.real / abs(lam)) if abs(lam) > 0 else 0.0,
            "dominant_dofs": [system.labels[j] for j in top],
            "energy_share": [float(energy[j] / energy.sum()) for j in top]}


@dataclass
class CriticalSpeed:
    """Result of :func:`critical_speed`."""

    speed_m_s: float                  # nan when stable over the whole range
    frequency_hz: float
    mode: dict
    scan: list[dict] = field(default_factory=list)   # (speed, largest real part, frequency)

    @property
    def speed_kmh(self) -> float:
        return 3.6 * self.speed_m_s


def critical_speed(build, v_min: float, v_max: float, n_scan: int = 40,
                   min_frequency_hz: float = 0.0, xtol: float = 1e-4) -> CriticalSpeed:
    """Lowest speed in [v_min, v_max] (m/s) at which the largest real part of the eigenvalues
    of ``build(V)`` (a :class:`LinearSystem`) becomes positive: a scan of ``n_scan`` speeds,
    then Brent's method on the bracketing interval to ``xtol`` m/s."""
    speeds = np.linspace(v_min, v_max, n_scan)
    scan = []
    prev = None
    for v in speeds:
        mode = least_damped(build(float(v)), min_frequency_hz)
        scan.append({"speed_m_s": float(v), "real_1_s": mode["real_1_s"],
                     "frequency_hz": mode["frequency_hz"]})
        if mode["real_1_s"] > 0.0:
            if prev is None:
                return CriticalSpeed(float(v), mode["frequency_hz"], mode, scan)
            vc = brentq(lambda s: least_damped(build(s), min_frequency_hz)["real_1_s"], prev,
                        float(v), xtol=xtol)
            at = least_damped(build(vc), min_frequency_hz)
            return CriticalSpeed(float(vc), at["frequency_hz"], at, scan)
        prev = float(v)
    return CriticalSpeed(float("nan"), float("nan"), {}, scan)
