"""Timings and accuracy figures of the irregularity stage. Prints; asserts nothing.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_irregularity.py [--length-km 200]

Prints: synthesis time of one and of four channels (TB/T 3352, 0.25 m), realised RMS against the
band RMS, Welch-vs-target ratios in wide bands for 256/500/1000 m segments on a profile whose
spectrum continues beyond 200 m (the leakage that sets the default segment length), and the time
of section_psds over the whole profile.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from ttbpipe.channels import SPECTRAL_CHANNELS, rails_from_spectral
from ttbpipe.irregularity.psd import section_psds, welch_psd
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.irregularity.synthesis import synthesize_channel, synthesize_profiles

from _timing import timed  # benchmarks/_timing.py (sibling module)

BANDS_M = [(133.0, 200.0), (100.0, 133.0), (50.0, 100.0), (20.0, 50.0), (2.0, 20.0)]


def band_ratios(frequency, psd, spectrum, channel):
    out = []
    for lam_min, lam_max in BANDS_M:
        sel = (frequency >= 1 / lam_max) & (frequency < 1 / lam_min)
        out.append(psd[sel].mean() / spectrum.psd_mm2_m(channel, frequency[sel]).mean()
                   if sel.any() else np.nan)
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--length-km", type=float, default=200.0)
    length_m = parser.parse_args().length_km * 1e3
    dx = 0.25
    spectrum = get_spectrum("tbt3352")

    rng = np.random.default_rng(0)
    t1, _ = timed(lambda: synthesize_channel(spectrum.as_function("vertical"), length_m, dx, rng))
    t4, profiles = timed(lambda: synthesize_profiles(spectrum, length_m, dx, seed=1))
    print(f"synthesis, {length_m / 1e3:g} km at {dx} m ({len(profiles)} samples): "
          f"one channel {t1:.3f} s, four channels {t4:.3f} s")
    print(f"FIGURE irregularity_synthesis_{length_m / 1e3:g}_km_4_channels = {t4:.4g} s")
    for channel in SPECTRAL_CHANNELS:
        rms = np.sqrt(np.mean(profiles[f"{channel}_mm"] ** 2))
        target = spectrum.band_rms_mm(channel)
        print(f"  {channel:12s} RMS {rms:.4f} mm, band RMS 2-200 m {target:.4f} mm "
              f"({100 * (rms / target - 1):+.2f} %)")

    print("Welch / target, spectrum continued to 600 m (leakage), bands "
          + ", ".join(f"{a:g}-{b:g} m" for a, b in BANDS_M))
    for channel in ("vertical", "gauge"):
        z = synthesize_channel(spectrum.as_function(channel, extrapolate=True), length_m, dx,
                               np.random.default_rng(5), (2.0, 600.0))
        for segment in (256.0, 500.0, 1000.0):
            f, p = welch_psd(z, dx, segment)
            ratios = band_ratios(f, p, spectrum, channel)
            print(f"  {channel:9s} segment {segment:6g} m: "
                  + "  ".join("  n/a" if np.isnan(r) else f"{r:5.2f}" for r in ratios))

    rails = rails_from_spectral(*(profiles[f"{c}_mm"].to_numpy() for c in SPECTRAL_CHANNELS))
    campaign = pd.DataFrame({
        "chainage_m": profiles["chainage_m"],
        "vertical_left_mm": rails["z_left"], "vertical_right_mm": rails["z_right"],
        "alignment_left_mm": rails["y_left"], "alignment_right_mm": rails["y_right"],
        "cross_level_mm": profiles["cross_level_mm"], "gauge_mm": profiles["gauge_mm"]})
    ts, table = timed(lambda: section_psds(campaign, 1000.0, 1000.0, wavelength_band_m=(2, 200)), 1)
    print(f"section_psds, {table['section'].nunique()} sections of 1000 m: {ts:.3f} s, "
          f"{len(table)} rows")


if __name__ == "__main__":
    main()
