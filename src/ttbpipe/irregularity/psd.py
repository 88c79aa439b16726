"""PSD estimation of measured (or synthetic) irregularity profiles, per channel and section.

Estimator: ``scipy.signal.welch`` with ``scaling='density'`` and ``return_onesided=True``, so the
result is the **one-sided** PSD G(n) in mm²/(1/m) of a profile in mm sampled every Δx m
(``fs = 1/Δx`` samples per metre), with ∫ G dn ≈ variance of the detrended profile
(physics.md §2 and §7.7). Parameters and defaults:

* ``window='hann'``;
* ``segment_length_m`` -> ``nperseg = round(segment_length_m / dx_m)``;
* ``overlap`` (fraction) -> ``noverlap = round(overlap * nperseg)``, default 0.5;
* ``detrend='linear'``: a least-squares line is removed from every segment (long-wave
  irregularity outside the band, and the absolute level, must not leak into the band).

Default segment length (config ``psd.segment_length_m``): **1000 m, i.e. the whole 1000 m
section**, a single Hann-tapered periodogram per section. Reason, measured on a 200 km synthetic
TB/T 3352 profile whose spectrum continues beyond 200 m: the steep long-wave spectrum (vertical
n^-3.39) leaks through the window's main lobe, biasing the 100-200 m band by +11 % with 1000 m
segments, +37 % with 500 m and +120 % with 256 m (docs/irregularity.md). The price is a
variance of ~100 % per ordinate (χ²₂, the raw-periodogram statistics of Liu, Li & Wang 2014 used
by the TIPM percentile method); averaging over sections and campaigns then reduces it.

Sections: a campaign is cut into consecutive sections of ``section_length_m`` starting at its
first chainage. A trailing part shorter than one section is **dropped, with a logged warning
giving its length and sample count**: a shorter section would have another frequency resolution
and variance, and each section is an equally weighted sample of the TIPM population. The zero
frequency is dropped (the mean is removed by the detrend).
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..channels import INSPECTION_COLUMNS, SPECTRAL_CHANNELS, spectral_from_inspection
from ..configuration import section_defaults

__all__ = ["welch_psd", "section_psds", "estimate_campaign_psd", "sample_spacing_m",
           "PSD_COLUMNS", "DEFAULTS"]

log = logging.getLogger(__name__)

#: columns of the long-format table :func:`section_psds` returns
PSD_COLUMNS: tuple[str, ...] = ("section", "section_start_m", "section_end_m", "channel",
                                "spatial_frequency_per_m", "psd_mm2_m")

#: estimator defaults: the study schema's ``psd:`` defaults (their only home), without the
#: reference spectrum (a figure setting)
DEFAULTS: dict[str, Any] = {k: (tuple(v) if isinstance(v, list) else v)
                            for k, v in section_defaults("psd").items()
                            if k != "reference_spectrum"}


def _segment_points(segment_length_m: float, dx_m: float, n_available: int,
                    what: str = "profile") -> int:
    if not (np.isfinite(segment_length_m) and segment_length_m > 0):
        raise ValueError(f"Welch segment length must be > 0 m, got {segment_length_m!r}")
    nperseg = int(round(segment_length_m / dx_m))
    if nperseg < 8:
        raise ValueError(f"Welch segment of {segment_length_m} m holds only {nperseg} samples at "
                         f"dx = {dx_m} m; use a longer segment")
    if nperseg > n_available:
        raise ValueError(f"Welch segment length {segment_length_m} m ({nperseg} samples) exceeds "
                         f"the {what} ({n_available} samples, {n_available * dx_m:g} m); choose "
                         "segment_length_m <= section_length_m")
    return nperseg


def welch_psd(profile_mm, dx_m: float, segment_length_m: float, overlap: float = 0.5,
              window: str = "hann", detrend: str | bool = "linear"
              ) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD of a uniformly sampled profile.

    Returns ``(spatial_frequency_per_m, psd_mm2_m)`` from ``scipy.signal.welch(profile,
    fs=1/dx_m, window, nperseg=round(segment_length_m/dx_m), noverlap=round(overlap*nperseg),
    detrend, scaling='density', return_onesided=True)``. The unit of the PSD is (profile unit)²
    per (1/m); the zero frequency is included (drop it before taking logs).
    """
    profile = np.asarray(profile_mm, dtype=float)
    if profile.ndim != 1:
        raise ValueError("profile must be one-dimensional")
    if not (np.isfinite(dx_m) and dx_m > 0):
        raise ValueError(f"sample spacing must be > 0 m, got {dx_m!r}")
    if not np.all(np.isfinite(profile)):
        bad = np.flatnonzero(~np.isfinite(profile))
        raise ValueError(f"profile has {bad.size} non-finite samples (first at index {bad[0]}); "
                         "clean the campaign first (ttbpipe check-inspection)")
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap must be a fraction in [0, 1), got {overlap!r}")
    # on use: `import scipy.signal` costs up to 1 s (SciPy 1.17 rewrites the docstrings of its
    # functions on import; about 0.1 s more once scipy.stats is loaded), which processes that
    # import ttbpipe.irregularity or ttbpipe.inspection without estimating a spectrum need not
    # pay (synth_inspections: 1.3 -> 0.7 s of imports)
    from scipy import signal

    nperseg = _segment_points(segment_length_m, dx_m, profile.size)
    noverlap = int(round(overlap * nperseg))
    frequencies, psd = signal.welch(profile, fs=1.0 / dx_m, window=window, nperseg=nperseg,
                                    noverlap=noverlap, detrend=detrend, scaling="density",
                                    return_onesided=True)
    return frequencies, psd


