"""EN 12299:2009 ride comfort: the mean comfort index N_MV (standard method) and its weightings.

Mean comfort, standard method (floor measurements): the car-body floor accelerations are
frequency weighted (Wd longitudinal and lateral, Wb vertical), their r.m.s. values taken over
consecutive 5 s windows, and the 95th percentile of those values over the evaluation period
(5 min in the standard) combined as

    N_MV = 6 sqrt( (a_XP95^Wd)^2 + (a_YP95^Wd)^2 + (a_ZP95^Wb)^2 )            (m/s^2 -> 1)

(the formula and the 5 s r.m.s. / 95th percentile as implemented by the public PyRidy
``ComfortProcessor``, ifs-rwth-aachen/PyRidy ``pyridy/processing/comfort.py`` [V: a public
implementation, not the standard's text]). Comfort scale: N_MV < 1 very comfortable, 1-2
comfortable, 2-4 medium, 4-5 uncomfortable, >= 5 very uncomfortable [M]; EN 12299 sets no limit
values, so the row is a grade (default boundary 1, "very comfortable").

Weighting filters (ISO 2631-1 form; parameters of EN 12299 as in PyRidy and in
tobias-bettinger/comfpy ``comfpy/filters.py``, two public implementations of EN 12299 [V: as
implemented there]): band limiting H_h = s^2/(s^2 + w1 s/Q1 + w1^2) and
H_l = w2^2/(s^2 + w2 s/Q1 + w2^2), Q1 = 1/sqrt(2); acceleration-velocity transition
H_t = (w4^2/w3 s + w4^2)/(s^2 + w4 s/Q4 + w4^2); upward step
H_s = K (s^2/w5^2 + s/(Q5 w5) + 1)/(s^2/w6^2 + s/(Q6 w6) + 1); w = 2 pi f.

| filter | f1 | f2 | f3 | f4 | Q4 | f5 | Q5 | f6 | Q6 | K | used for |
|---|---|---|---|---|---|---|---|---|---|---|---|
| Wb | 0.4 | 100 | 16 | 16 | 0.63 | 2.5 | 0.8 | 4 | 0.8 | 0.4 | vertical (floor) |
| Wc | 0.4 | 100 | 8 | 8 | 0.63 | - | - | - | - | 1 | seat back (complete method) |
| Wd | 0.4 | 100 | 2 | 2 | 0.63 | - | - | - | - | 1 | longitudinal, lateral |
| Wp | - | 100 | 2 | 2 | 0.63 | - | - | - | - | 1 | lateral, discrete events (no high-pass) |

(BS 6841:1987's Wb has Q4 = 0.55, Q5 = 0.9, Q6 = 0.95, as in cseats/Footfall_app_data
``bs6841bandlimit.m``; the EN 12299 implementations above use the values in the table.) The
digital filters are the bilinear transforms (``scipy.signal.bilinear_zpk``) of these analog
filters at the output rate, applied causally (``sosfilt``) as an instrument would; the r.m.s.
depends on |H| only. At 1 kHz their gain is within 0.1 % of the analog one up to 16 Hz and
0.3 % at 30 Hz (the bilinear transform's frequency warping; ``tests/test_assessment_en12299.py``).

The model's car body has no longitudinal degree of freedom, so a_XP95 = 0. The run's record
(3.5 s for the reference case) is shorter than one 5 s window and far shorter than the 5 min
of the standard: it is then evaluated as one window (logged, and said in the row's notes).
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass

import numpy as np

from .base import Profile, Row, governing
from .processing import percentile, window_rms
from .run import RunData

log = logging.getLogger(__name__)

STANDARD = "EN 12299:2009"
Q_BAND = 1.0 / math.sqrt(2.0)


@dataclass(frozen=True)
class Weighting:
    """An ISO 2631 / EN 12299 frequency weighting (module docstring); f1 None: no high-pass,
    f5 None: no upward step."""

    name: str
    f1: float | None
    f2: float
    f3: float
    f4: float
    q4: float
    f5: float | None = None
    q5: float | None = None
    f6: float | None = None
    q6: float | None = None
    k: float = 1.0

    def _sections(self):
        """Analog (numerator, denominator) polynomials in s of each section."""
        w = {n: 2 * math.pi * getattr(self, n) for n in ("f2", "f3", "f4")}
        out = []
        if self.f1 is not None:
            w1 = 2 * math.pi * self.f1
            out.append(([1.0, 0.0, 0.0], [1.0, w1 / Q_BAND, w1 * w1]))
        out.append(([w["f2"] ** 2], [1.0, w["f2"] / Q_BAND, w["f2"] ** 2]))
        out.append(([w["f4"] ** 2 / w["f3"], w["f4"] ** 2], [1.0, w["f4"] / self.q4, w["f4"] ** 2]))
        if self.f5 is not None:
            w5, w6 = 2 * math.pi * self.f5, 2 * math.pi * self.f6
            out.append(([self.k / w5 ** 2, self.k / (self.q5 * w5), self.k],
                        [1.0 / w6 ** 2, 1.0 / (self.q6 * w6), 1.0]))
        else:
            out.append(([self.k], [1.0]))
        return out

    def analog_gain(self, freq_hz: np.ndarray) -> np.ndarray:
        """|H(j 2 pi f)| of the analog weighting."""
        s = 2j * math.pi * np.asarray(freq_hz, dtype=float)
        h = np.ones_like(s)
        for num, den in self._sections():
            h = h * np.polyval(num, s) / np.polyval(den, s)
        return np.abs(h)

    def sos(self, fs_hz: float) -> np.ndarray:
        """Second-order sections of the bilinear transform at ``fs_hz``: designed once per
        weighting and sampling rate in a process (every sample of a study weights its records
        alike), a copy each call."""
        return _weighting_design(self, float(fs_hz)).copy()

    def digital_gain(self, freq_hz: np.ndarray, dt_s: float) -> np.ndarray:
        from scipy import signal

        _, h = signal.freqz_sos(self.sos(1.0 / dt_s), worN=np.asarray(freq_hz, float), fs=1.0 / dt_s)
        return np.abs(h)

    def apply(self, values: np.ndarray, dt_s: float) -> np.ndarray:
        """The weighted signal(s), causal, samples along axis 0."""
        from scipy import signal

        return signal.sosfilt(self.sos(1.0 / dt_s), np.asarray(values, dtype=float), axis=0)


@functools.lru_cache(maxsize=32)
def _weighting_design(weighting: Weighting, fs_hz: float) -> np.ndarray:
    from scipy import signal

    z, p, k = [], [], 1.0
    for num, den in weighting._sections():
        zz, pp, kk = signal.tf2zpk(num, den)
        z += list(zz)
        p += list(pp)
        k *= kk
    zd, pd_, kd = signal.bilinear_zpk(np.array(z), np.array(p), k, fs_hz)
    return signal.zpk2sos(zd, pd_, kd)


WB = Weighting("Wb", 0.4, 100.0, 16.0, 16.0, 0.63, 2.5, 0.8, 4.0, 0.8, 0.4)
WC = Weighting("Wc", 0.4, 100.0, 8.0, 8.0, 0.63)
WD = Weighting("Wd", 0.4, 100.0, 2.0, 2.0, 0.63)
WP = Weighting("Wp", None, 100.0, 2.0, 2.0, 0.63)
WEIGHTINGS = {w.name: w for w in (WB, WC, WD, WP)}

#: N_MV = NMV_FACTOR sqrt(sum of squared a_P95).
NMV_FACTOR = 6.0

DEFAULTS = {
    "window_s": 5.0,          # r.m.s. windows
    "percentile": 95.0,       # a_P95
    "grade": 1.0,             # N_MV boundary of "very comfortable" [M]
}


def mean_comfort(a_y: np.ndarray, a_z: np.ndarray, dt_s: float, a_x: np.ndarray | None = None,
                 window_s: float = DEFAULTS["window_s"],
                 pct: float = DEFAULTS["percentile"]) -> tuple[np.ndarray, dict]:
    """N_MV of floor accelerations (m/s^2; samples along axis 0, points in columns) and its
    parts {'a_XP95', 'a_YP95', 'a_ZP95', 'n_windows'}; a_x None: 0 (no longitudinal motion)."""
    parts = {}
    for key, acc, weighting in (("a_XP95", a_x, WD), ("a_YP95", a_y, WD), ("a_ZP95", a_z, WB)):
        if acc is None:
            parts[key] = np.zeros(np.shape(a_y)[1:]) if np.ndim(a_y) > 1 else 0.0
            continue
        rms = window_rms(weighting.apply(acc, dt_s), dt_s, window_s)
        parts["n_windows"] = rms.shape[0]
        parts[key] = percentile(rms, pct)
    n_mv = NMV_FACTOR * np.sqrt(np.square(parts["a_XP95"]) + np.square(parts["a_YP95"])
                                + np.square(parts["a_ZP95"]))
    return n_mv, parts


def evaluate(run: RunData, options) -> list[Row]:
    window, pct = float(options["window_s"]), float(options["percentile"])
    dt = run.dt_s
    labels_y, a_y = run.carbody("ay")
    labels_z, a_z = run.carbody("az")
    if labels_y != labels_z:
        raise ValueError("car-body lateral and vertical columns do not match point by point")
    record_s = a_y.shape[0] * dt
    if record_s < window:
        log.warning("EN 12299 N_MV: the %.2f s record is shorter than the %.1f s window; "
                    "evaluated as one window", record_s, window)
    n_mv, parts = mean_comfort(a_y, a_z, dt, window_s=window, pct=pct)
    i, v, lim = governing(np.atleast_1d(n_mv), float(options["grade"]), labels_y)
    return [Row(
        "mean comfort, standard method N_MV (floor)", "N_MV", "1", "car", labels_y[i], v, lim,
        "scale: < 1 very comfortable, 1-2 comfortable, 2-4 medium, 4-5 uncomfortable [M]; "
        "EN 12299 sets no limit values", category="grade",
        filter="Wd (lateral), Wb (vertical), EN 12299 weightings, causal",
        filter_low_hz=WD.f1, filter_high_hz=WD.f2,
        statistic=f"{pct:g} % percentile of {window:g} s r.m.s. values",
        notes=(f"a_YP95 = {np.atleast_1d(parts['a_YP95'])[i]:.4g} m/s^2, "
               f"a_ZP95 = {np.atleast_1d(parts['a_ZP95'])[i]:.4g} m/s^2, a_XP95 = 0 (no "
               f"longitudinal car-body DOF); {parts['n_windows']} window(s) from a "
               f"{record_s:.2f} s record (the standard: 60 windows, 5 min)"),
    )]


PROFILE = Profile("en12299", STANDARD, "ride comfort (mean comfort N_MV)", DEFAULTS, evaluate)
