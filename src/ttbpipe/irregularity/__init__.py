"""Track irregularity: standard spectra, space-domain synthesis and PSD estimation.

* :mod:`.spectra`   -- TB/T 3352-2014, German high-speed and FRA spectra behind one interface
  (:func:`get_spectrum`), plus the rad/m <-> 1/m unit helpers;
* :mod:`.synthesis` -- random profiles from a one-sided PSD by inverse FFT;
* :mod:`.psd`       -- Welch PSD estimates per channel and per track section.

See docs/irregularity.md for conventions.
"""

from .spectra import (SPECTRUM_NAMES, TrackSpectrum, get_spectrum, per_m_to_rad_per_m,
                      psd_per_cycle_to_per_rad, psd_per_rad_to_per_cycle, rad_per_m_to_per_m)

__all__ = [
    "SPECTRUM_NAMES", "TrackSpectrum", "get_spectrum", "per_m_to_rad_per_m",
    "rad_per_m_to_per_m", "psd_per_rad_to_per_cycle", "psd_per_cycle_to_per_rad",
]
