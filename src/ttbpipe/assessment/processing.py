"""Signal processing shared by the assessment profiles: filters, distance windows, statistics.

Every profile post-processes the output histories of a run (uniform in time, ``time_s``) the
way its standard prescribes; the steps are these, each a small function with its closed form:

* :class:`Butterworth`: zero-phase Butterworth low-, high- or band-pass (``scipy.signal.butter``
  in second-order sections, applied forward and backward with ``sosfiltfilt``). The *order* is
  that of the designed filter; the forward-backward pass squares its magnitude, so the applied
  gain is ``|H(f)|^2`` (:meth:`Butterworth.power_gain`), -6 dB at the cut-off, with no phase
  shift. A digital Butterworth designed at ``fs`` (bilinear transform with pre-warping) has
  ``|H(f)|^2 = 1 / (1 + (tan(pi f/fs) / tan(pi fc/fs))^(2N))`` (low-pass; Oppenheim & Schafer,
  Discrete-Time Signal Processing, 3rd ed., section 7.3), which ``tests/test_assessment_processing.py``
  checks. A filtered record starts and ends with the filter's response to its truncation; the
  statistics leave out :attr:`Butterworth.settling_s` (three periods of the upper cut-off) at each
  end (:meth:`Butterworth.interior`). Low-passes pad the record with scipy's default (odd
  extension, which keeps a trend such as a static load); band- and high-passes with its mirror
  image over three periods of the lower cut-off (at most the record), which adds no step in the
  mean for the slow high-pass edge to respond to.
* Distance windows. Every wheel moves at the train speed V, so a window of length d along the
  track is a window of d/V in time: the histories are put on the run's position axis
  (``x_lead_m``, the leading wheelset; the other wheels differ by a constant) and
  :func:`sliding_mean` averages over a distance window with a step (EN 14363: 2 m, 0.5 m),
  :func:`resample` interpolates onto a distance grid and :func:`segment_maxima` takes the largest
  value of each segment of a given length (GB/T 5599 statistics on 2 m pieces).
  The sliding mean is the exact mean of the linear interpolant of the samples over each window,
  so a sinusoid of wavelength lambda is scaled by ``sin(pi L/lambda) / (pi L/lambda)``
  (:func:`sliding_mean_gain`), up to the interpolation error ``(2 pi dx/lambda)^2 / 12``.
* :func:`percentile`: numpy's linear-interpolation percentile (``method="linear"``), the
  F1 = 0.15 %, F0 = 50 % and F2 = 99.85 % of EN 14363 and the 99.85 % of GB/T 5599.
* :func:`mean_plus_k_sigma` and :func:`window_rms`: window statistics (GB/T 5599 car-body
  accelerations, EN 12299 5 s r.m.s. values).

All inputs and outputs are SI (m, s, Hz); arrays may be 1-D (one signal) or 2-D with the signals
in columns (the samples along axis 0).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..filters import butterworth_sos

log = logging.getLogger(__name__)

#: A cut-off at or above this fraction of the Nyquist frequency cannot be designed; the signal
#: is passed unfiltered (there is no content above the Nyquist frequency to remove).
MAX_CUTOFF_FRACTION_OF_NYQUIST = 0.95


@dataclass(frozen=True)
class Butterworth:
    """A zero-phase Butterworth filter: ``kind`` 'lowpass' | 'highpass' | 'bandpass', cut-off(s)
    in Hz (a (low, high) pair for 'bandpass'), ``order`` of the designed filter (applied forward
    and backward, so the magnitude is squared: :meth:`power_gain`)."""

    kind: str
    cutoff_hz: float | tuple[float, float]
    order: int = 4

    def __post_init__(self):
        if self.kind not in ("lowpass", "highpass", "bandpass"):
            raise ValueError(f"Butterworth kind {self.kind!r}: expected lowpass | highpass | "
                             "bandpass")
        cut = np.atleast_1d(np.asarray(self.cutoff_hz, dtype=float))
        if cut.size != (2 if self.kind == "bandpass" else 1) or np.any(cut <= 0):
            raise ValueError(f"Butterworth {self.kind}: cut-off {self.cutoff_hz!r} must be "
                             f"{'a (low, high) pair' if self.kind == 'bandpass' else 'one'} "
                             "positive frequency (Hz)")
        if self.kind == "bandpass" and not cut[0] < cut[1]:
            raise ValueError(f"Butterworth bandpass: low {cut[0]} Hz must be below high {cut[1]} Hz")
        if int(self.order) < 1:
            raise ValueError(f"Butterworth order {self.order} must be at least 1")

    @property
    def low_hz(self) -> float:
        """Lower edge of the pass band (0 for a low-pass)."""
        cut = np.atleast_1d(self.cutoff_hz)
        return 0.0 if self.kind == "lowpass" else float(cut[0])

    @property
    def high_hz(self) -> float:
        """Upper edge of the pass band (inf for a high-pass)."""
        cut = np.atleast_1d(self.cutoff_hz)
        return np.inf if self.kind == "highpass" else float(cut[-1])

    def describe(self) -> str:
        band = {"lowpass": f"low-pass {self.high_hz:g} Hz", "highpass": f"high-pass {self.low_hz:g} Hz",
                "bandpass": f"band-pass {self.low_hz:g}-{self.high_hz:g} Hz"}[self.kind]
        return f"Butterworth {band}, order {self.order}, zero phase (forward-backward)"

    def _design(self, fs_hz: float):
        """(sos, applied): the second-order sections at fs, or None where a cut-off is too close
        to the Nyquist frequency to design (that edge is then dropped: nothing lies above it)."""
        from scipy import signal

        nyq = 0.5 * fs_hz
        top = MAX_CUTOFF_FRACTION_OF_NYQUIST * nyq
        kind, cut = self.kind, self.cutoff_hz
        if kind in ("lowpass", "bandpass") and self.high_hz >= top:
            if kind == "lowpass":
                return None
            kind, cut = "highpass", self.low_hz
        if kind == "highpass" and self.low_hz >= top:
            raise ValueError(f"{self.describe()}: the high-pass edge {self.low_hz:g} Hz is above "
                             f"0.95 x the Nyquist frequency {nyq:g} Hz of the history")
        cut = tuple(map(float, cut)) if np.ndim(cut) else float(cut)   # hashable: a cached design
        return butterworth_sos(int(self.order), cut, kind, float(fs_hz))

    def apply(self, values: np.ndarray, dt_s: float) -> np.ndarray:
        """The filtered signal(s), same shape as ``values`` (samples along axis 0)."""
        from scipy import signal

        x = np.asarray(values, dtype=float)
        sos = self._design(1.0 / dt_s)
        if sos is None:
            log.info("%s: cut-off at or above 0.95 x Nyquist (%g Hz); passed unfiltered",
                     self.describe(), 0.5 / dt_s)
            return x.copy()
        if self.kind == "lowpass":
            return signal.sosfiltfilt(sos, x, axis=0)
        # a high-pass edge responds slowly: pad over three of its periods, with the mirror image
        # (no step in the mean at the ends, which the odd extension of scipy's default makes)
        padlen = min(x.shape[0] - 1, int(np.ceil(3.0 / (self.low_hz * dt_s))))
        return signal.sosfiltfilt(sos, x, axis=0, padtype="even", padlen=padlen)

    @property
    def settling_s(self) -> float:
        """Start-up time left out of the statistics at each end of a filtered record: three
        periods of the upper cut-off (the fastest edge transient; a high-pass: of its cut-off).
        An 80 Hz step through the 20 Hz low-pass of order 4 decays to 1e-4 within it."""
        return 3.0 / (self.high_hz if np.isfinite(self.high_hz) else self.low_hz)

    def interior(self, n: int, dt_s: float) -> slice:
        """The samples of an n-sample record outside :attr:`settling_s` at either end."""
        k = int(np.ceil(self.settling_s / dt_s - 1e-9))
        if n - 2 * k < 2:
            raise ValueError(f"{self.describe()}: a {n * dt_s:.3f} s record is shorter than twice "
                             f"the filter's settling time {self.settling_s:.3f} s")
        return slice(k, n - k)

    def power_gain(self, freq_hz: np.ndarray, dt_s: float) -> np.ndarray:
        """Gain |H(f)|^2 of the zero-phase filter at ``freq_hz`` (from the designed sections)."""
        from scipy import signal

        f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        sos = self._design(1.0 / dt_s)
        if sos is None:
            return np.ones_like(f)
        _, h = signal.freqz_sos(sos, worN=f, fs=1.0 / dt_s)
        return np.abs(h) ** 2


def sample_interval(time_s: np.ndarray) -> float:
    """The output interval (s) of a uniformly sampled history; ValueError if it is not uniform
    (within 1e-6 relative) or has fewer than two samples."""
    t = np.asarray(time_s, dtype=float)
    if t.size < 2:
        raise ValueError("a history needs at least two samples")
    d = np.diff(t)
    dt = float(np.median(d))
    if dt <= 0 or np.max(np.abs(d - dt)) > 1e-6 * dt + 1e-12:
        raise ValueError(f"the history is not uniformly sampled in time (median step {dt:g} s, "
                         f"steps {d.min():g} to {d.max():g} s)")
    return dt


def _linear_integral(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Integral from x[0] to ``at`` of the piecewise-linear interpolant of (x, y), exact
    (quadratic within each interval); y may be 2-D with signals in columns."""
    dx = np.diff(x)
    y2 = y.reshape(y.shape[0], -1)
    cum = np.vstack([np.zeros((1, y2.shape[1])),
                     np.cumsum(0.5 * (y2[1:] + y2[:-1]) * dx[:, None], axis=0)])
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    s = (at - x[i])[:, None]
    slope = (y2[i + 1] - y2[i]) / dx[i][:, None]
    out = cum[i] + y2[i] * s + 0.5 * slope * s * s
    return out.reshape((at.size,) + y.shape[1:])


