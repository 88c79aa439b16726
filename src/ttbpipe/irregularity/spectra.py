"""Standard track-irregularity spectra behind one interface.

Every standard is a :class:`TrackSpectrum` that returns the **one-sided** PSD of the four
spectral channels of :mod:`ttbpipe.channels` (``vertical``, ``alignment``, ``cross_level``,
``gauge``), as a *height* PSD in mm²/(1/m) with the argument in cycles per metre (1/m), whatever
units the standard itself is published in:

===============  =========================  ============================  =====================
name             published argument          published PSD unit            converted here with
===============  =========================  ============================  =====================
``tbt3352``      n, cycles/m (1/m)          mm²/(1/m)                     (none)
``german_low``   Ω, rad/m                   m²/(rad/m); cross-level is    G_n = 2π·G_Ω(2πn)·1e6;
``german_high``                             an angle PSD rad²/(rad/m)     cross-level ×(2b)²
``fra_class1-6`` Ω, rad/m                   cm²/(rad/m)                   G_n = 2π·G_Ω(2πn)·1e2
===============  =========================  ============================  =====================

The conversion between a PSD per rad/m and one per cycle/m keeps the variance in a band
unchanged: with Ω = 2πn, G_Ω(Ω)·dΩ = G_n(n)·dn, so **G_n(n) = 2π·G_Ω(2πn)** (physics.md §7.1).

Each spectrum is valid over a wavelength band only; :meth:`TrackSpectrum.psd_mm2_m` raises a
``ValueError`` outside it unless ``extrapolate=True`` (physics.md §7.6: the TB/T vertical power
k = 3.39 explodes at low frequency).

Sources: docs/reference/physics.md section 1 (with the primary sources named in each
class docstring).
"""

from __future__ import annotations

import abc
import math
from typing import Callable

import numpy as np

from ..channels import SPECTRAL_CHANNELS

__all__ = [
    "TrackSpectrum", "TBT3352Spectrum", "GermanHighSpeedSpectrum", "FRASpectrum",
    "get_spectrum", "SPECTRUM_NAMES",
    "per_m_to_rad_per_m", "rad_per_m_to_per_m",
    "psd_per_rad_to_per_cycle", "psd_per_cycle_to_per_rad",
]


# --------------------------------------------------------------------------------------------
# Unit helpers
# --------------------------------------------------------------------------------------------

def per_m_to_rad_per_m(spatial_frequency_per_m):
    """Angular spatial frequency Ω (rad/m) from a spatial frequency n (cycles/m): Ω = 2πn."""
    return 2.0 * np.pi * np.asarray(spatial_frequency_per_m, dtype=float)


def rad_per_m_to_per_m(angular_frequency_rad_m):
    """Spatial frequency n (cycles/m) from an angular spatial frequency Ω (rad/m): n = Ω/2π."""
    return np.asarray(angular_frequency_rad_m, dtype=float) / (2.0 * np.pi)


def psd_per_rad_to_per_cycle(psd_per_rad):
    """PSD value per (rad/m) -> PSD value per (1/m), **at corresponding frequencies** Ω = 2πn.

    G_n(n) = 2π·G_Ω(2πn) (physics.md §7.1), so that ∫G_n dn = ∫G_Ω dΩ over the same band.
    The length unit of the PSD (mm², m², cm²) is unchanged.
    """
    return 2.0 * np.pi * np.asarray(psd_per_rad, dtype=float)


def psd_per_cycle_to_per_rad(psd_per_cycle):
    """PSD value per (1/m) -> PSD value per (rad/m): G_Ω(Ω) = G_n(Ω/2π)/2π (inverse of above)."""
    return np.asarray(psd_per_cycle, dtype=float) / (2.0 * np.pi)


# --------------------------------------------------------------------------------------------
# Interface
# --------------------------------------------------------------------------------------------

