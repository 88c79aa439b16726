"""Horizontal curves with cant and clothoid transitions: the track frame the train follows.

The vehicle's DOFs are measured in track-following axes: each body's y, z, roll and yaw are
relative to the local track frame at the body's chainage (tangent to the centreline, in the
plane of the canted rails). On tangent track these are the model's usual axes. On a curve the
frame turns (heading Psi(x), curvature kappa = dPsi/dx, + = curving to the left) and rolls with
the cant (angle theta(x) of the track plane about x, + = left rail up; a left curve raises the
right rail, theta < 0). Three groups of terms follow (seed paper eqs. 28-30; Iwnicki (ed.),
Handbook of Railway Vehicle Dynamics, 2006, on track-following coordinates):

* inertial loads of the moving frame on every body of mass m, roll inertia I_x, yaw inertia I_z
  (track axes): F_y = -m (V^2 kappa cos theta + g sin theta) (centrifugal minus the cant's share
  of the weight), F_z = m V^2 kappa sin theta - m g cos theta (the weight itself is in the
  model's constant loads), M_z = -I_z V^2 dkappa/dx (the frame's yaw acceleration in a
  transition);
* the suspension sees the frames of the bodies it joins: the suspension forces are
  -K (q + q_track) - C (v + v_track), where q_track is the pose of each body's local frame in one
  common frame (the lead wheelset's) -- lateral offset of the curve from that frame's tangent
  minus h theta (the body's centre of gravity at height h rotates with the track plane about the
  centreline), the centreline's rise with the cant (the inner rail stays), roll theta, yaw
  Psi - Psi_lead -- and v_track its rate. K and C annihilate rigid motions, so on a constant
  curve with constant cant only the curve's sag between suspension points (kappa l^2 / 2) and
  the yaw angles between bodies (kappa l) load the springs; in a transition also the twist;
* the wheelset's yaw rate includes the frame's, V kappa: in the longitudinal creepage
  (+- a0 kappa, which puts a free coned wheelset at the pure-rolling offset r0 a0 / (lambda R)
  outwards) and in the spin creepage; and the gyroscopic moments of the rolling wheelsets from
  the frame's turning, I_spin (V/r0) V kappa in roll and -I_spin (V/r0) V dtheta/dx in yaw.

On the structure the track (rails, pads, slab) lies in the canted track plane, so the wheel
forces, which the contact gives in track axes, act on it as they are, and the CA mortar carries
them into the level girder through the cant's rotation (:func:`cant_knots`,
``ttbpipe.structure.build_structure(cant=...)``): at balanced cant the girder receives the
train's weight downwards and its centrifugal force outwards. The ground under the approaches is
rigid, so the track's springs to it need no rotation.

The girders are straight from bearing to bearing while the track follows the curve, so on a
curve the track's centre line runs off the girder's axis by the curve's offset from the span's
chord (:func:`plan_knots`, ``ttbpipe.structure.plan``): the eccentricity of the CA mortar's
load on the girder varies along each span (seed paper eq. 24's B_r - b_s/2 at every point).

Not modelled: the frame's roll acceleration V^2 d^2theta/dx^2 (zero on linear cant ramps
except at their ends), vertical curves, the track's curvature in plan in the rails' and slab's
own bending (they are modelled straight along the developed chainage; on R >> span the
track-frame loads are what matters), and the gyroscopic coupling of the wheelsets' own yaw and
roll rates on tangent track.

Configuration (``simulation.layout``)::

    layout:
      cant_base_m: 1.5          # distance over which cant is measured (EN 13803: 1.5 m)
      curves:
        - {start_x_m: 150, transition_m: 60, length_m: 200, radius_m: 3000, cant_mm: 120,
           direction: left}

Each curve: a clothoid (curvature and cant linear in x) of ``transition_m`` from
``start_x_m``, the circular arc of ``length_m``, and the exit clothoid of the same length.
"""

from __future__ import annotations

from collections import namedtuple
from typing import Any, Mapping

import numpy as np

from ..constants import STANDARD_GRAVITY
from ..jit import kernel

#: EN 13803-1: cant is the height difference of the rails over 1500 mm.
CANT_BASE_M = 1.5
#: The layout's knots span this far beyond the configured curves (tangent track).
_FAR_M = 1.0e5

