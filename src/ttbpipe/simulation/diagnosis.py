"""Why did a coupled run stop, or lose wheel-rail contact? Input indicators and the explanation.

A stop of the coupled loop (non-finite state, every wheel off the rail, vehicle divergence) is
not always a time-step problem: an implausible or too rough irregularity, or wheel loads too low
for it, stop it as well, at any step. :func:`explain` weighs, in this order,

1. the step against every stability limit of the case (``dt_limits`` of the setup/summary;
   :func:`ttbpipe.timestepping.limits.step_limits`): above one, the step is the cause;
2. the irregularity's amplitude in the 3-25 m band (EN 13848's D1 band, where the isolated-defect
   limits apply) against :data:`PLAUSIBLE_D1_PEAK_MM`, and a factor 1000 beyond it (mm vs m, or
   a wrong ``irregularity.scale``);
3. the irregularity's curvature: to stay on a rail that drops with curvature z'' at speed V the
   wheel must accelerate downwards at V^2 |z''|, and contact can give at most P0 / m_u (static
   wheel load over the unsprung mass per wheel, half a wheelset: N = m_u z'' + P0 >= 0). The
   ratio of the two (:func:`irregularity_indicators`) above 1 means wheels must lift;
4. loss of contact before the stop (which wheel, how long, where);

and names the likely cause with a remedy that works. Measured on one trailer car at 300 km/h on
rigid track, 200 m (regression values of this code): TB/T 3352 demand ratio 0.22 (no loss);
FRA class 6 0.76 (unloading 0.98); FRA class 5 1.84 (contact lost, run completes); FRA class 4
2.9 and class 1 4.5 (every wheel off the rail at 0.43 s).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

#: Largest plausible peak (mm) of the vertical or lateral irregularity of one rail in the
#: 3-25 m band: about the EN 13848-5 immediate-action limit for isolated longitudinal-level
#: defects in its loosest speed class (~28 mm up to 80 km/h [M]); a track beyond it is closed.
PLAUSIBLE_D1_PEAK_MM = 30.0
#: Band of the amplitude check (m): EN 13848-1 wavelength range D1 [M].
D1_BAND_M = (3.0, 25.0)


def _d1_peak_mm(values: np.ndarray, dx: float) -> float:
    """Largest |value| (mm) of rows of ``values`` (m) band-passed to :data:`D1_BAND_M`
    (4th-order Butterworth, forward-backward); the raw peak for records too short to filter."""
    from scipy import signal

    from ..filters import butterworth_sos

    lo, hi = D1_BAND_M
    fs = 1.0 / dx
    if values.shape[1] < 64 or 1.0 / lo >= 0.5 * fs:
        return float(1e3 * np.abs(values).max())
    sos = butterworth_sos(4, (1.0 / hi, 1.0 / lo), "bandpass", fs)
    return float(1e3 * np.abs(signal.sosfiltfilt(sos, values, axis=1)).max())


def irregularity_indicators(irr, speed: float, model) -> dict[str, float]:
    """Amplitudes and contact demand of the irregularity input of a run (module docstring).

    ``irr``: :class:`ttbpipe.irregularity.track_input.Irregularity` (rows z_left, z_right, y_left,
    y_right in m); returns peak_vertical_mm, peak_lateral_mm (all wavelengths), their 3-25 m band
    peaks (``*_d1_mm``), contact_hold_acc_m_s2 = min P0 / m_u, contact_demand_acc_m_s2 =
    V^2 max |z''| and contact_demand_ratio (their ratio).
    """
    z, y = irr.values[:2], irr.values[2:]
    hold = min(car.static_wheel_load / (0.5 * car.wheelset_mass) for car in model.params.cars)
    curvature = np.gradient(irr.slopes[:2], irr.dx, axis=1) if z.shape[1] > 2 else np.zeros(1)
    demand = speed ** 2 * float(np.abs(curvature).max())
    return {"peak_vertical_mm": float(1e3 * np.abs(z).max()),
            "peak_lateral_mm": float(1e3 * np.abs(y).max()),
            "peak_vertical_d1_mm": _d1_peak_mm(z, irr.dx) if z.any() else 0.0,
            "peak_lateral_d1_mm": _d1_peak_mm(y, irr.dx) if y.any() else 0.0,
            "contact_hold_acc_m_s2": float(hold), "contact_demand_acc_m_s2": demand,
            "contact_demand_ratio": demand / hold}


def contact_loss_stats(contact_loss: np.ndarray, dt: float, ws_x0: np.ndarray, speed: float,
                       labels: list[str]) -> dict[str, Any]:
    """Loss-of-contact index of a run from the loop's per-wheel counters (``_coupled_loop``).

    contact_loss_count (events over all wheels), contact_loss_total_s (time without contact,
    summed over wheels), contact_loss_max_s (longest event), per wheel
    ``contact_loss_per_wheel[label] = {count, total_s, max_s}``, and where it happened:
    ``contact_loss_longest`` = {wheel, start_s, start_x_m, duration_s} and
    ``contact_loss_first`` = {wheel, start_s, start_x_m} (None without loss). An event is a run
    of consecutive steps with zero normal force; k steps last k dt.
    """
    cl = np.asarray(contact_loss)
    per_wheel, longest, first = {}, None, None
    for w in range(cl.shape[0]):
        for k, side in enumerate(("left", "right")):
            c = cl[w, k]
            name = f"{labels[w]}_{side}"
            per_wheel[name] = {"count": int(c[0]), "total_s": float(c[1] * dt),
                               "max_s": float(c[2] * dt)}
            if c[0] > 0:
                if longest is None or c[2] * dt > longest["duration_s"]:
                    longest = {"wheel": name, "start_s": float(c[3] * dt),
                               "start_x_m": float(ws_x0[w] + speed * c[3] * dt),
                               "duration_s": float(c[2] * dt)}
                if first is None or c[5] * dt < first["start_s"]:
                    first = {"wheel": name, "start_s": float(c[5] * dt),
                             "start_x_m": float(ws_x0[w] + speed * c[5] * dt)}
    return {"contact_loss_count": int(cl[:, :, 0].sum()),
            "contact_loss_total_s": float(cl[:, :, 1].sum() * dt),
            "contact_loss_max_s": float(cl[:, :, 2].max() * dt) if cl.size else 0.0,
            "contact_loss_wheels": int((cl[:, :, 0] > 0).sum()),
            "contact_loss_per_wheel": per_wheel,
            "contact_loss_longest": longest, "contact_loss_first": first}


def _exceeded(dt: float, limits: Mapping[str, Any]) -> list[tuple[str, float]]:
    from ..timestepping.limits import LIMIT_NAMES, step_limits

    out = []
    for key, value in step_limits(limits).items():
        bound = limits["dt_structure_limit_s"] if key == "structure" else value
        if dt > bound * (1 + 1e-9):
            out.append((LIMIT_NAMES[key], bound))
    return out


def explain(dt: float, limits: Mapping[str, Any], irr: Mapping[str, float],
            loss: Mapping[str, Any] | None, irregularity_config: Mapping[str, Any] | None,
            speed: float, *, propose_auto: bool = False, stopped: bool = True
            ) -> tuple[str, str]:
    """(cause, text): the likely cause of a stop (or of a loss of contact when ``stopped`` is
    False) and the sentence naming it with its remedy and the evidence (module docstring).
    ``irregularity_config``: the case's irregularity section (None: unknown, e.g. from a summary).

    cause: ``time_step``, ``irregularity_scale``, ``irregularity_rough``, ``contact_loss`` or
    ``unexplained``.
    """
    from ..timestepping.limits import LIMIT_NAMES, step_limits, time_step_remedy

    cfg = dict(irregularity_config or {})
    source = cfg.get("source", "synthetic")
    what = ("the irregularity input" if irregularity_config is None else
            f"irregularity.scale {cfg.get('scale', 1.0):g} of spectrum "
            f"{cfg.get('spectrum', 'tbt3352')}" if source == "synthetic" else
            f"irregularity file {cfg.get('file')} (scale {cfg.get('scale', 1.0):g})"
            if source == "file" else "no irregularity")
    kmh = 3.6 * speed
    d1 = max(irr.get("peak_vertical_d1_mm", 0.0), irr.get("peak_lateral_d1_mm", 0.0))
    axis = ("vertical" if irr.get("peak_vertical_d1_mm", 0.0) >= irr.get("peak_lateral_d1_mm", 0.0)
            else "lateral")
    raw = irr.get(f"peak_{axis}_mm", 0.0)
    ratio = irr.get("contact_demand_ratio", 0.0)
    lims = step_limits(limits)
    exceeded = _exceeded(dt, limits)
    parts = []
    if exceeded:
        cause = "time_step"
        names = ", ".join(f"{n} {v:.3g} s" for n, v in exceeded)
        parts.append(f"likely cause: the time step {dt:g} s, above the stability limit(s) {names}; "
                     + time_step_remedy(limits, propose_auto))
    elif d1 > PLAUSIBLE_D1_PEAK_MM:
        cause = "irregularity_scale"
        factor = ("; a factor of about 1000 points to mm vs m (irregularity files and spectra "
                  "are in mm) or a wrong irregularity.scale" if d1 > 10 * PLAUSIBLE_D1_PEAK_MM else "")
        parts.append(f"likely cause: the irregularity: {what} gives {d1:.0f} mm peak {axis} "
                     f"irregularity in the 3-25 m band ({raw:.0f} mm over all wavelengths), beyond "
                     f"the plausible {PLAUSIBLE_D1_PEAK_MM:.0f} mm of the worst track in service "
                     f"(EN 13848-5 immediate-action limit){factor}: check the scale / units")
    elif ratio > 1.0:
        cause = "irregularity_rough"
        v_ok = kmh / np.sqrt(ratio)
        parts.append(f"likely cause: the irregularity is too rough for {kmh:.0f} km/h: at this "
                     f"speed its curvature asks the wheels for {ratio:.1f} times the downward "
                     f"acceleration wheel-rail contact can give (V^2 |z''| = "
                     f"{irr['contact_demand_acc_m_s2']:.0f} m/s^2 vs P0/m_wheel = "
                     f"{irr['contact_hold_acc_m_s2']:.0f} m/s^2), so wheels lift; on this profile "
                     f"({what}) contact would hold below about {v_ok:.0f} km/h: check the "
                     "irregularity input for this speed")
    elif loss and loss.get("contact_loss_count", 0) > 0 and stopped:
        cause = "contact_loss"
        parts.append("likely cause: the wheels lost contact before the stop although the step is "
                     "within every limit and the irregularity is plausible: check the wheel "
                     "loads and the contact parameters (train.contact), or a suspension that "
                     "lets a wheel lift")
    else:
        cause = "unexplained"
        parts.append("neither the time step (within every limit) nor the irregularity explains "
                     "it: check the suspension and contact parameters (train:); halving "
                     "simulation.time_step_s tells a step problem (the stop moves) from a model "
                     "problem (it stays)" if stopped else
                     "the irregularity is plausible and its curvature within what contact holds: "
                     "check the wheel loads and the contact parameters")
    if loss and loss.get("contact_loss_count", 0) > 0 and "contact_loss_longest" in loss:
        lo, fi = loss["contact_loss_longest"], loss["contact_loss_first"]
        parts.append(f"wheel-rail contact {'before the stop' if stopped else 'in the run'}: "
                     f"{loss['contact_loss_count']} losses on {loss['contact_loss_wheels']} "
                     f"wheel(s), {1e3 * loss['contact_loss_total_s']:.1f} ms in all, longest "
                     f"{1e3 * lo['duration_s']:.1f} ms ({lo['wheel']} from x = {lo['start_x_m']:.1f} m, "
                     f"t = {lo['start_s']:.4f} s), first {fi['wheel']} at x = "
                     f"{fi['start_x_m']:.1f} m")
    elif stopped:
        parts.append("no wheel had lost contact before the stop")
    if cause != "time_step" and lims:
        key = min(lims, key=lims.get)
        parts.append(f"the time step {dt:g} s is within every stability limit (smallest: "
                     f"{LIMIT_NAMES[key]} {lims[key]:.3g} s), so it is not the cause")
    parts.append(f"irregularity: peak {irr.get('peak_vertical_mm', 0.0):.1f} mm vertical / "
                 f"{irr.get('peak_lateral_mm', 0.0):.1f} mm lateral ({irr.get('peak_vertical_d1_mm', 0.0):.1f}"
                 f" / {irr.get('peak_lateral_d1_mm', 0.0):.1f} mm in 3-25 m), contact demand "
                 f"ratio {ratio:.2f} at {kmh:.0f} km/h")
    return cause, "; ".join(parts)