def sample_spacing_m(chainage_m, *, source: str = "campaign", rtol: float = 1e-6) -> float:
    """The uniform sample spacing of a chainage column; ``ValueError`` naming the first bad row
    if the chainage is not strictly increasing and uniform (relative tolerance ``rtol``)."""
    chainage = np.asarray(chainage_m, dtype=float)
    if chainage.size < 2:
        raise ValueError(f"{source}: need at least two samples")
    if not np.all(np.isfinite(chainage)):
        row = int(np.flatnonzero(~np.isfinite(chainage))[0])
        raise ValueError(f"{source}: row {row}, column chainage_m: non-finite chainage")
    steps = np.diff(chainage)
    dx = float(np.median(steps))
    if dx <= 0:
        raise ValueError(f"{source}: column chainage_m is not increasing")
    # relative tolerance on the step, plus the round-off of chainages stored as decimals
    bad = np.flatnonzero(np.abs(steps - dx) > rtol * dx + 1e-12 * np.abs(chainage).max())
    if bad.size:
        row = int(bad[0]) + 1
        raise ValueError(f"{source}: row {row}, column chainage_m: step {steps[bad[0]]:g} m differs "
                         f"from the sample spacing {dx:g} m ({bad.size} irregular steps); PSD "
                         "estimation needs a uniform grid (clean/resample the campaign first)")
    return dx