class TrackSpectrum(abc.ABC):
    """A standard irregularity spectrum of the four spectral channels.

    Subclasses implement :meth:`_psd_mm2_m` (no range check) and set :attr:`name`,
    :attr:`valid_wavelength_band_m` and :attr:`source`.
    """

    #: registry name, e.g. ``"tbt3352"``
    name: str
    #: (shortest, longest) wavelength in m over which the standard is defined
    valid_wavelength_band_m: tuple[float, float]
    #: short citation of where the formula and coefficients come from
    source: str = ""
    #: the four spectral channels, in the order of :data:`ttbpipe.channels.SPECTRAL_CHANNELS`
    channels: tuple[str, ...] = SPECTRAL_CHANNELS

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"

    @property
    def valid_frequency_band_per_m(self) -> tuple[float, float]:
        """(lowest, highest) spatial frequency in 1/m of the valid band, inclusive."""
        lo, hi = self.valid_wavelength_band_m
        return 1.0 / hi, 1.0 / lo

    def _check_channel(self, channel: str) -> None:
        if channel not in self.channels:
            raise ValueError(f"{self.name}: unknown channel {channel!r}; expected one of "
                             f"{', '.join(self.channels)}")

    def psd_mm2_m(self, channel: str, spatial_frequency_per_m, *,
                  extrapolate: bool = False) -> np.ndarray:
        """One-sided height PSD in mm²/(1/m) of ``channel`` at ``spatial_frequency_per_m`` (1/m).

        Raises ``ValueError`` if a frequency is not finite and positive, or lies outside
        :attr:`valid_frequency_band_per_m` (band edges included, with a relative slack of 1e-9
        for round-off) unless ``extrapolate=True``.
        """
        self._check_channel(channel)
        n = np.asarray(spatial_frequency_per_m, dtype=float)
        if not np.all(np.isfinite(n)) or np.any(n <= 0.0):
            raise ValueError(f"{self.name}: spatial frequencies must be finite and > 0 (1/m)")
        if not extrapolate:
            lo, hi = self.valid_frequency_band_per_m
            outside = (n < lo * (1 - 1e-9)) | (n > hi * (1 + 1e-9))
            if np.any(outside):
                bad = n[outside]
                raise ValueError(
                    f"{self.name} {channel}: {bad.size} spatial frequencies outside the valid band "
                    f"{lo:g}-{hi:g} 1/m (wavelengths {self.valid_wavelength_band_m[0]:g}-"
                    f"{self.valid_wavelength_band_m[1]:g} m), e.g. {bad.flat[0]:g} 1/m; "
                    "restrict the band or pass extrapolate=True knowingly")
        return self._psd_mm2_m(channel, n)

    @abc.abstractmethod
    def _psd_mm2_m(self, channel: str, n: np.ndarray) -> np.ndarray:
        """PSD in mm²/(1/m) at n (1/m), no range check."""

    def band_rms_mm(self, channel: str, wavelength_band_m: tuple[float, float] = (2.0, 200.0), *,
                    extrapolate: bool = False) -> float:
        """RMS in mm of ``channel`` over ``wavelength_band_m``: sqrt(∫ G_n(n) dn) from 1/λmax to
        1/λmin, by adaptive quadrature (``scipy.integrate.quad``) in log n, split at the
        spectrum's breakpoints.

        Raises ``ValueError`` if the band leaves the valid band, unless ``extrapolate=True``.
        """
        lam_min, lam_max = (float(v) for v in wavelength_band_m)
        if not 0 < lam_min < lam_max:
            raise ValueError(f"wavelength band must be 0 < min < max, got {wavelength_band_m}")
        n_lo, n_hi = 1.0 / lam_max, 1.0 / lam_min
        # validate the band once (raises a clear error outside the valid band)
        self.psd_mm2_m(channel, np.array([n_lo, n_hi]), extrapolate=extrapolate)
        edges = [n_lo] + [b for b in self._breakpoints_per_m(channel) if n_lo < b < n_hi] + [n_hi]

        def integrand(log_n: float) -> float:
            n = math.exp(log_n)
            return float(self._psd_mm2_m(channel, np.array([n]))[0]) * n  # dn = n d(log n)

        # imported here: scipy.integrate loads SciPy's sparse and linear-algebra modules, which
        # planning a study (it counts a synthetic campaign's rows) does not need
        from scipy import integrate

        variance = 0.0
        for a, b in zip(edges[:-1], edges[1:]):
            value, _ = integrate.quad(integrand, math.log(a), math.log(b), epsabs=0.0,
                                      epsrel=1e-10, limit=200)
            variance += value
        return math.sqrt(variance)

    def _breakpoints_per_m(self, channel: str) -> tuple[float, ...]:
        """Frequencies (1/m) where the formula changes (for piecewise spectra)."""
        return ()

    def as_function(self, channel: str, *, extrapolate: bool = False
                    ) -> Callable[[np.ndarray], np.ndarray]:
        """``n -> psd_mm2_m(channel, n)``, the callable :func:`synthesize_channel` takes."""
        self._check_channel(channel)
        return lambda n: self.psd_mm2_m(channel, n, extrapolate=extrapolate)


