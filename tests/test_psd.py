"""Welch PSD estimation per channel and section (ttbpipe.irregularity.psd).

References: Parseval's theorem (the one-sided density integrates to the variance), a pure
sinusoid of known power A²/2, physics.md §2 (Welch on a synthetic TB/T profile, ∫G dn ≈ var).
"""

import logging

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import INSPECTION_COLUMNS, SPECTRAL_CHANNELS, rails_from_spectral
from ttbpipe.irregularity.psd import (PSD_COLUMNS, estimate_campaign_psd, sample_spacing_m,
                                      section_psds, welch_psd)
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.irregularity.synthesis import synthesize_profiles


def campaign_from_spectral(profiles: pd.DataFrame) -> pd.DataFrame:
    """Per-rail inspection table from synthesised spectral channels (channels.py conventions)."""
    rails = rails_from_spectral(profiles["vertical_mm"].to_numpy(), profiles["alignment_mm"].to_numpy(),
                                profiles["cross_level_mm"].to_numpy(), profiles["gauge_mm"].to_numpy())
    return pd.DataFrame({
        "chainage_m": profiles["chainage_m"],
        "vertical_left_mm": rails["z_left"], "vertical_right_mm": rails["z_right"],
        "alignment_left_mm": rails["y_left"], "alignment_right_mm": rails["y_right"],
        "cross_level_mm": profiles["cross_level_mm"], "gauge_mm": profiles["gauge_mm"],
    })


@pytest.fixture(scope="module")
def synthetic_profiles():
    """5.25 km of TB/T 3352 profiles at 0.25 m (5 full 1000 m sections + 250.25 m)."""
    return synthesize_profiles("tbt3352", 5250.0, 0.25, seed=4)


@pytest.fixture(scope="module")
def synthetic_campaign(synthetic_profiles):
    return campaign_from_spectral(synthetic_profiles)


def test_parseval_white_noise():
    """White noise of variance 4 mm²: ∑G Δn over all Welch bins equals the variance (Parseval,
    scaling='density', one-sided). Tolerance 1 %: 2^20 samples, 4096-point segments give ~500
    averages, so the statistical error of the mean is ~0.1 %."""
    rng = np.random.default_rng(0)
    profile = rng.normal(0.0, 2.0, 2 ** 20)
    dx = 0.25
    frequencies, psd = welch_psd(profile, dx, segment_length_m=1024.0)
    delta_n = frequencies[1] - frequencies[0]
    assert delta_n == pytest.approx(1 / 1024.0)
    assert frequencies[-1] == pytest.approx(0.5 / dx)  # Nyquist of fs = 1/dx
    assert np.sum(psd) * delta_n == pytest.approx(np.var(profile), rel=0.01)
    # flat one-sided level 2σ²Δx of white noise, averaged over bins; 1 %
    assert np.mean(psd[1:-1]) == pytest.approx(2 * 4.0 * dx, rel=0.01)


def test_sinusoid_power_and_frequency():
    """z = 3 cos(2π·0.05 x) mm: the peak sits at 0.05 1/m and the PSD integrates to A²/2 = 4.5 mm²
    (Hann window, density scaling). Tolerance 0.5 % (the wave is bin-centred, no leakage loss)."""
    dx = 0.25
    x = np.arange(400_000) * dx
    profile = 3.0 * np.cos(2 * np.pi * 0.05 * x + 0.3)
    frequencies, psd = welch_psd(profile, dx, segment_length_m=1000.0, overlap=0.5)
    assert frequencies[np.argmax(psd)] == pytest.approx(0.05)
    assert np.sum(psd) * (frequencies[1] - frequencies[0]) == pytest.approx(4.5, rel=5e-3)


def test_parseval_synthetic_tbt_profile(synthetic_profiles):
    """TB/T profile band-limited to 2-200 m: ∫G dn of the full Welch estimate equals the variance
    of the (linearly detrended) profile; tolerance 5 % (5 km: the detrend of each segment removes
    part of the longest waves, the rest is round-off)."""
    profile = synthetic_profiles["vertical_mm"].to_numpy()
    frequencies, psd = welch_psd(profile, 0.25, segment_length_m=1000.0)
    variance = np.sum(psd) * (frequencies[1] - frequencies[0])
    assert variance == pytest.approx(np.var(profile), rel=0.05)