def section_psds(clean: pd.DataFrame, section_length_m: float = DEFAULTS["section_length_m"],
                 segment_length_m: float = DEFAULTS["segment_length_m"],
                 overlap: float = DEFAULTS["overlap"], window: str = DEFAULTS["window"],
                 detrend: str = DEFAULTS["detrend"],
                 wavelength_band_m: tuple[float, float] | None = None, *,
                 source: str = "campaign") -> pd.DataFrame:
    """Welch PSD of the four spectral channels in every full section of a cleaned campaign.

    ``clean`` has ``chainage_m`` (uniform, increasing) and the six columns of
    :data:`ttbpipe.channels.INSPECTION_COLUMNS` in mm; they are converted to the spectral
    channels with :func:`ttbpipe.channels.spectral_from_inspection`.

    Returns a long table with columns :data:`PSD_COLUMNS`: ``section`` (int, from 0),
    ``section_start_m``, ``section_end_m`` (chainage of the section's first sample and
    first sample + section length), ``channel``, ``spatial_frequency_per_m`` (> 0) and
    ``psd_mm2_m``. With ``wavelength_band_m=(λmin, λmax)`` only frequencies
    1/λmax <= n <= 1/λmin are kept. The trailing partial section is dropped with a warning
    (module docstring). Raises ``ValueError`` if the segment is longer than a section or the
    campaign holds no full section.
    """
    missing = [c for c in ("chainage_m", *INSPECTION_COLUMNS) if c not in clean.columns]
    if missing:
        raise ValueError(f"{source}: missing columns {missing}")
    if not (np.isfinite(section_length_m) and section_length_m > 0):
        raise ValueError(f"section length must be > 0 m, got {section_length_m!r}")
    if segment_length_m > section_length_m * (1 + 1e-12):
        raise ValueError(f"Welch segment length {segment_length_m} m exceeds the section length "
                         f"{section_length_m} m; choose segment_length_m <= section_length_m")
    chainage = clean["chainage_m"].to_numpy(dtype=float)
    dx = sample_spacing_m(chainage, source=source)
    points_per_section = int(round(section_length_m / dx))
    nperseg = _segment_points(segment_length_m, dx, points_per_section, what="section")
    n_sections = chainage.size // points_per_section
    if n_sections == 0:
        raise ValueError(f"{source}: {chainage.size} samples ({chainage.size * dx:g} m) hold no "
                         f"full {section_length_m:g} m section; use a shorter section length")
    leftover = chainage.size - n_sections * points_per_section
    if leftover == 1:
        # the usual closing sample of a file sampled from 0 to its length inclusive
        log.info("%s: the closing sample at chainage %g m (end of the last full section) belongs "
                 "to no section; 1 sample dropped", source, chainage[-1])
    elif leftover:
        log.warning("%s: dropped the last partial section: %d samples (%.2f m) after %d full "
                    "sections of %g m", source, leftover, leftover * dx, n_sections,
                    section_length_m)
    channels = spectral_from_inspection({c: clean[c].to_numpy(dtype=float)
                                         for c in INSPECTION_COLUMNS})
    for channel, values in channels.items():
        if not np.all(np.isfinite(values)):
            row = int(np.flatnonzero(~np.isfinite(values))[0])
            raise ValueError(f"{source}: row {row}: non-finite value in channel {channel}; clean "
                             "the campaign first (ttbpipe check-inspection)")

    segment_length_exact = nperseg * dx
    frames = []
    for section in range(n_sections):
        first = section * points_per_section
        rows = slice(first, first + points_per_section)
        start = chainage[first]
        for channel in SPECTRAL_CHANNELS:
            frequencies, psd = welch_psd(channels[channel][rows], dx, segment_length_exact,
                                         overlap, window, detrend)
            keep = frequencies > 0
            if wavelength_band_m is not None:
                lam_min, lam_max = (float(v) for v in wavelength_band_m)
                keep &= ((frequencies >= (1 / lam_max) * (1 - 1e-12))
                         & (frequencies <= (1 / lam_min) * (1 + 1e-12)))
            frames.append(pd.DataFrame({
                "section": np.full(keep.sum(), section, dtype=np.int64),
                "section_start_m": start,
                "section_end_m": start + points_per_section * dx,
                "channel": channel,
                "spatial_frequency_per_m": frequencies[keep],
                "psd_mm2_m": psd[keep],
            }))
    table = pd.concat(frames, ignore_index=True)
    table["channel"] = table["channel"].astype(str)
    log.info("%s: PSD of %d sections x %d channels, %d frequencies each (dx %g m, segment %g m, "
             "overlap %g, window %s, detrend %s)", source, n_sections, len(SPECTRAL_CHANNELS),
             len(frames[0]), dx, segment_length_exact, overlap, window, detrend)
    return table[list(PSD_COLUMNS)]


def estimate_campaign_psd(clean: pd.DataFrame, psd_config: Mapping[str, Any] | None = None, *,
                          source: str = "campaign") -> pd.DataFrame:
    """:func:`section_psds` with the options of the config ``psd:`` section (missing keys take
    :data:`DEFAULTS`; ``reference_spectrum`` is ignored here)."""
    options = {**DEFAULTS, **{k: v for k, v in dict(psd_config or {}).items() if k in DEFAULTS}}
    band = options["wavelength_band_m"]
    return section_psds(clean, section_length_m=float(options["section_length_m"]),
                        segment_length_m=float(options["segment_length_m"]),
                        overlap=float(options["overlap"]), window=str(options["window"]),
                        detrend=str(options["detrend"]),
                        wavelength_band_m=None if band is None else tuple(band), source=source)
