"""Sperling ride index (Wz) from car-body acceleration histories.

Formula (physics.md section 4, [V]): for each spectral component of amplitude A_i (m/s^2, peak)
at frequency f_i in 0.5-40 Hz,

    W_i = 3.57 [ (A_i^3 / f_i) F(f_i) ]^0.1,       W = ( sum_i W_i^10 )^0.1

with the frequency weighting (F = 400/f^2, NOT 400/f, a common error: physics.md section 7 item 10)

    vertical: F = 0.325 f^2 (0.5-5.9 Hz), 400/f^2 (5.9-20 Hz), 1 (> 20 Hz)
    lateral:  F = 0.8 f^2   (0.5-5.4 Hz), 650/f^2 (5.4-26 Hz), 1 (> 26 Hz).

3.57 is 0.896 (A in cm/s^2) converted to m/s^2: 0.896 * 100^0.3 = 3.57. The record is cut into
5 s windows; each window's amplitude spectrum is the one-sided DFT amplitude 2|X_k|/N
(rectangular window, so a sinusoid on a bin is measured exactly); the index of the record is the
largest window value (conservative; the per-window values are returned too).
"""

from __future__ import annotations

import logging

import numpy as np

log = logging.getLogger(__name__)

SPERLING_CONSTANT = 3.57   # for A in m/s^2
BAND_HZ = (0.5, 40.0)
WINDOW_S = 5.0


def sperling_weighting(freq_hz: np.ndarray, direction: str) -> np.ndarray:
    """Frequency weighting F(f) of the Sperling index ('vertical' or 'lateral')."""
    f = np.asarray(freq_hz, dtype=float)
    if direction == "vertical":
        f1, c1, f2, c2 = 5.9, 0.325, 20.0, 400.0
    elif direction == "lateral":
        f1, c1, f2, c2 = 5.4, 0.8, 26.0, 650.0
    else:
        raise ValueError(f"direction must be 'vertical' or 'lateral', got {direction!r}")
    out = np.ones_like(f)
    low = f < f1
    mid = (f >= f1) & (f <= f2)
    out[low] = c1 * f[low] ** 2
    with np.errstate(divide="ignore"):
        out[mid] = c2 / f[mid] ** 2
    return out


def sperling_window(accel_ms2: np.ndarray, dt_s: float, direction: str) -> float:
    """Sperling index of one window of acceleration (m/s^2) sampled at dt_s."""
    a = np.asarray(accel_ms2, dtype=float)
    n = a.size
    spectrum = np.fft.rfft(a - a.mean())
    freq = np.fft.rfftfreq(n, dt_s)
    amp = 2.0 * np.abs(spectrum) / n
    band = (freq >= BAND_HZ[0]) & (freq <= BAND_HZ[1])
    if not np.any(band):
        raise ValueError(f"no DFT bin in {BAND_HZ} Hz: window {n * dt_s:.3f} s at dt {dt_s} s")
    f, amp = freq[band], amp[band]
    total = np.sum(amp ** 3 / f * sperling_weighting(f, direction))
    return float(SPERLING_CONSTANT * total ** 0.1)


def sperling_index(accel_ms2: np.ndarray, dt_s: float, direction: str,
                   window_s: float = WINDOW_S, quiet: bool = False) -> tuple[float, np.ndarray]:
    """Sperling index of a record: (largest 5 s window value, per-window values).

    A record shorter than one window is evaluated as a single window (logged unless ``quiet``;
    the caller then logs once); a trailing partial window is not used (logged at debug level).
    """
    a = np.asarray(accel_ms2, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ValueError("Sperling index: acceleration record contains NaN or inf")
    per = int(round(window_s / dt_s))
    if a.size < per:
        if not quiet:
            log.warning("Sperling index: record of %.2f s is shorter than the %.1f s window; "
                    "evaluated as one window", a.size * dt_s, window_s)
        values = np.array([sperling_window(a, dt_s, direction)])
        return float(values.max()), values
    n_win = a.size // per
    rest = a.size - n_win * per
    if rest:
        log.debug("Sperling index: trailing %.2f s (partial window) not used", rest * dt_s)
    values = np.array([sperling_window(a[i * per:(i + 1) * per], dt_s, direction) for i in range(n_win)])
    return float(values.max()), values
