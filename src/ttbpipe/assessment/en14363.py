"""EN 14363:2016 (+A1:2018): running safety and track loading as the standard evaluates them.

Processing (UIC 518 / EN 14363 post-processing table of the GENSYS course notes,
http://gensys.se/course/UIC518_tests.html [V], as in docs/reference/standards.md):

| quantity | filter | method | statistic |
|---|---|---|---|
| (Y/Q)2m, per wheel | low-pass >= 20 Hz | sliding mean over 2 m, sampling interval 0.5 m | F2 = 99.85 % (F1 = 0.15 %) |
| (sum Y)2m, per wheelset | low-pass >= 20 Hz | sliding mean over 2 m, 0.5 m | F1 = 0.15 %, F2 = 99.85 % |
| Q, per wheel | low-pass 20 Hz | - | F2 = 99.85 % |
| Y_qst, Q_qst, per wheel | low-pass >= 20 Hz | - | F0 = 50 % |

Here the filter is a Butterworth low-pass at the minimum cut-off, 20 Hz, of order 4 applied
forward and backward (zero phase; :class:`~.processing.Butterworth`) [M: the standard's filter
type and order not re-read; the table gives only the cut-off]. Notation: EN 14363 calls the
lateral force Y and the vertical force Q; the run's table calls them Q and P (GB notation).
Y/Q is taken in the flange-climbing sense of each wheel (Y > 0 pushing the flange away from its
rail: -Q for a left wheel, +Q for a right one), from the filtered Y and Q where the wheel is on
the rail (0 where it is off, as the table's Q/P; the loss of contact is its own index). The
whole run is one section: its percentiles are the section's statistics (the standard's
combination of sections by test zone is not applied). On a layout with curves (:mod:`.track`)
the limits follow the radius under each wheel: (Y/Q)2m is assessed where the wheel is within
the limit's range (tangent track and R >= 250 m, option ``yq_min_radius_m``), smaller radii
only against a limit given as ``yq_limit_small_radius`` (else reported in the row's notes); the
quasi-static Q_qst and Y_qst are taken over each wheel's time on curves, where the standard
assesses them.

Limits (defaults, :data:`DEFAULTS`): (Y/Q)lim = 0.8 for R >= 250 m; (sum Y)2m,lim =
alpha (10 + 2 Q0/3) kN with Q0 the static wheel force and alpha = 1 (0.85 for freight wagons)
(standards.md [M]); Q_lim = 90 kN + Q0, not above a speed-dependent maximum (200 kN up to
160 km/h, 190 up to 200, 180 up to 250, 170 up to 300, 160 kN above) [M: recalled from UIC 518 /
EN 14363:2005, not confirmed in a public source reachable here; set ``q_lim_N`` to override];
Y_qst,lim = 60 kN and Q_qst,lim = 145 kN (quasi-static track loading, assessed in curves; on
tangent track informative) [M]. Q0 is the run's static wheel load (summary
``static_wheel_load_N``), per wheel or per wheelset.
"""

from __future__ import annotations

import math

import numpy as np

from .base import Profile, Row, governing, speed_band_value, speed_bands_text
from .processing import Butterworth, percentile, percentile_where, sliding_mean
from .run import RunData
from .track import RadiusRange, governing_by_radius, split_by_radius

STANDARD = "EN 14363:2016"

#: Options and their defaults (SI). ``q_lim_N`` None: 90 kN + Q0 capped by :data:`QMAX_CAP_N`.
DEFAULTS = {
    "cutoff_hz": 20.0,          # low-pass cut-off of every force (>= 20 Hz in the standard)
    "filter_order": 4,
    "window_m": 2.0,            # sliding mean of Y/Q and sum Y
    "step_m": 0.5,              # its sampling interval
    "percentile_high": 99.85,   # F2
    "percentile_low": 0.15,     # F1
    "percentile_quasi_static": 50.0,   # F0
    "yq_limit": 0.8,            # (Y/Q)lim, R >= 250 m [M]
    "yq_min_radius_m": 250.0,   # the radius range of (Y/Q)lim: tangent track and R >= this [M]
    "yq_limit_small_radius": None,   # (Y/Q) limit on smaller radii (None: reported only)
    "alpha": 1.0,               # sum-Y factor: 1 (0.85 freight) [M]
    "q_lim_N": None,
    "y_qst_limit_N": 60e3,      # [M]
    "q_qst_limit_N": 145e3,     # [M]
}