# --------------------------------------------------------------------------------------------
# China, TB/T 3352-2014
# --------------------------------------------------------------------------------------------

class TBT3352Spectrum(TrackSpectrum):
    """China high-speed ballastless track, TB/T 3352-2014 (physics.md §1a).

    Piecewise power law S(n) = A_i / n^{k_i}, n in 1/m, S in mm²/(1/m), one-sided, defined for
    wavelengths 2-200 m (n = 0.005-0.5 1/m, edges included).

    **Breakpoint inclusivity:** with breakpoints n_1 < n_2 < ..., segment i (coefficients
    A_i, k_i) applies on the half-open interval [n_{i-1}, n_i); a breakpoint itself belongs to the
    higher-frequency (shorter-wavelength) segment. The segments join within 0.4 % (physics.md),
    so the choice changes values at the breakpoints by less than that.

    Coefficients: TB/T 3352-2014 "Track irregularity PSD of high-speed railway ballastless
    track", as quoted in physics.md §1a (three independent public code copies agree).
    """

    name = "tbt3352"
    valid_wavelength_band_m = (2.0, 200.0)
    source = "TB/T 3352-2014 (physics.md §1a)"

    #: channel -> (breakpoints 1/m, A coefficients, k exponents)
    COEFFICIENTS: dict[str, tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]] = {
        "vertical": ((0.0187, 0.0474, 0.1533),
                     (1.0544e-5, 3.5588e-3, 1.9784e-2, 3.9488e-4),
                     (3.3891, 1.9271, 1.3643, 3.4516)),
        "alignment": ((0.0450, 0.1234),
                      (3.9513e-3, 1.1047e-2, 7.5633e-4),
                      (1.8670, 1.5354, 2.8171)),
        "cross_level": ((0.0258, 0.1163),
                        (3.6148e-3, 4.3685e-2, 4.5867e-3),
                        (1.7278, 1.0461, 2.0939)),
        "gauge": ((0.1090, 0.2938),
                  (5.4978e-2, 5.0701e-3, 1.8778e-4),
                  (0.8282, 1.9037, 4.5948)),
    }

    def _psd_mm2_m(self, channel: str, n: np.ndarray) -> np.ndarray:
        breaks, a_coef, k_exp = self.COEFFICIENTS[channel]
        # side="right": n equal to a breakpoint gets the index of the segment above it
        segment = np.searchsorted(np.asarray(breaks), n, side="right")
        a = np.asarray(a_coef)[segment]
        k = np.asarray(k_exp)[segment]
        return a / n ** k

    def _breakpoints_per_m(self, channel: str) -> tuple[float, ...]:
        return self.COEFFICIENTS[channel][0]


# --------------------------------------------------------------------------------------------
# German high-speed, low and high interference
# --------------------------------------------------------------------------------------------

