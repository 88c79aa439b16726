"""Track irregularity: standard spectra, space-domain synthesis and PSD estimation.

* :mod:`.spectra`   -- TB/T 3352-2014, German high-speed and FRA spectra behind one interface
  (:func:`get_spectrum`), plus the rad/m <-> 1/m unit helpers;
* :mod:`.synthesis` -- random profiles from a one-sided PSD by inverse FFT (random phases, or
  Gaussian Fourier coefficients from explicit normals);
* :mod:`.gaussian`  -- Gaussian profiles with a random spectral level as a function of
  standard normals (:class:`~.gaussian.GaussianIrregularityModel`);
* :mod:`.psd`       -- Welch PSD estimates per channel and per track section;
* :mod:`.plots`     -- the PSD-versus-standard figure (imported on demand: matplotlib).

Conventions (one-sided PSD in mm²/(1/m), n in cycles/m): docs/irregularity.md.
"""

from .psd import estimate_campaign_psd, section_psds, welch_psd
from .spectra import (SPECTRUM_NAMES, TrackSpectrum, get_spectrum, per_m_to_rad_per_m,
                      psd_per_cycle_to_per_rad, psd_per_rad_to_per_cycle, rad_per_m_to_per_m)
from .synthesis import synthesize_channel, synthesize_from_psd_table, synthesize_profiles

__all__ = [
    "SPECTRUM_NAMES", "TrackSpectrum", "get_spectrum", "per_m_to_rad_per_m",
    "rad_per_m_to_per_m", "psd_per_rad_to_per_cycle", "psd_per_cycle_to_per_rad",
    "synthesize_channel", "synthesize_profiles", "synthesize_from_psd_table",
    "welch_psd", "section_psds", "estimate_campaign_psd",
]