#: (sum Y)2m,lim = alpha (SUM_Y_CONSTANT_N + SUM_Y_Q0_FACTOR Q0) (Prud'homme limit in EN 14363 form).
SUM_Y_CONSTANT_N = 10e3
SUM_Y_Q0_FACTOR = 2.0 / 3.0
#: Q_lim = QMAX_OFFSET_N + Q0, capped by speed (km/h upper bound, N) [M].
QMAX_OFFSET_N = 90e3
QMAX_CAP_N = ((160.0, 200e3), (200.0, 190e3), (250.0, 180e3), (300.0, 170e3), (math.inf, 160e3))

#: The rule of Q_lim (the run's Q0 and speed cap go to the row's notes: a study's samples share
#: one limit source).
_Q_MAX_SOURCE = (f"90 kN + Q0, at most {speed_bands_text(QMAX_CAP_N, 1e-3, 'kN')} [M: UIC 518 / "
                 "EN 14363:2005 table, not re-read]")

_SOURCE = ("GENSYS course notes on UIC 518 / EN 14363 post-processing "
           "(gensys.se/course/UIC518_tests.html) [V]; statistics without the filter's settling "
           "time at each end")


def sum_y_limit_N(q0_N: np.ndarray | float, alpha: float) -> np.ndarray | float:
    """(sum Y)2m,lim = alpha (10 kN + 2 Q0 / 3), Q0 the static wheel force (N)."""
    return alpha * (SUM_Y_CONSTANT_N + SUM_Y_Q0_FACTOR * np.asarray(q0_N, dtype=float))


def q_max_cap_N(speed_kmh: float) -> float:
    """The speed's maximum of Q_lim (:data:`QMAX_CAP_N`)."""
    return speed_band_value(QMAX_CAP_N, speed_kmh)


def q_max_limit_N(q0_N: np.ndarray | float, speed_kmh: float) -> np.ndarray | float:
    """Q_lim = 90 kN + Q0, not above the speed's maximum (:data:`QMAX_CAP_N`)."""
    return np.minimum(QMAX_OFFSET_N + np.asarray(q0_N, dtype=float), q_max_cap_N(speed_kmh))


def force_filter(options) -> Butterworth:
    return Butterworth("lowpass", float(options["cutoff_hz"]), int(options["filter_order"]))


