"""GB/T 5599-2019: running safety and ride quality of rolling stock as the standard evaluates them.

Clauses (titles from the standard's public table of contents, chinesestandard.net preview of
GB/T 5599-2019 [V]): 9 "Assessment index", 10 "Assessment and data processing methods",
Appendix D "Statistical processing method of operational stability and operational quality
data", Appendix E "Measurement and data processing method of stability index W" (Sperling).

Indices and limits (docs/reference/standards.md, [V] = read in a public post-processing script
for a commercial code, [M] = not confirmed): derailment coefficient Q/P <= 0.8 (tangent and
R > 400 m) [V]; wheel unloading ratio (P0 - P)/P0 <= 0.65 up to 160 km/h [V], 0.8 above [M];
lateral wheelset force H <= 15 + P0/3 kN with P0 the static **axle** load in kN [V] (as the
study's :class:`ttbpipe.stats.limits.StaticLoadLimit` does for the raw index);
car-body acceleration 2.5 m/s^2 as mean + 2.2 sigma of the 2 m peaks of the 0.4-40 Hz band [V];
Sperling index W from 5 s windows, grade "excellent" below 2.5, "good" 2.75, "pass" 3.0 [M], the
5 s window confirmed by Zhang, Zhou et al., J. Tongji Univ. 2023,
doi:10.11908/j.issn.0253-374x.22146 (GB/T 5599-2019 shortened the 18-20 s of the 1985 edition
to UIC 513's 5 s) [V]. The limit values that the study also uses come from
:func:`ttbpipe.stats.limits.default_limits` (their one home); the car-body 2.5 m/s^2 lives here.

Processing: the wheel forces are low-passed (Butterworth, 20 Hz, order 4, zero phase) [M: the
standard's force filter not re-read; the same cut-off as EN 14363]; the ratios are formed from
the filtered forces (Q/P where the wheel is on the rail, 0 off it; unloading 1 off it, as the
table), without the filter's settling time at either end
(:meth:`~.processing.Butterworth.interior`); the data are "resampled at 2 m": each 2 m piece of
the run is represented by its largest value (:func:`~.processing.segment_maxima`, our reading of
the resampling: a peak is never lost between grid points) [M]; the statistic is the 99.85th
percentile of the pieces. On a layout with curves (:mod:`.track`) the derailment coefficient is
assessed per wheel over the pieces (by their centre) where the wheel is on tangent track or
R > 400 m (option ``derailment_min_radius_m``), smaller radii only against a limit given as
``derailment_limit_small_radius`` (else reported in the row's notes). Car-body accelerations:
Butterworth band-pass 0.4-40 Hz (order 4, zero phase [M: order]), largest |a| of each 2 m
piece, mean + 2.2 sigma of those peaks. Sperling: :func:`ttbpipe.vehicle.comfort.sperling_index`
(5 s windows, the largest window value [M: the standard's statistic over the windows], over the
floor points of each car).
"""

from __future__ import annotations

import logging

import numpy as np

from ..stats.limits import default_limits
from ..vehicle.comfort import BAND_HZ as SPERLING_BAND_HZ
from ..vehicle.comfort import WINDOW_S as SPERLING_WINDOW_S
from ..vehicle.comfort import sperling_index
from .base import Profile, Row, governing
from .processing import Butterworth, mean_plus_k_sigma, percentile, segment_maxima
from .run import RunData
from .track import RadiusRange, governing_by_radius, split_by_radius

log = logging.getLogger(__name__)

STANDARD = "GB/T 5599-2019"

#: Car-body acceleration limit (m/s^2) of the statistical value mean + 2.2 sigma (standards.md,
#: GB/T 5599-2019 as implemented by a public post-processing script [V]).
CARBODY_ACC_LIMIT_M_S2 = 2.5