class GermanHighSpeedSpectrum(TrackSpectrum):
    """German high-speed spectra, low or high interference (physics.md §1b).

    Published with Ω in rad/m and S in m²/(rad/m), one-sided:

    * vertical   S_v(Ω) = A_v Ω_c² / [(Ω²+Ω_r²)(Ω²+Ω_c²)]
    * alignment  S_a(Ω) = A_a Ω_c² / [(Ω²+Ω_r²)(Ω²+Ω_c²)]
    * cross-level S_c(Ω) = (A_v/b²) Ω_c² Ω² / [(Ω²+Ω_r²)(Ω²+Ω_c²)(Ω²+Ω_s²)], an **angle** PSD in
      rad²/(rad/m); the height difference of the two rails is (2b)·angle, so the height PSD is
      (2b)²·S_c with b = 0.75 m (half the distance between the rail contact points),
    * gauge      S_g(Ω) = A_g Ω_c² Ω² / [(Ω²+Ω_r²)(Ω²+Ω_c²)(Ω²+Ω_s²)].

    Converted to mm²/(1/m) per cycle/m with G_n(n) = 2π·S(2πn)·1e6.

    Valid band: the sources disagree (0.5-80 m, or 3-150 m in the TTB-2D MATLAB tool,
    ``DanielCanteroNTNU/TTB-2D`` ``A04_Options.m``, citing Guo et al., Comput. Struct. 2012).
    We use the named source, 3-150 m. The rational form stays finite outside it, so an
    evaluation over 2-200 m with ``extrapolate=True`` is harmless (physics.md [C] RMS values are
    given over 2-200 m).
    """

    valid_wavelength_band_m = (3.0, 150.0)
    source = "German high-speed spectra, low/high interference (physics.md §1b)"

    OMEGA_C = 0.8246  # rad/m
    OMEGA_R = 0.0206  # rad/m
    OMEGA_S = 0.4380  # rad/m
    HALF_GAUGE_B_M = 0.75
    #: level -> (A_v, A_a, A_g), m·rad
    LEVELS = {
        "low": (4.032e-7, 2.119e-7, 5.32e-8),
        "high": (1.080e-6, 6.125e-7, 1.032e-7),
    }

    def __init__(self, level: str):
        if level not in self.LEVELS:
            raise ValueError(f"German spectrum level must be 'low' or 'high', got {level!r}")
        self.level = level
        self.name = f"german_{level}"
        self.a_vertical, self.a_alignment, self.a_gauge = self.LEVELS[level]

    def psd_m2_rad(self, channel: str, angular_frequency_rad_m) -> np.ndarray:
        """The published PSD, m²/(rad/m) (cross-level: rad²/(rad/m), an angle), no range check."""
        self._check_channel(channel)
        w2 = np.asarray(angular_frequency_rad_m, dtype=float) ** 2
        wc2, wr2, ws2 = self.OMEGA_C ** 2, self.OMEGA_R ** 2, self.OMEGA_S ** 2
        base = wc2 / ((w2 + wr2) * (w2 + wc2))
        if channel == "vertical":
            return self.a_vertical * base
        if channel == "alignment":
            return self.a_alignment * base
        shaped = base * w2 / (w2 + ws2)
        if channel == "cross_level":
            return self.a_vertical / self.HALF_GAUGE_B_M ** 2 * shaped
        return self.a_gauge * shaped

    def _psd_mm2_m(self, channel: str, n: np.ndarray) -> np.ndarray:
        psd = self.psd_m2_rad(channel, per_m_to_rad_per_m(n))
        if channel == "cross_level":  # angle -> height difference of the rails
            psd = psd * (2.0 * self.HALF_GAUGE_B_M) ** 2
        return psd_per_rad_to_per_cycle(psd) * 1e6  # m² -> mm²


# --------------------------------------------------------------------------------------------
# US FRA classes 1-6
# --------------------------------------------------------------------------------------------