def evaluate(run: RunData, options) -> list[Row]:
    filt = force_filter(options)
    window, step = float(options["window_m"]), float(options["step_m"])
    hi, lo, mid = (float(options[k]) for k in ("percentile_high", "percentile_low",
                                               "percentile_quasi_static"))
    keep = filt.interior(run.table.shape[0], run.dt_s)     # without the filter's start-up
    x = run.x_m[keep]
    P = run.filtered(filt, "P_N")[keep]
    Y = (run.filtered(filt, "Q_N") * run.wheel_side_sign)[keep]     # climbing sense
    on = run.in_contact[keep] & (P > 0.0)
    yq = np.where(on, Y / np.where(on, P, 1.0), 0.0)
    rows = []

    centres, yq2m = sliding_mean(x, yq, window, step)
    valid = RadiusRange(float(options["yq_min_radius_m"]), inclusive=True)
    split = split_by_radius(run.wheel_radius_m(centres), yq2m, valid, hi)
    i, v, lim, where = governing_by_radius(split, float(options["yq_limit"]),
                                           options["yq_limit_small_radius"], run.wheel_labels,
                                           valid)
    rows.append(Row(
        "running safety, assessment quantity (Y/Q)2m (flange climbing)", "Y_Q_2m", "1", "wheel",
        run.wheel_labels[i], v, lim,
        f"(Y/Q)lim = {float(options['yq_limit']):g} for R >= {valid.min_radius_m:g} m "
        "(standards.md) [M]",
        category="limit" if np.isfinite(lim) else "info",
        raw_index="max_derailment_coefficient", raw_value=run.raw("max_derailment_coefficient"),
        window_m=window, step_m=step, statistic=f"F2 = {hi:g} % percentile",
        notes=("; ".join(filter(None, [where, "Y/Q in the flange-climbing sense from the "
                                       "filtered forces", _SOURCE]))),
    ).with_filter(filt))

    H = run.filtered(filt, "H_N")[keep]
    _, h2m = sliding_mean(x, H, window, step)
    f12 = np.maximum(np.abs(np.atleast_1d(percentile(h2m, hi))),
                     np.abs(np.atleast_1d(percentile(h2m, lo))))
    q0_ws = run.static_wheel_load_N.mean(axis=1)
    i, v, lim = governing(f12, sum_y_limit_N(q0_ws, float(options["alpha"])), run.wheelsets)
    rows.append(Row(
        "running safety, assessment quantity (sum Y)2m (track shift force)", "sum_Y_2m_N", "N",
        "wheelset", run.wheelsets[i], v, lim,
        f"alpha (10 kN + 2 Q0/3), alpha = {float(options['alpha']):g}, Q0 the static wheel "
        "force of the wheelset (standards.md) [M]",
        raw_index="max_lateral_wheelset_force_N", raw_value=run.raw("max_lateral_wheelset_force_N"),
        window_m=window, step_m=step, statistic=f"max(|F1|, |F2|), F1 = {lo:g} %, F2 = {hi:g} %",
        notes=(f"Q0 = {q0_ws[i]:.0f} N; sum Y = Y_left + Y_right (the table's H); " + _SOURCE),
    ).with_filter(filt))

    q0 = run.wheel_static_N
    if options["q_lim_N"] is None:
        q_lim = q_max_limit_N(q0, run.speed_kmh)
        q_src = _Q_MAX_SOURCE
        q_cap = f", at most {q_max_cap_N(run.speed_kmh) / 1e3:g} kN at {run.speed_kmh:g} km/h; "
    else:
        q_lim = np.full(q0.shape, float(options["q_lim_N"]))
        q_src, q_cap = "configured (option q_lim_N)", None
    qmax = np.atleast_1d(percentile(P, hi))
    i, v, lim = governing(qmax, q_lim, run.wheel_labels)
    q_note = "" if q_cap is None else f"Q0 = {q0[i]:.0f} N{q_cap}"
    rows.append(Row(
        "track loading, assessment quantity Q (maximum vertical wheel force)", "Q_max_N", "N",
        "wheel", run.wheel_labels[i], v, lim, q_src,
        raw_index="max_wheel_vertical_force_N", raw_value=run.raw("max_wheel_vertical_force_N"),
        statistic=f"F2 = {hi:g} % percentile", notes=q_note + _SOURCE,
    ).with_filter(filt))

    # quasi-static values: over each wheel's time on curves where the run has any, else the run
    raw_on_curve, curve_note = _curve_samples(run)
    on_curve = None if raw_on_curve is None else raw_on_curve[keep]
    if on_curve is not None and not on_curve.any():
        on_curve, curve_note = None, ("no wheel reaches the layout's curves within the assessed "
                                      "part of the run: evaluated over the whole run")
    if on_curve is None:
        on_curve, raw_on_curve = np.ones(P.shape, bool), np.ones(run.P_N.shape, bool)
    qqst = percentile_where(P, on_curve, mid)
    i, v, lim = governing(qqst, float(options["q_qst_limit_N"]), run.wheel_labels)
    rows.append(Row(
        "track loading, assessment quantity Q_qst (quasi-static vertical wheel force)",
        "Q_qst_N", "N", "wheel", run.wheel_labels[i], v, lim,
        f"Q_qst,lim = {lim / 1e3:g} kN (assessed in curves; informative on tangent track) [M]",
        raw_value=float(np.nanmax(percentile_where(run.P_N, raw_on_curve, mid))),
        statistic=f"F0 = {mid:g} % percentile",
        notes="; ".join(filter(None, [curve_note, "raw_value: the same percentile of the "
                                      "unfiltered forces", _SOURCE])),
    ).with_filter(filt))

    yqst = np.abs(percentile_where(Y, on_curve, mid))
    i, v, lim = governing(yqst, float(options["y_qst_limit_N"]), run.wheel_labels)
    rows.append(Row(
        "track loading, assessment quantity Y_qst (quasi-static lateral wheel force)",
        "Y_qst_N", "N", "wheel", run.wheel_labels[i], v, lim,
        f"Y_qst,lim = {lim / 1e3:g} kN (assessed in curves; informative on tangent track) [M]",
        raw_value=float(np.nanmax(np.abs(percentile_where(run.Q_N, raw_on_curve, mid)))),
        statistic=f"|F0|, F0 = {mid:g} % percentile",
        notes="; ".join(filter(None, [curve_note, "raw_value: the same percentile of the "
                                      "unfiltered forces", _SOURCE])),
    ).with_filter(filt))
    return rows


def _curve_samples(run: RunData) -> tuple[np.ndarray | None, str]:
    """(n, n_wheels) whether each wheel is on a curve (clothoid or arc) at each output step, and
    the note saying so; (None, "") where the case has no curves."""
    if not run.has_curves:
        return None, ""
    radius = run.wheel_radius_m(run.x_m)
    on_curve = np.isfinite(radius)
    smallest = f"R {np.min(radius):.0f} m and above, " if on_curve.any() else ""
    return on_curve, f"evaluated over each wheel's time on curves ({smallest}clothoids included)"


PROFILE = Profile("en14363", STANDARD, "running safety and track loading", DEFAULTS, evaluate)