DEFAULTS = {
    "cutoff_hz": 20.0,              # force low-pass [M]
    "filter_order": 4,
    "segment_m": 2.0,               # "resampled at 2 m"
    "percentile": 99.85,
    # Q/P 0.8 holds on tangent track and R > 400 m [V]; smaller radii against this limit when
    # given (None: reported in the row's notes only)
    "derailment_min_radius_m": 400.0,
    "derailment_limit_small_radius": None,
    "carbody_band_hz": (0.4, 40.0),
    "carbody_k_sigma": 2.2,
    "carbody_limit_m_s2": CARBODY_ACC_LIMIT_M_S2,
    "sperling_window_s": SPERLING_WINDOW_S,
}

_SCRIPT = "standards.md: GB/T 5599-2019 as implemented by a public post-processing script"


def _study_limits() -> dict:
    return {lim.name: lim for lim in default_limits()}


def force_filter(options) -> Butterworth:
    """The wheel forces' low-pass."""
    return Butterworth("lowpass", float(options["cutoff_hz"]), int(options["filter_order"]))


def carbody_filter(options) -> Butterworth:
    """The car-body accelerations' band-pass."""
    return Butterworth("bandpass", tuple(float(f) for f in options["carbody_band_hz"]),
                       int(options["filter_order"]))