#: The curve terms for a time loop: layout knots (chainage, curvature 1/m, cant angle rad, and
#: the heading and lateral offset integrated exactly from the first knot), the bodies
#: (first DOF, x relative to the lead wheelset, mass, yaw inertia, spin inertia and rolling
#: speed factor 1/r0 of wheelsets (0 otherwise), centre-of-gravity height), the wheelsets' body
#: index, and ``scal`` = (active 0/1, gravity, cant base).
CurveArrays = namedtuple("CurveArrays", [
    "knot_x", "kappa", "theta", "heading", "offset", "body_dof0", "body_x", "body_mass",
    "body_yaw_inertia", "body_spin_inertia", "body_inv_radius", "body_height", "ws_body",
    "scal"])


def layout_knots(layout: Mapping[str, Any] | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(chainage, curvature, cant angle) knots of a ``simulation.layout`` section, piecewise
    linear between knots; tangent track beyond. Raises ValueError naming the curve at fault."""
    layout = dict(layout or {})
    base = float(layout.get("cant_base_m", CANT_BASE_M))
    xs, ks, ts = [-_FAR_M], [0.0], [0.0]
    curves = sorted(layout.get("curves") or [], key=lambda c: float(c["start_x_m"]))
    for i, c in enumerate(curves):
        where = f"simulation.layout.curves[{i}] (start_x_m {c.get('start_x_m')})"
        radius = float(c["radius_m"])
        if radius <= 0:
            raise ValueError(f"{where}: radius_m must be positive, got {radius}")
        cant = float(c.get("cant_mm", 0.0)) / 1000.0
        if not 0.0 <= cant < base:
            raise ValueError(f"{where}: cant_mm {cant * 1000:.0f} must lie in [0, "
                             f"{base * 1000:.0f}) (cant over {base} m)")
        direction = c.get("direction", "left")
        if direction not in ("left", "right"):
            raise ValueError(f"{where}: direction {direction!r}; expected left | right")
        sign = 1.0 if direction == "left" else -1.0
        kappa = sign / radius
        theta = -sign * np.arcsin(cant / base)     # the outer rail up
        x0 = float(c["start_x_m"])
        lt = float(c.get("transition_m", 0.0))
        lc = float(c["length_m"])
        if lt < 0 or lc < 0:
            raise ValueError(f"{where}: transition_m and length_m must not be negative")
        if x0 < xs[-1] or (x0 == xs[-1] and ks[-1] != 0.0):
            raise ValueError(f"{where}: overlaps the previous curve, which ends at {xs[-1]} m")
        pts = [(x0, 0.0, 0.0), (x0 + lt, kappa, theta), (x0 + lt + lc, kappa, theta),
               (x0 + 2 * lt + lc, 0.0, 0.0)]
        for x, k, t in pts:
            if x == xs[-1]:
                # a step in curvature (no transition): two knots a hair apart
                x = xs[-1] + 1e-9
            xs.append(x); ks.append(k); ts.append(t)
    xs.append(max(_FAR_M, xs[-1] + 1.0)); ks.append(0.0); ts.append(0.0)
    return np.array(xs), np.array(ks), np.array(ts)


def cant_knots(layout: Mapping[str, Any] | None) -> tuple[np.ndarray, np.ndarray] | None:
    """(chainage, cant angle) knots of a ``simulation.layout`` section for the structure
    (:func:`ttbpipe.structure.build_structure`'s ``cant``); None when the layout has no cant."""
    xs, _, ts = layout_knots(layout)
    return (xs, ts) if np.any(ts != 0.0) else None


def plan_knots(layout: Mapping[str, Any] | None) -> tuple[np.ndarray, np.ndarray] | None:
    """(chainage, curvature) knots of a ``simulation.layout`` section for the structure
    (:func:`ttbpipe.structure.build_structure`'s ``plan``: the track curved in plan on straight
    spans); None when the layout has no curvature."""
    xs, ks, _ = layout_knots(layout)
    return (xs, ks) if np.any(ks != 0.0) else None


def centreline_offset(xs: np.ndarray, ks: np.ndarray, x) -> np.ndarray:
    """Lateral offset (m, + left) of the track's centre line at chainage ``x`` from the tangent
    at the first knot, for the piecewise-linear curvature ``ks`` at the knots ``xs``: the
    curvature integrated twice, exactly (a cubic in x between knots; small-angle geometry, as
    the track frame of the loop)."""
    heading, offset = _integrate_knots(xs, ks)
    x = np.asarray(x, dtype=float)
    return _centreline_offsets(xs, ks, heading, offset, x.ravel()).reshape(x.shape)


@kernel
def _centreline_offsets(xk, kappa, heading, offset, x):
    """:func:`centreline_offset` at each of the points ``x`` (1-D), by the loop's own
    :func:`_pose_on_segment`."""
    out = np.empty(x.shape[0])
    for j in range(x.shape[0]):
        i = _knot_segment(xk, x[j])
        out[j] = _pose_on_segment(xk, kappa, heading, offset, i, x[j])[1]
    return out


def _integrate_knots(xs: np.ndarray, ks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Heading and lateral offset at the knots, integrating the piecewise-linear curvature
    exactly from 0 at the first knot (re-referenced to x = 0 by :func:`curve_arrays`)."""
    heading = np.zeros(xs.size)
    offset = np.zeros(xs.size)
    for i in range(xs.size - 1):
        s = xs[i + 1] - xs[i]
        dk = (ks[i + 1] - ks[i]) / s
        heading[i + 1] = heading[i] + ks[i] * s + 0.5 * dk * s * s
        offset[i + 1] = offset[i] + heading[i] * s + 0.5 * ks[i] * s * s + dk * s ** 3 / 6.0
    return heading, offset


def layout_along(layout: Mapping[str, Any] | None, direction: int) -> dict:
    """The ``simulation.layout`` as a train running in ``direction`` sees it, in its own
    travel chainage s = direction x (the coordinate its lead wheelset advances in).

    For -x every curve is met from its far end: it spans s in [-(x0 + 2 l_t + l_c), -x0] and
    turns the other way (a left-hand curve for +x is a right-hand one for -x); its radius,
    clothoids (both of the same length) and cant are the same, the raised rail is the same
    physical (outer) rail."""
    layout = dict(layout or {})
    if int(direction) == 1:
        return layout
    if int(direction) != -1:
        raise ValueError(f"direction must be 1 or -1, got {direction}")
    mirrored = []
    for c in layout.get("curves") or []:
        lt, lc = float(c.get("transition_m", 0.0)), float(c["length_m"])
        turned = "right" if c.get("direction", "left") == "left" else "left"
        mirrored.append({**c, "start_x_m": -(float(c["start_x_m"]) + 2.0 * lt + lc),
                         "direction": turned})
    return {**layout, "curves": mirrored}


def curve_arrays(model, layout: Mapping[str, Any] | None, direction: int = 1) -> CurveArrays:
    """:class:`CurveArrays` of a train model running in ``direction`` (+1: +x, -1: -x) on a
    ``simulation.layout`` (:func:`layout_along`; inactive when there are no curves: the loop
    then skips every curve term)."""
    from .model import BODIES_PER_CAR, DOF_PER_BODY, DOF_PER_CAR, WHEELSETS, _body_positions

    layout = layout_along(layout, direction)
    xs, ks, ts = layout_knots(layout)
    heading, offset = _integrate_knots(xs, ks)
    params = model.params
    r0 = params.contact.wheel_radius
    dof0, bx, mass, iz, ispin, inv_r, height, ws_body = [], [], [], [], [], [], [], []
    for c, car in enumerate(params.cars):
        pos = _body_positions(car, r0)
        for b in range(BODIES_PER_CAR):
            d = DOF_PER_CAR * c + DOF_PER_BODY * b
            if b in WHEELSETS:
                ws_body.append(len(dof0))
            dof0.append(d)
            bx.append(float(model.car_x[c]) + pos[b, 0])
            mass.append(model.mass[d])
            iz.append(model.mass[d + 4])
            ispin.append(model.mass[d + 3] if b in WHEELSETS else 0.0)
            inv_r.append(1.0 / r0 if b in WHEELSETS else 0.0)
            height.append(pos[b, 2])
    active = 1.0 if np.any(ks != 0.0) or np.any(ts != 0.0) else 0.0
    curve = CurveArrays(xs, ks, ts, heading, offset, np.asarray(dof0, dtype=np.int64),
                        np.asarray(bx), np.asarray(mass), np.asarray(iz), np.asarray(ispin),
                        np.asarray(inv_r), np.asarray(height), np.asarray(ws_body, dtype=np.int64),
                        np.array([active, STANDARD_GRAVITY,
                                  float(layout.get("cant_base_m", CANT_BASE_M))]))
    # re-reference heading and offset to x = 0, keeping the numbers small near the model
    _, _, _, _, h0, y0 = _frame_at(curve, 0.0)
    return curve._replace(heading=heading - h0, offset=offset - y0 - h0 * xs)


def no_curve(model) -> CurveArrays:
    """Tangent track everywhere (inactive)."""
    return curve_arrays(model, None)


@kernel(creates_arrays=False)
def _knot_segment(xk, x):
    """Index i of the knot interval [xk[i], xk[i+1]) holding x (the first or last interval
    beyond the knots)."""
    lo = 0
    hi = xk.shape[0] - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xk[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@kernel(creates_arrays=False)
def _pose_on_segment(xk, kappa, heading, offset, i, x):
    """(heading, lateral offset) of the centre line at x in knot interval i: the
    piecewise-linear curvature integrated exactly from the knots' heading and offset."""
    s = x - xk[i]
    dk = (kappa[i + 1] - kappa[i]) / (xk[i + 1] - xk[i])
    return (heading[i] + kappa[i] * s + 0.5 * dk * s * s,
            offset[i] + heading[i] * s + 0.5 * kappa[i] * s * s + dk * s * s * s / 6.0)


@kernel(creates_arrays=False)
def _frame_at(curve, x):
    """(curvature, its x-derivative, cant angle, its x-derivative, heading, lateral offset) of
    the track frame at chainage x (linear interpolation; heading and offset integrated
    exactly)."""
    xk = curve.knot_x
    i = _knot_segment(xk, x)
    seg = xk[i + 1] - xk[i]
    s = x - xk[i]
    dk = (curve.kappa[i + 1] - curve.kappa[i]) / seg
    dth = (curve.theta[i + 1] - curve.theta[i]) / seg
    kappa = curve.kappa[i] + dk * s
    theta = curve.theta[i] + dth * s
    heading, offset = _pose_on_segment(xk, curve.kappa, curve.heading, curve.offset, i, x)
    return kappa, dk, theta, dth, heading, offset


@kernel(creates_arrays=False)
def curve_frame(curve, x_lead, speed, q_track, v_track, f_track, ws_yaw_rate):
    """Fill the track frames' poses ``q_track`` and rates ``v_track`` (per vehicle DOF), the
    frame's inertial and gyroscopic loads ``f_track``, and every wheelset's frame yaw rate
    V kappa, for the lead wheelset at chainage ``x_lead`` (see the module's docstring)."""
    g = curve.scal[1]
    half_base = 0.5 * curve.scal[2]
    k_l, dk_l, th_l, dth_l, psi_l, y_l = _frame_at(curve, x_lead)
    v2 = speed * speed
    w = 0
    for b in range(curve.body_dof0.shape[0]):
        x = x_lead + curve.body_x[b]
        kappa, dk, theta, dth, psi, y = _frame_at(curve, x)
        dx = curve.body_x[b]
        h = curve.body_height[b]
        d = curve.body_dof0[b]
        sgn = 1.0 if theta >= 0.0 else -1.0
        rise = half_base * abs(np.sin(theta))
        drise = half_base * np.cos(theta) * dth * sgn
        q_track[d] = y - y_l - psi_l * dx - h * theta
        q_track[d + 1] = rise
        q_track[d + 2] = theta
        q_track[d + 3] = 0.0 if curve.body_inv_radius[b] > 0.0 else -drise
        q_track[d + 4] = psi - psi_l
        v_track[d] = speed * (psi - psi_l - k_l * dx) - h * speed * dth
        v_track[d + 1] = speed * drise
        v_track[d + 2] = speed * dth
        v_track[d + 3] = 0.0
        v_track[d + 4] = speed * (kappa - k_l)
        m = curve.body_mass[b]
        spin_momentum = curve.body_spin_inertia[b] * speed * curve.body_inv_radius[b]
        f_track[d] = -m * (v2 * kappa * np.cos(theta) + g * np.sin(theta))
        f_track[d + 1] = m * v2 * kappa * np.sin(theta) - m * g * (np.cos(theta) - 1.0)
        f_track[d + 2] = spin_momentum * speed * kappa
        f_track[d + 3] = 0.0
        f_track[d + 4] = -curve.body_yaw_inertia[b] * v2 * dk - spin_momentum * speed * dth
        if curve.body_inv_radius[b] > 0.0:
            # wheelsets come in the model's order (ws_body is increasing)
            ws_yaw_rate[w] = speed * kappa
            w += 1


def frame_at(curve: CurveArrays, x: float) -> dict:
    """Python view of the track frame at chainage x (curvature 1/m, cant angle rad, ...)."""
    kappa, dk, theta, dth, heading, offset = _frame_at(curve, float(x))
    return {"curvature_1_m": kappa, "curvature_slope_1_m2": dk, "cant_angle_rad": theta,
            "cant_angle_slope_rad_m": dth, "heading_rad": heading, "offset_m": offset}
