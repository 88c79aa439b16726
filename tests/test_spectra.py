"""Standard track-irregularity spectra (ttbpipe.irregularity.spectra).

Reference values: docs/reference/physics.md section 1 ([C] band RMS values) and closed-form
integrals of the published formulas.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from ttbpipe.channels import SPECTRAL_CHANNELS
from ttbpipe.irregularity.spectra import (SPECTRUM_NAMES, FRASpectrum, GermanHighSpeedSpectrum,
                                          TBT3352Spectrum, get_spectrum, per_m_to_rad_per_m,
                                          psd_per_cycle_to_per_rad, psd_per_rad_to_per_cycle,
                                          rad_per_m_to_per_m)


def test_registry_names_and_interface():
    """Every documented name resolves and exposes the common interface."""
    expected = {"tbt3352", "german_low", "german_high"} | {f"fra_class{c}" for c in range(1, 7)}
    assert set(SPECTRUM_NAMES) == expected
    for name in SPECTRUM_NAMES:
        spectrum = get_spectrum(name)
        assert spectrum.name == name
        assert tuple(spectrum.channels) == SPECTRAL_CHANNELS
        lo, hi = spectrum.valid_wavelength_band_m
        assert 0 < lo < hi
    with pytest.raises(ValueError, match="unknown track spectrum"):
        get_spectrum("tbt3353")


@pytest.mark.parametrize("channel, expected_mm", [
    ("vertical", 1.220), ("alignment", 0.668), ("cross_level", 0.524), ("gauge", 0.344)])
def test_tbt3352_band_rms(channel, expected_mm):
    """TB/T 3352 RMS over 2-200 m equals physics.md §1a [C] within 0.5 %."""
    rms = get_spectrum("tbt3352").band_rms_mm(channel, (2.0, 200.0))
    assert rms == pytest.approx(expected_mm, rel=5e-3)


@pytest.mark.parametrize("channel", SPECTRAL_CHANNELS)
def test_tbt3352_quad_matches_closed_form(channel):
    """band_rms_mm (numerical quad) vs the closed-form integral of the power-law pieces,
    ∫ A n^-k dn = A n^(1-k)/(1-k); tolerance 1e-8 relative (both are exact up to round-off)."""
    spectrum = TBT3352Spectrum()
    breaks, a_coef, k_exp = spectrum.COEFFICIENTS[channel]
    edges = [0.005, *breaks, 0.5]
    variance = sum(a / (1 - k) * (hi ** (1 - k) - lo ** (1 - k))
                   for lo, hi, a, k in zip(edges[:-1], edges[1:], a_coef, k_exp))
    assert spectrum.band_rms_mm(channel) == pytest.approx(math.sqrt(variance), rel=1e-8)


def test_tbt3352_breakpoint_inclusivity_and_continuity():
    """A breakpoint belongs to the higher-frequency segment (documented); segments join within
    0.4 % (physics.md §1a)."""
    spectrum = TBT3352Spectrum()
    for channel in SPECTRAL_CHANNELS:
        breaks, a_coef, k_exp = spectrum.COEFFICIENTS[channel]
        for i, b in enumerate(breaks):
            at = spectrum.psd_mm2_m(channel, b)
            assert at == pytest.approx(a_coef[i + 1] / b ** k_exp[i + 1], rel=1e-14)
            below = a_coef[i] / b ** k_exp[i]
            assert at == pytest.approx(below, rel=4e-3)


def test_valid_band_enforced():
    """Outside the valid band: clear ValueError, unless extrapolate=True (physics.md §7.6)."""
    spectrum = get_spectrum("tbt3352")
    spectrum.psd_mm2_m("vertical", [0.005, 0.5])  # band edges are included
    with pytest.raises(ValueError, match="outside the valid band"):
        spectrum.psd_mm2_m("vertical", [0.001, 0.1])
    with pytest.raises(ValueError, match="outside the valid band"):
        spectrum.band_rms_mm("vertical", (1.0, 200.0))
    assert spectrum.psd_mm2_m("vertical", 0.001, extrapolate=True) > 0
    with pytest.raises(ValueError, match="unknown channel"):
        spectrum.psd_mm2_m("twist", 0.1)
    with pytest.raises(ValueError, match="finite and > 0"):
        spectrum.psd_mm2_m("vertical", 0.0, extrapolate=True)


# physics.md §1b [C], RMS over 2-200 m, rounded to the digits shown. The cross-level value is the
# height RMS (1.23 mrad x 2b = 1.85 mm for the low level; 2.02 mrad x 1.5 m = 3.03 mm for high).
GERMAN_RMS_2_200 = {
    "german_low": {"vertical": 3.26, "alignment": 2.36, "cross_level": 1.23e-3 * 1500, "gauge": 0.34},
    "german_high": {"vertical": 5.33, "alignment": 4.02, "cross_level": 2.02e-3 * 1500, "gauge": 0.47},
}


@pytest.mark.parametrize("name", ["german_low", "german_high"])
@pytest.mark.parametrize("channel", SPECTRAL_CHANNELS)
def test_german_band_rms(name, channel):
    """German spectra, RMS over 2-200 m vs physics.md §1b [C]. That band exceeds the named valid
    band (3-150 m), hence extrapolate=True. Tolerance: half a unit of the last quoted digit
    (the references are rounded to 2-3 digits) -- at most 1.5 %."""
    expected = GERMAN_RMS_2_200[name][channel]
    rms = get_spectrum(name).band_rms_mm(channel, (2.0, 200.0), extrapolate=True)
    # quoted to 3 significant digits except the two-digit gauge values; cross-level in mrad
    half_unit = {"gauge": 0.005, "cross_level": 0.005e-3 * 1500}.get(channel, 0.005)
    assert abs(rms - expected) <= half_unit + 1e-9


def test_german_cross_level_is_angle_times_2b_squared():
    """Cross-level height PSD = (2b)^2 x the published angle PSD, b = 0.75 m (physics.md §7.4)."""
    spectrum = GermanHighSpeedSpectrum("low")
    n = np.geomspace(1 / 150, 1 / 3, 7)
    angle_psd = spectrum.psd_m2_rad("cross_level", 2 * np.pi * n)  # rad^2/(rad/m)
    expected = angle_psd * 1.5 ** 2 * 2 * np.pi * 1e6  # mm^2/(1/m)
    np.testing.assert_allclose(spectrum.psd_mm2_m("cross_level", n), expected, rtol=1e-13)


def test_german_low_vs_tbt_at_0p1():
    """physics.md §1b: at n = 0.1 1/m German-low vertical is 4.06 mm²/(1/m), TB/T 0.46
    (tolerance: half a unit of the quoted digits)."""
    assert abs(get_spectrum("german_low").psd_mm2_m("vertical", 0.1) - 4.06) <= 0.005
    assert abs(get_spectrum("tbt3352").psd_mm2_m("vertical", 0.1) - 0.46) <= 0.005


@pytest.mark.parametrize("name, expected_mm", [("fra_class6", 6.29), ("fra_class5", 15.6)])
def test_fra_vertical_rms(name, expected_mm):
    """FRA vertical RMS vs physics.md §1c [C] (6.29 mm class 6, 15.6 mm class 5). Investigation:
    these values are over FRA's own valid band 1.524-304.8 m (over 2-200 m they would be 5.04 and
    12.5 mm). Tolerance: half a unit of the last quoted digit (<= 0.3 %)."""
    spectrum = get_spectrum(name)
    assert spectrum.valid_wavelength_band_m == (1.524, 304.8)
    rms = spectrum.band_rms_mm("vertical", spectrum.valid_wavelength_band_m)
    half_unit = 0.005 if expected_mm < 10 else 0.05
    assert abs(rms - expected_mm) <= half_unit


def test_fra_vertical_closed_form_all_classes():
    """FRA vertical, second method: with 1/[Ω²(Ω²+Ωc²)] = (1/Ω² - 1/(Ω²+Ωc²))/Ωc², the variance
    over [Ω1, Ω2] is k·Av·[(1/Ω1 - 1/Ω2) - (atan(Ω2/Ωc) - atan(Ω1/Ωc))/Ωc] cm²; tolerance 1e-8."""
    for track_class in range(1, 7):
        spectrum = FRASpectrum(track_class)
        w1, w2 = 2 * np.pi / 200.0, 2 * np.pi / 2.0
        wc = spectrum.OMEGA_C
        for channel, a in (("vertical", spectrum.a_vertical), ("alignment", spectrum.a_alignment)):
            var_cm2 = spectrum.K * a * ((1 / w1 - 1 / w2) - (math.atan(w2 / wc) - math.atan(w1 / wc)) / wc)
            assert spectrum.band_rms_mm(channel) == pytest.approx(math.sqrt(var_cm2) * 10, rel=1e-8)


def test_fra_cross_level_equals_gauge():
    """FRA: S_c = S_g (physics.md §1c)."""
    spectrum = get_spectrum("fra_class4")
    n = np.geomspace(0.005, 0.5, 11)
    np.testing.assert_array_equal(spectrum.psd_mm2_m("cross_level", n),
                                  spectrum.psd_mm2_m("gauge", n))


def test_frequency_unit_round_trip():
    """1/m -> rad/m -> 1/m is the identity; Ω = 2πn (physics.md §7.1). Tolerance 1e-15 rel."""
    n = np.geomspace(1e-3, 10, 9)
    np.testing.assert_allclose(per_m_to_rad_per_m(n), 2 * np.pi * n, rtol=1e-15)
    np.testing.assert_allclose(rad_per_m_to_per_m(per_m_to_rad_per_m(n)), n, rtol=1e-15)
    g = np.geomspace(1e-4, 1e2, 9)
    np.testing.assert_allclose(psd_per_cycle_to_per_rad(psd_per_rad_to_per_cycle(g)), g, rtol=1e-15)


@pytest.mark.parametrize("name", ["german_low", "german_high", "fra_class1", "fra_class6"])
@pytest.mark.parametrize("channel", SPECTRAL_CHANNELS)
def test_variance_invariant_under_unit_conversion(name, channel):
    """The variance over 3-150 m integrated in the published units (over Ω in rad/m, PSD per
    rad/m) equals the one integrated over n in 1/m of psd_mm2_m: the 2π factors cancel only if
    G_n(n) = 2π·G_Ω(2πn) (physics.md §7.1). Independent quad over Ω; tolerance 1e-7 relative."""
    spectrum = get_spectrum(name)
    if isinstance(spectrum, GermanHighSpeedSpectrum):
        height = 1.5 ** 2 if channel == "cross_level" else 1.0

        def published_mm2(w):
            return spectrum.psd_m2_rad(channel, w) * height * 1e6
    else:
        def published_mm2(w):
            return spectrum.psd_cm2_rad(channel, w) * 100.0
    w1, w2 = 2 * np.pi / 150.0, 2 * np.pi / 3.0
    variance_omega, _ = integrate.quad(published_mm2, w1, w2, epsrel=1e-11, limit=400)
    rms_n = spectrum.band_rms_mm(channel, (3.0, 150.0))
    assert rms_n ** 2 == pytest.approx(variance_omega, rel=1e-7)