def test_section_psds_shape_and_columns(synthetic_campaign, caplog):
    """Long-format table: 5 full sections x 4 channels x 496 band frequencies (1000 m segments:
    Δn = 0.001 1/m, 0.005..0.5 inclusive); the 250 m tail is dropped with a logged count."""
    with caplog.at_level(logging.WARNING, logger="ttbpipe.irregularity.psd"):
        table = section_psds(synthetic_campaign, 1000.0, 1000.0, 0.5, "hann", "linear", (2.0, 200.0))
    assert list(table.columns) == list(PSD_COLUMNS)
    assert table["section"].dtype == np.int64
    assert sorted(table["section"].unique()) == [0, 1, 2, 3, 4]
    assert set(table["channel"]) == set(SPECTRAL_CHANNELS)
    n_freq = 496
    assert len(table) == 5 * 4 * n_freq
    assert table.groupby(["section", "channel"]).size().eq(n_freq).all()
    first = table[table["section"] == 3].iloc[0]
    assert first["section_start_m"] == 3000.0 and first["section_end_m"] == 4000.0
    f = table["spatial_frequency_per_m"]
    assert f.min() == pytest.approx(0.005) and f.max() == pytest.approx(0.5)
    assert (table["psd_mm2_m"] > 0).all()
    assert "dropped the last partial section: 1001 samples (250.25 m)" in caplog.text


def test_section_psds_uses_spectral_channels(synthetic_campaign, synthetic_profiles):
    """The per-rail columns are recombined into the spectral channels (channels.py): the section
    PSD of 'vertical' equals welch_psd of the synthesised vertical channel. Tolerance 1e-9 rel."""
    table = section_psds(synthetic_campaign, 1000.0, 500.0)
    rows = table[(table["section"] == 1) & (table["channel"] == "alignment")]
    frequencies, psd = welch_psd(synthetic_profiles["alignment_mm"].to_numpy()[4000:8000], 0.25, 500.0)
    np.testing.assert_allclose(rows["spatial_frequency_per_m"], frequencies[1:], rtol=1e-12)
    # round-off of the per-rail round trip (a + g/2 + a - g/2)/2 matters only where the PSD is
    # ~1e-9 of its peak, hence an absolute tolerance relative to the peak
    np.testing.assert_allclose(rows["psd_mm2_m"], psd[1:], rtol=1e-9, atol=1e-9 * psd.max())


def test_section_psds_mean_matches_standard():
    """Per-section 1000 m periodograms of a 20 km TB/T profile vs the standard: the mean over
    sections and bins of the ratio estimate/target in three bands (100-20 m, 20-4 m, 4-2 m) is
    within 20 %. Source of the tolerance: each ratio is ~χ²₂/2 (mean 1, CV 100 %); the band with
    fewest ordinates has 40 bins x 20 sections, i.e. a CV of ~5 % allowing for the correlation of
    adjacent Hann bins, plus a leakage bias of a few % (docs/irregularity.md)."""
    spectrum = get_spectrum("tbt3352")
    campaign = campaign_from_spectral(synthesize_profiles(spectrum, 20_000.0, 0.25, seed=8))
    table = section_psds(campaign, 1000.0, 1000.0, wavelength_band_m=(2.0, 200.0))
    assert table["section"].nunique() == 20
    for channel in SPECTRAL_CHANNELS:
        rows = table[table["channel"] == channel]
        f = rows["spatial_frequency_per_m"].to_numpy()
        ratio = rows["psd_mm2_m"].to_numpy() / spectrum.psd_mm2_m(channel, f)
        for lo, hi in [(0.01, 0.05), (0.05, 0.25), (0.25, 0.5)]:
            band_ratio = ratio[(f >= lo) & (f < hi)].mean()
            assert band_ratio == pytest.approx(1.0, rel=0.20), (channel, lo, band_ratio)


def test_segment_longer_than_section_fails(synthetic_campaign):
    with pytest.raises(ValueError, match="exceeds the section length"):
        section_psds(synthetic_campaign, 500.0, 1000.0)


def test_campaign_shorter_than_a_section_fails(synthetic_campaign):
    with pytest.raises(ValueError, match="no full 10000 m section"):
        section_psds(synthetic_campaign, 10_000.0, 1000.0)