def evaluate(run: RunData, options) -> list[Row]:
    limits = _study_limits()
    filt = force_filter(options)
    seg, pct = float(options["segment_m"]), float(options["percentile"])
    dt = run.dt_s
    keep = filt.interior(run.table.shape[0], dt)     # without the filter's start-up
    x = run.x_m[keep]
    P = run.filtered(filt, "P_N")[keep]
    Q = run.filtered(filt, "Q_N")[keep]
    on = run.in_contact[keep] & (P > 0.0)
    stat = f"{pct:g} % percentile of the {seg:g} m piece maxima"
    rows = []

    qp = np.where(on, np.abs(Q) / np.where(on, P, 1.0), 0.0)
    starts, pieces = segment_maxima(x, qp, seg)
    valid = RadiusRange(float(options["derailment_min_radius_m"]), inclusive=False)
    split = split_by_radius(run.wheel_radius_m(starts + 0.5 * seg), pieces, valid, pct)
    lim_qp = limits["derailment_coefficient"]
    i, v, lim, where = governing_by_radius(split, lim_qp.threshold,
                                           options["derailment_limit_small_radius"],
                                           run.wheel_labels, valid)
    rows.append(Row(
        "9 (assessment index: derailment coefficient), 10 and Appendix D (data processing)",
        "derailment_coefficient_Q_P", "1", "wheel", run.wheel_labels[i], v, lim, lim_qp.source,
        category="limit" if np.isfinite(lim) else "info",
        raw_index="max_derailment_coefficient", raw_value=run.raw("max_derailment_coefficient"),
        window_m=seg, statistic=stat,
        notes="; ".join(filter(None, [where, "|Q|/P from the filtered forces, 0 off the rail"])),
    ).with_filter(filt))

    p0 = run.wheel_static_N
    unloading = np.where(run.in_contact[keep], (p0 - P) / p0, 1.0)
    value = np.atleast_1d(percentile(segment_maxima(x, unloading, seg)[1], pct))
    lim_u = limits["wheel_unloading_ratio"]
    u_lim = float(lim_u.value_at(run.speed_kmh))
    i, v, lim = governing(value, u_lim, run.wheel_labels)
    rows.append(Row(
        "9 (assessment index: wheel unloading ratio), 10 and Appendix D (data processing)",
        "wheel_unloading_ratio", "1", "wheel", run.wheel_labels[i], v, lim,
        lim_u.source,
        raw_index="max_wheel_unloading_ratio", raw_value=run.raw("max_wheel_unloading_ratio"),
        window_m=seg, statistic=stat,
        notes=(f"{lim:g} at {run.speed_kmh:g} km/h; (P0 - P)/P0 from the filtered P, P0 the "
               "static wheel load; 1 off the rail"),
    ).with_filter(filt))

    H = np.abs(run.filtered(filt, "H_N")[keep])
    value = np.atleast_1d(percentile(segment_maxima(x, H, seg)[1], pct))
    lim_h = limits["lateral_wheelset_force"]
    axle = run.static_wheel_load_N.sum(axis=1)
    h_lim = lim_h.constant + axle / lim_h.divisor
    i, v, lim = governing(value, h_lim, run.wheelsets)
    rows.append(Row(
        "9 (assessment index: lateral wheelset force), 10 and Appendix D (data processing)",
        "lateral_wheelset_force_H_N", "N", "wheelset", run.wheelsets[i], v, lim,
        f"{lim_h.constant / 1e3:g} kN + P0/{lim_h.divisor:g}, P0 the static axle load of the "
        f"wheelset ({lim_h.source})",
        raw_index="max_lateral_wheelset_force_N", raw_value=run.raw("max_lateral_wheelset_force_N"),
        window_m=seg, statistic=stat,
        notes=f"P0 = {axle[i]:.0f} N; H = Q_left + Q_right from the filtered forces",
    ).with_filter(filt))

    band = carbody_filter(options)
    k = float(options["carbody_k_sigma"])
    for direction, axis in (("vertical", "az"), ("lateral", "ay")):
        labels, acc = run.carbody(axis)
        inner = band.interior(acc.shape[0], dt)
        peaks = segment_maxima(run.x_m[inner], np.abs(band.apply(acc, dt)[inner]), seg)[1]
        value = np.atleast_1d(mean_plus_k_sigma(peaks, k))
        i, v, lim = governing(value, float(options["carbody_limit_m_s2"]), labels)
        rows.append(Row(
            f"9 (assessment index: car-body {direction} acceleration), Appendix D (statistics)",
            f"carbody_{direction}_acc_m_s2", "m/s^2", "car", labels[i], v, lim,
            f"{lim:g} m/s^2 ({_SCRIPT}) [V]",
            raw_index=f"max_carbody_{direction}_acc_m_s2",
            raw_value=run.raw(f"max_carbody_{direction}_acc_m_s2"),
            window_m=seg, statistic=f"mean + {k:g} sigma of the {seg:g} m piece peaks of |a|",
            notes="floor above the bogie pivots and at the centre",
        ).with_filter(band))

    window = float(options["sperling_window_s"])
    record_s = run.table.shape[0] * dt
    short = record_s < window
    if short:
        log.warning("GB/T 5599 Sperling: the %.2f s record is shorter than the %.1f s window; "
                    "evaluated as one window", record_s, window)
    for direction, axis in (("vertical", "az"), ("lateral", "ay")):
        labels, acc = run.carbody(axis)
        value = np.array([sperling_index(acc[:, j], dt, direction, window_s=window, quiet=True)[0]
                          for j in range(acc.shape[1])])
        passing = limits[f"sperling_{direction}_pass"]
        i, v, lim = governing(value, passing.threshold, labels)
        grades = ", ".join(f"{g} {limits[f'sperling_{direction}_{g}'].threshold:g}"
                           for g in ("excellent", "good"))
        rows.append(Row(
            "Appendix E (stability index W, Sperling)", f"sperling_{direction}", "1", "car",
            labels[i], v, lim, f"{passing.source}; grades: {grades}",
            raw_index=f"sperling_{direction}", raw_value=run.raw(f"sperling_{direction}"),
            filter=(f"Sperling weighting {SPERLING_BAND_HZ[0]:g}-{SPERLING_BAND_HZ[1]:g} Hz "
                    "(ttbpipe.vehicle.comfort)"),
            filter_low_hz=SPERLING_BAND_HZ[0], filter_high_hz=SPERLING_BAND_HZ[1],
            statistic=f"largest {window:g} s window",
            notes=(f"record {record_s:.2f} s shorter than one window: one window" if short
                   else f"record {record_s:.2f} s"),
        ))
    return rows


PROFILE = Profile("gb5599", STANDARD, "running safety and ride quality", DEFAULTS, evaluate)