def sliding_mean(x_m: np.ndarray, values: np.ndarray, window_m: float,
                 step_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Means over windows of ``window_m`` along the increasing position ``x_m``, every ``step_m``:
    (window centres, means). The first window starts at x_m[0]; only complete windows are used.
    Each mean is the exact mean of the linear interpolant of the samples over the window."""
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(values, dtype=float)
    if window_m <= 0 or step_m <= 0:
        raise ValueError(f"sliding mean: window {window_m} m and step {step_m} m must be positive")
    if np.any(np.diff(x) <= 0):
        raise ValueError("sliding mean: the position axis must increase strictly")
    n = int(np.floor((x[-1] - x[0] - window_m) / step_m + 1e-9)) + 1
    if n < 1:
        raise ValueError(f"sliding mean: a {window_m} m window does not fit in the "
                         f"{x[-1] - x[0]:.3f} m record")
    centres = x[0] + 0.5 * window_m + step_m * np.arange(n)
    upper = _linear_integral(x, y, centres + 0.5 * window_m)
    lower = _linear_integral(x, y, centres - 0.5 * window_m)
    return centres, (upper - lower) / window_m


def sliding_mean_gain(window_m: float, wavelength_m: float) -> float:
    """Amplitude factor of a sliding mean over ``window_m`` on a sinusoid of ``wavelength_m``:
    sin(pi L/lambda) / (pi L/lambda) (the mean of a sinusoid over one window)."""
    return float(np.sinc(window_m / wavelength_m))


def resample(x_m: np.ndarray, values: np.ndarray, step_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation onto the grid x_m[0], x_m[0] + step, ... <= x_m[-1]."""
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(values, dtype=float)
    grid = x[0] + step_m * np.arange(int(np.floor((x[-1] - x[0]) / step_m + 1e-9)) + 1)
    y2 = y.reshape(y.shape[0], -1)
    out = np.column_stack([np.interp(grid, x, y2[:, j]) for j in range(y2.shape[1])])
    return grid, out.reshape((grid.size,) + y.shape[1:])


def segment_maxima(x_m: np.ndarray, values: np.ndarray,
                   length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Largest value of each complete segment [x0 + k L, x0 + (k+1) L): (segment starts, maxima).
    Pass ``np.abs(values)`` for the largest magnitude."""
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(values, dtype=float)
    n = int(np.floor((x[-1] - x[0]) / length_m + 1e-9))
    if n < 1:
        raise ValueError(f"segments of {length_m} m do not fit in the {x[-1] - x[0]:.3f} m record")
    starts = x[0] + length_m * np.arange(n)
    bounds = np.searchsorted(x, np.append(starts, starts[-1] + length_m) - 1e-9 * length_m)
    if np.any(np.diff(bounds) < 1):
        raise ValueError(f"segments of {length_m} m are shorter than the sampling interval "
                         f"{float(np.median(np.diff(x))):.3g} m")
    maxima = np.maximum.reduceat(y[:bounds[-1]], bounds[:-1], axis=0)
    return starts, maxima


def percentile(values: np.ndarray, percent: float) -> np.ndarray | float:
    """The ``percent`` percentile along axis 0 (numpy, linear interpolation between order
    statistics)."""
    out = np.percentile(np.asarray(values, dtype=float), percent, axis=0, method="linear")
    return float(out) if np.ndim(out) == 0 else out


def percentile_where(values: np.ndarray, mask: np.ndarray, percent: float) -> np.ndarray:
    """The ``percent`` percentile of each column of ``values`` (n, k) over its rows where
    ``mask`` (n, k) holds, NaN for a column where it holds nowhere; :func:`percentile` itself
    where it holds everywhere."""
    v = np.asarray(values, dtype=float).reshape(len(values), -1)
    m = np.asarray(mask, dtype=bool).reshape(v.shape)
    if m.all():
        return np.atleast_1d(percentile(v, percent))
    return np.array([np.percentile(v[m[:, j], j], percent, method="linear") if m[:, j].any()
                     else np.nan for j in range(v.shape[1])])


def mean_plus_k_sigma(values: np.ndarray, k: float) -> np.ndarray | float:
    """mean + k x standard deviation (population, ddof = 0) along axis 0."""
    v = np.asarray(values, dtype=float)
    out = v.mean(axis=0) + k * v.std(axis=0)
    return float(out) if np.ndim(out) == 0 else out


def window_rms(values: np.ndarray, dt_s: float, window_s: float) -> np.ndarray:
    """R.m.s. of consecutive, non-overlapping windows of ``window_s`` (a trailing partial window
    is not used); a record shorter than one window is one window (the caller says so)."""
    v = np.asarray(values, dtype=float)
    per = int(round(window_s / dt_s))
    if v.shape[0] < per:
        return np.sqrt(np.mean(v ** 2, axis=0, keepdims=True))
    n = v.shape[0] // per
    w = v[:n * per].reshape((n, per) + v.shape[1:])
    return np.sqrt(np.mean(w ** 2, axis=1))