def test_bad_input_named(synthetic_campaign):
    """Missing columns, irregular chainage (row named) and NaN values fail clearly."""
    with pytest.raises(ValueError, match="missing columns"):
        section_psds(synthetic_campaign.drop(columns="gauge_mm"), 1000.0, 500.0)
    irregular = synthetic_campaign.copy()
    irregular.loc[100:, "chainage_m"] += 0.1
    with pytest.raises(ValueError, match="row 100, column chainage_m"):
        section_psds(irregular, 1000.0, 500.0, source="x.parquet")
    holey = synthetic_campaign.copy()
    holey.loc[77, "cross_level_mm"] = np.nan
    with pytest.raises(ValueError, match="row 77: non-finite value in channel cross_level"):
        section_psds(holey, 1000.0, 500.0)
    with pytest.raises(ValueError, match="non-finite samples"):
        welch_psd(np.array([1.0, np.nan] * 100), 0.25, 10.0)
    with pytest.raises(ValueError, match="exceeds the profile"):
        welch_psd(np.zeros(100), 0.25, 100.0)


def test_sample_spacing():
    assert sample_spacing_m(np.arange(10) * 0.25 + 1000.0) == 0.25
    with pytest.raises(ValueError, match="not increasing"):
        sample_spacing_m(np.arange(10)[::-1] * 1.0)


def test_estimate_campaign_psd_reads_config(synthetic_campaign):
    """The config psd section (with its extra reference_spectrum key) drives section_psds."""
    config = {"section_length_m": 2000.0, "segment_length_m": 1000.0, "overlap": 0.5,
              "window": "hann", "detrend": "linear", "wavelength_band_m": [2.0, 200.0],
              "reference_spectrum": "tbt3352"}
    table = estimate_campaign_psd(synthetic_campaign, config)
    assert sorted(table["section"].unique()) == [0, 1]
    assert table["section_end_m"].max() == 4000.0
    assert set(INSPECTION_COLUMNS).isdisjoint(table.columns)


def test_cli_psd_clean_and_raw(tmp_path, synthetic_campaign):
    """`ttbpipe psd` on a cleaned Parquet (provenance kind "inspection_clean") and on a raw CSV
    (cleaned first by ttbpipe.inspection) writes the same table with provenance kind "psd";
    a segment longer than the section exits with status 1 and writes nothing."""
    from ttbpipe.cli import main
    from ttbpipe.io import read_provenance, read_table, write_table

    campaign = synthetic_campaign.iloc[:8001].copy()  # 0..2000 m
    clean_path = write_table(campaign, tmp_path / "2024-01-01.parquet", kind="inspection_clean")
    raw_path = tmp_path / "2024-01-01.csv"
    campaign.to_csv(raw_path, index=False)
    out_clean, out_raw = tmp_path / "psd_clean.parquet", tmp_path / "psd_raw.parquet"
    assert main(["psd", str(clean_path), "--section-length-m", "1000", "--out", str(out_clean)]) == 0
    assert main(["psd", str(raw_path), "--section-length-m", "1000", "--out", str(out_raw)]) == 0
    from_clean, from_raw = read_table(out_clean), read_table(out_raw)
    assert list(from_clean.columns) == list(PSD_COLUMNS)
    assert from_clean["section"].nunique() == 2
    assert read_provenance(out_clean)["kind"] == "psd"
    assert read_provenance(out_clean)["config"]["psd"]["segment_length_m"] == 1000.0
    # the raw file went through the inspection cleaning (linear detrend per file), so the
    # estimates agree closely but not bit for bit: 1 % on the band-averaged PSD
    assert from_raw["psd_mm2_m"].mean() == pytest.approx(from_clean["psd_mm2_m"].mean(), rel=0.01)
    # a raw file with its own column names and units, read through the --config mapping
    import yaml

    own = campaign.rename(columns={"chainage_m": "KM"}).assign(KM=campaign["chainage_m"] / 1000)
    own_path = tmp_path / "2024-01-02.csv"
    own.to_csv(own_path, index=False, float_format="%.10g")
    config = tmp_path / "study.yaml"
    config.write_text(yaml.safe_dump({"inspections": {"columns": {"KM": "chainage_m"},
                                                      "units": {"chainage": "km"}}}))
    out_own = tmp_path / "psd_own.parquet"
    assert main(["psd", str(own_path), "--section-length-m", "1000", "--out", str(out_own)]) == 1
    assert main(["psd", str(own_path), "--section-length-m", "1000", "--config", str(config),
                 "--out", str(out_own)]) == 0
    np.testing.assert_allclose(read_table(out_own)["psd_mm2_m"], from_raw["psd_mm2_m"],
                               rtol=1e-6)
    bad_out = tmp_path / "bad.parquet"
    assert main(["psd", str(clean_path), "--section-length-m", "500", "--segment-length-m",
                 "1000", "--out", str(bad_out)]) == 1
    assert not bad_out.exists()