class FRASpectrum(TrackSpectrum):
    """US FRA track classes 1-6 (Hamid et al., FRA 1983; physics.md §1c).

    Published with Ω in rad/m, S in **cm²/(rad/m)**, one-sided, k = 0.25:

    * vertical    S_v(Ω) = k A_v Ω_c² / [Ω² (Ω²+Ω_c²)]
    * alignment   S_a(Ω) = k A_a Ω_c² / [Ω² (Ω²+Ω_c²)]
    * cross-level and gauge S_c = S_g = 4 k A_v Ω_c² / [(Ω²+Ω_c²)(Ω²+Ω_s²)] (height, cm²)

    Ω_c = 0.8245 rad/m for all classes; A_v [V], A_a and Ω_s [M] per physics.md §1c.
    Converted to mm²/(1/m) with G_n(n) = 2π·S(2πn)·100. Valid for wavelengths 1.524-304.8 m
    (TTB-2D ``A04_Options.m``).
    """

    valid_wavelength_band_m = (1.524, 304.8)
    source = "FRA classes 1-6, Hamid et al. 1983 (physics.md §1c)"

    K = 0.25
    OMEGA_C = 0.8245  # rad/m
    #: class -> (A_v cm²·rad/m, A_a cm²·rad/m, Ω_s rad/m)
    CLASSES = {
        1: (1.2107, 3.3634, 0.6046),
        2: (1.0181, 1.2107, 0.9308),
        3: (0.6816, 0.4128, 0.8520),
        4: (0.5376, 0.3027, 1.1312),
        5: (0.2095, 0.0762, 0.8209),
        6: (0.0339, 0.0339, 0.4380),
    }

    def __init__(self, track_class: int):
        if track_class not in self.CLASSES:
            raise ValueError(f"FRA track class must be 1..6, got {track_class!r}")
        self.track_class = track_class
        self.name = f"fra_class{track_class}"
        self.a_vertical, self.a_alignment, self.omega_s = self.CLASSES[track_class]

    def psd_cm2_rad(self, channel: str, angular_frequency_rad_m) -> np.ndarray:
        """The published PSD in cm²/(rad/m), no range check."""
        self._check_channel(channel)
        w2 = np.asarray(angular_frequency_rad_m, dtype=float) ** 2
        wc2 = self.OMEGA_C ** 2
        if channel == "vertical":
            return self.K * self.a_vertical * wc2 / (w2 * (w2 + wc2))
        if channel == "alignment":
            return self.K * self.a_alignment * wc2 / (w2 * (w2 + wc2))
        return 4.0 * self.K * self.a_vertical * wc2 / ((w2 + wc2) * (w2 + self.omega_s ** 2))

    def _psd_mm2_m(self, channel: str, n: np.ndarray) -> np.ndarray:
        return psd_per_rad_to_per_cycle(self.psd_cm2_rad(channel, per_m_to_rad_per_m(n))) * 1e2


# --------------------------------------------------------------------------------------------
# Registry
# --------------------------------------------------------------------------------------------

_FACTORIES: dict[str, Callable[[], TrackSpectrum]] = {
    "tbt3352": TBT3352Spectrum,
    "german_low": lambda: GermanHighSpeedSpectrum("low"),
    "german_high": lambda: GermanHighSpeedSpectrum("high"),
    **{f"fra_class{c}": (lambda c=c: FRASpectrum(c)) for c in range(1, 7)},
}

#: names accepted by :func:`get_spectrum`
SPECTRUM_NAMES: tuple[str, ...] = tuple(_FACTORIES)


def get_spectrum(name: str) -> TrackSpectrum:
    """The standard spectrum called ``name`` (one of :data:`SPECTRUM_NAMES`)."""
    if isinstance(name, TrackSpectrum):
        return name
    try:
        return _FACTORIES[str(name).strip().lower()]()
    except KeyError:
        raise ValueError(f"unknown track spectrum {name!r}; choose one of "
                         f"{', '.join(SPECTRUM_NAMES)}") from None
