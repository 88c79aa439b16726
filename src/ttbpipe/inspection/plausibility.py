"""Plausibility of a campaign's magnitudes, judged against the standard track spectra.

A channel written in centimetres or inches but labelled millimetres is 10 or 25.4 times too
small: its PSD is 100 or 645 times too low, and every exceedance probability computed from it is
non-conservative. Such a channel has no tell-tale single value (all samples are within the
plausible limit), but its *band RMS* does: the standard spectra of :mod:`ttbpipe.irregularity.
spectra` span real track geometry from the best class (TB/T 3352, Chinese high-speed slab track)
to the worst (FRA class 1), and a channel far below the best or far above the worst is in the
wrong unit or comes from a faulty sensor.

The expected range of each inspection column is computed from the spectra, never typed in:
per spectrum, the band RMS of the four spectral channels (:meth:`TrackSpectrum.band_rms_mm`) is
turned into the RMS of each per-rail column with the relations of :mod:`ttbpipe.channels`
(``z_left = vertical + cross_level / 2``, ``y_left = alignment + gauge / 2``, the four channels
independent as the standards and :mod:`ttbpipe.irregularity.synthesis` treat them), so
``rms(vertical_left) = sqrt(rms(vertical)**2 + rms(cross_level)**2 / 4)``; the range is the
smallest and the largest of these over all standard spectra, widened by ``margin`` (a factor on
the RMS, config ``inspections.cleaning.band_rms_margin``) on each side.

Over 2-200 m (:data:`PLAUSIBILITY_BAND_M`) that gives, for the rail vertical profile, 1.25 mm
(TB/T 3352) to 30.8 mm (FRA class 1), so with the default margin of 3 the accepted band RMS is
0.416-92.4 mm (the table of all columns: docs/inspection_format.md): a TB/T 3352 campaign in
centimetres (0.125 mm) or inches (0.049 mm) fails, and so does German track.
What the check cannot see: poor track (FRA classes 1-5) written in centimetres still lies inside
the range of real track, so files of inspection cars that do not write millimetres must declare
their unit (``inspections.units``), which this check backs up but cannot replace.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from pathlib import Path
from typing import Mapping

import numpy as np

from ..channels import INSPECTION_COLUMNS
from .format import InspectionError

logger = logging.getLogger(__name__)

#: Wavelength band (m) of the band RMS check: the band TB/T 3352 is defined on, the band of the
#: reference RMS values of physics.md section 1 and the default ``psd.wavelength_band_m``.
#: The German spectra (defined on 3-150 m) are evaluated over it with ``extrapolate=True``, which
#: their rational form allows (docstring of :class:`GermanHighSpeedSpectrum`).
PLAUSIBILITY_BAND_M: tuple[float, float] = (2.0, 200.0)

#: The shortest wavelength used is at least this many sampling steps: well above the Nyquist
#: wavelength (2 steps), where the anti-alias filter of a measuring system cuts.
MIN_WAVELENGTH_STEPS = 4.0

#: The longest wavelength used is at most this fraction of the record length, so that the
#: periodogram resolves it (a Hann window's main lobe is 2 frequency bins wide).
MAX_WAVELENGTH_FRACTION = 0.5

#: The check needs a band of at least this ratio longest/shortest wavelength; shorter records
#: are not checked (logged as a warning).
MIN_BAND_RATIO = 5.0

# Spectral channels behind each inspection column: (own channel, partner channel whose half
# enters the per-rail column) per ttbpipe.channels.rails_from_spectral.
_COLUMN_CHANNELS: dict[str, tuple[str, str | None]] = {
    "vertical_left_mm": ("vertical", "cross_level"),
    "vertical_right_mm": ("vertical", "cross_level"),
    "alignment_left_mm": ("alignment", "gauge"),
    "alignment_right_mm": ("alignment", "gauge"),
    "cross_level_mm": ("cross_level", None),
    "gauge_mm": ("gauge", None),
}


@dataclasses.dataclass(frozen=True)
class BandRmsRange:
    """Band RMS of one inspection column over the standard spectra: smallest and largest."""

    column: str
    low_mm: float
    low_spectrum: str
    high_mm: float
    high_spectrum: str

    def accepted(self, margin: float) -> tuple[float, float]:
        """The accepted band RMS range (mm) with ``margin`` (>= 1) on each side."""
        return self.low_mm / margin, self.high_mm * margin


@functools.lru_cache(maxsize=64)
def standard_band_rms_range(wavelength_band_m: tuple[float, float] = PLAUSIBILITY_BAND_M
                            ) -> dict[str, BandRmsRange]:
    """Per inspection column, the band RMS range spanned by the standard spectra (mm).

    Computed from :data:`ttbpipe.irregularity.spectra.SPECTRUM_NAMES` (module docstring); cached
    per band.
    """
    from ..irregularity.spectra import SPECTRUM_NAMES, get_spectrum

    band = (float(wavelength_band_m[0]), float(wavelength_band_m[1]))
    per_spectrum: dict[str, dict[str, float]] = {}
    for name in SPECTRUM_NAMES:
        spectrum = get_spectrum(name)
        rms = {channel: spectrum.band_rms_mm(channel, band, extrapolate=True)
               for channel in spectrum.channels}
        per_spectrum[name] = {
            column: math.hypot(rms[own], 0.5 * rms[partner]) if partner else rms[own]
            for column, (own, partner) in _COLUMN_CHANNELS.items()}
    ranges = {}
    for column in INSPECTION_COLUMNS:
        low = min(per_spectrum, key=lambda name: per_spectrum[name][column])
        high = max(per_spectrum, key=lambda name: per_spectrum[name][column])
        ranges[column] = BandRmsRange(column, per_spectrum[low][column], low,
                                      per_spectrum[high][column], high)
    return ranges


def check_band(step_m: float, length_m: float,
               wavelength_band_m: tuple[float, float] = PLAUSIBILITY_BAND_M
               ) -> tuple[float, float] | None:
    """The part of ``wavelength_band_m`` a record of ``length_m`` at ``step_m`` resolves.

    Shortest wavelength at least :data:`MIN_WAVELENGTH_STEPS` steps, longest at most
    :data:`MAX_WAVELENGTH_FRACTION` of the record; ``None`` when what is left is narrower than
    :data:`MIN_BAND_RATIO`.
    """
    shortest = max(float(wavelength_band_m[0]), MIN_WAVELENGTH_STEPS * step_m)
    longest = min(float(wavelength_band_m[1]), MAX_WAVELENGTH_FRACTION * length_m)
    if longest < MIN_BAND_RATIO * shortest:
        return None
    return round(shortest, 9), round(longest, 9)


def band_rms_mm(values: np.ndarray, step_m: float, wavelength_band_m: tuple[float, float]) -> float:
    """RMS (mm) of ``values`` (uniform step ``step_m``) over ``wavelength_band_m``.

    One-sided periodogram (``scipy.signal.periodogram``, Hann window, linear detrend, density
    scaling so that the integral of the PSD is the variance) integrated over
    1/longest..1/shortest wavelength (discrete Parseval, physics.md section 2).
    """
    from scipy import signal   # on use, as in ttbpipe.irregularity.psd.welch_psd

    frequency, psd = signal.periodogram(np.asarray(values, dtype=float), fs=1.0 / step_m,
                                        window="hann", detrend="linear", scaling="density")
    keep = ((frequency >= 1.0 / wavelength_band_m[1] * (1 - 1e-12))
            & (frequency <= 1.0 / wavelength_band_m[0] * (1 + 1e-12)))
    return float(math.sqrt(float(psd[keep].sum()) * (frequency[1] - frequency[0])))


def check_band_rms(columns: Mapping[str, np.ndarray], step_m: float, source: str | Path, *,
                   margin: float) -> tuple[tuple[float, float] | None, dict[str, float]]:
    """Band RMS of each column against the range of the standard spectra; raise if outside.

    ``columns`` holds the six channels (mm, uniform step ``step_m``, no NaN). Returns the band
    used (``None`` when the record is too short: not checked, logged) and the band RMS per
    column. Raises :class:`InspectionError` naming the file, the column, the measured band RMS,
    the expected range and the probable cause.
    """
    if not margin >= 1.0:
        raise ValueError(f"band_rms_margin must be >= 1, not {margin!r}")
    n = len(next(iter(columns.values())))
    band = check_band(step_m, (n - 1) * step_m)
    if band is None:
        logger.warning("%s: record of %.4g m at %g m too short for the band RMS plausibility "
                       "check (units not checked against the standard spectra)", source,
                       (n - 1) * step_m, step_m)
        return None, {}
    ranges = standard_band_rms_range(band)
    measured: dict[str, float] = {}
    for column in INSPECTION_COLUMNS:
        rms = band_rms_mm(columns[column], step_m, band)
        measured[column] = rms
        expected = ranges[column]
        low, high = expected.accepted(margin)
        if low <= rms <= high:
            continue
        where = (f"band RMS over {band[0]:g}-{band[1]:g} m is {rms:.4g} mm, "
                 + (f"below" if rms < low else "above")
                 + f" the {low:.3g}-{high:.3g} mm expected (the standard spectra span "
                   f"{expected.low_mm:.3g} mm, {expected.low_spectrum}, to {expected.high_mm:.3g} "
                   f"mm, {expected.high_spectrum}; band_rms_margin = {margin:g})")
        if rms < low:
            cause = ("values look like centimetres or inches: convert to mm or declare the unit "
                     "in inspections.units")
        else:
            cause = ("values look like a unit smaller than mm (e.g. micrometres or hundredths "
                     "of a millimetre) or a faulty sensor: convert to mm or declare the unit in "
                     "inspections.units")
        raise InspectionError(source, None, column, f"implausible magnitude: {where}: {cause}")
    return band, measured