def test_plot_psd_vs_standard(tmp_path, synthetic_campaign):
    """Figure: 2x2 log-log panels; the thick dashed line is the reference standard's PSD over
    the band (exact values, rtol 1e-12); the 5-95 % band and one line per campaign are drawn."""
    from ttbpipe.io import save_figure
    from ttbpipe.irregularity.plots import plot_psd_vs_standard

    table = section_psds(synthetic_campaign, 1000.0, 1000.0, wavelength_band_m=(2.0, 200.0))
    tables = {"2024-01-15": table, "2024-02-15": table.assign(psd_mm2_m=table["psd_mm2_m"] * 2)}
    fig = plot_psd_vs_standard(tables, "tbt3352", (2.0, 200.0))
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["Vertical profile", "Alignment", "Cross-level", "Gauge"]
    spectrum = get_spectrum("tbt3352")
    for ax, channel in zip(panels, SPECTRAL_CHANNELS):
        assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
        assert "(1/m)" in ax.get_xlabel() and "mm²/(1/m)" in ax.get_ylabel()
        dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
        assert len(dashed) == 1
        n, psd = dashed[0].get_data()
        assert n.min() == pytest.approx(0.005) and n.max() == pytest.approx(0.5)
        np.testing.assert_allclose(psd, spectrum.psd_mm2_m(channel, n), rtol=1e-12)
        solid = [line for line in ax.get_lines() if line.get_linestyle() == "-"]
        assert len(solid) == 2  # one mean line per campaign
        assert len(ax.collections) >= 1  # percentile band
    path = save_figure(fig, tmp_path / "psd.png")
    assert path.stat().st_size > 10_000


def _section_matrix_reference(tables, channel, grid):
    """Obviously correct: one pandas group per section, each sorted by frequency."""
    rows, freq = [], grid
    for table in tables.values():
        for _, section in table[table["channel"] == channel].groupby("section"):
            section = section.sort_values("spatial_frequency_per_m")
            f = section["spatial_frequency_per_m"].to_numpy()
            p = section["psd_mm2_m"].to_numpy()
            if grid is None:
                freq = f
                rows.append(p)
            else:
                ok = (f > 0) & (p > 0)
                rows.append(np.exp(np.interp(np.log(grid), np.log(f[ok]), np.log(p[ok]),
                                             left=np.nan, right=np.nan)))
    return np.asarray(freq), np.vstack(rows)


@pytest.mark.parametrize("common_grid", [False, True])
def test_section_matrix_equals_the_per_section_groups(synthetic_campaign, common_grid):
    """The figure's section matrix (one sort per table) equals the per-section pandas groups
    bit for bit, rows shuffled and section labels out of order; on a common grid too, where
    sections interpolate onto it and the percentile band then skips NaN."""
    from ttbpipe.irregularity.plots import _section_matrix

    table = section_psds(synthetic_campaign, 500.0, 250.0, wavelength_band_m=(2.0, 200.0))
    rng = np.random.default_rng(7)
    shuffled = table.sample(frac=1.0, random_state=3).reset_index(drop=True)
    relabelled = table.assign(section=table["section"].max() - table["section"],
                              psd_mm2_m=table["psd_mm2_m"] * rng.uniform(0.5, 2.0, len(table)))
    tables = {"2024-01-15": shuffled, "2024-02-15": relabelled}
    freq = np.sort(table["spatial_frequency_per_m"].unique())
    grid = np.geomspace(freq[freq > 0][0] * 0.9, freq[-1], 50) if common_grid else None
    for channel in SPECTRAL_CHANNELS:
        got_f, got = _section_matrix(tables, channel, grid)
        want_f, want = _section_matrix_reference(tables, channel, grid)
        assert got.shape == want.shape and got.shape[0] == 2 * table["section"].nunique()
        np.testing.assert_array_equal(got_f, want_f)
        np.testing.assert_array_equal(got, want)
        assert np.isnan(got).any() == common_grid   # the grid starts below the sections' range
