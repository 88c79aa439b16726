"""TIPM workflow stages on small PSD tables (ttbpipe.tipm.stages, .profiles)."""

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import SPECTRAL_CHANNELS
from ttbpipe.io import write_table
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.tipm import synthetic_population
from ttbpipe.tipm.evolution import SpectralEvolution
from ttbpipe.tipm.stages import (evolution_stage, forecast_base, forecast_stage, population_dates,
                                 profiles_stage, select_stage, validation_stage)

FREQ = np.arange(5, 501, 5) / 1000.0
DATES = [f"2024-{m:02d}-15" for m in range(1, 9)]
PSD_CFG = {"wavelength_band_m": [2.0, 200.0]}
TIPM_CFG = {"profiles": {"length_m": 200.0, "dx_m": 0.25},
            "forecast": {"horizons_months": [2, 3], "levels": [0.05, 0.5, 0.95], "monte_carlo_paths": 50},
            "validation": {"holdout_campaigns": 3, "band": [0.05, 0.95], "monte_carlo_paths": 50}}


@pytest.fixture(scope="module")
def psd_files(tmp_path_factory):
    """Eight monthly campaigns of six 1 km sections whose level grows 3 %/month."""
    folder = tmp_path_factory.mktemp("psd")
    spectrum = get_spectrum("tbt3352")
    mean = np.stack([spectrum.psd_mm2_m(c, FREQ) for c in SPECTRAL_CHANNELS], axis=1)
    paths = []
    for t, date in enumerate(DATES):
        pop = synthetic_population(6, FREQ, mean * 1.03 ** t, np.random.default_rng(t), welch_dof=2.0)
        rows = []
        for s in range(6):
            for c, ch in enumerate(SPECTRAL_CHANNELS):
                rows.append(pd.DataFrame({"section": s, "section_start_m": 1000.0 * s,
                                          "section_end_m": 1000.0 * (s + 1), "channel": ch,
                                          "spatial_frequency_per_m": FREQ,
                                          "psd_mm2_m": pop.psd_mm2_m[s, :, c]}))
        path = folder / f"{date}.parquet"
        write_table(pd.concat(rows, ignore_index=True), path)
        paths.append(str(path))
    return paths


def test_population_never_contains_a_later_campaign():
    assert population_dates(DATES, DATES[3], "all") == DATES[:4]
    assert population_dates(DATES, DATES[3], 2) == DATES[2:4]
    assert population_dates(DATES[:4], DATES[3], "all") == population_dates(DATES, DATES[3], "all")
    with pytest.raises(ValueError, match="not among"):
        population_dates(DATES, "2030-01-01", "all")


def test_selection_of_a_campaign_is_unchanged_by_later_campaigns(psd_files):
    """Must-show 3: campaign 5's selection from the files of campaigns 1-5 equals the one made
    after campaigns 6-8 were added (their files exist but are not in its population)."""
    by_date = dict(zip(DATES, psd_files))
    before = select_stage([by_date[d] for d in population_dates(DATES[:5], DATES[4], "all")],
                          TIPM_CFG, PSD_CFG)
    after = select_stage([by_date[d] for d in population_dates(DATES, DATES[4], "all")],
                         TIPM_CFG, PSD_CFG)
    for a, b in zip(before, after):
        pd.testing.assert_frame_equal(a, b)
    assert before[1]["weight"].sum() == pytest.approx(1.0)
    assert len(before[1]) == 5                       # min(5 sets, 30 sections)


def test_profiles_are_seeded_by_study_seed_date_and_index(psd_files):
    selection, weights, _ = select_stage(psd_files[:2], TIPM_CFG, PSD_CFG)
    a = profiles_stage(selection, weights, DATES[1], TIPM_CFG, PSD_CFG, study_seed=7)
    b = profiles_stage(selection, weights, DATES[1], TIPM_CFG, PSD_CFG, study_seed=7)
    c = profiles_stage(selection, weights, DATES[2], TIPM_CFG, PSD_CFG, study_seed=7)
    pd.testing.assert_frame_equal(a, b)
    assert list(a.columns) == ["sample_index", "chainage_m", "vertical_mm", "alignment_mm",
                               "cross_level_mm", "gauge_mm"]
    assert not np.allclose(a["vertical_mm"], c["vertical_mm"])
    # one sample's profile does not depend on which other samples are synthesised
    one = a[a["sample_index"] == 3]["vertical_mm"].to_numpy()
    from ttbpipe.tipm.profiles import profiles_from_psd_sets
    from ttbpipe.tipm.selection import TIPMSelection
    sel = TIPMSelection.from_long_table(selection, weights)
    alone = profiles_from_psd_sets(sel.psd_mm2_m[3:4], sel.frequency_per_m, sel.channels, [3],
                                   length_m=200.0, dx_m=0.25, study_seed=7, date=DATES[1], stream=0)
    assert np.array_equal(alone["vertical_mm"].to_numpy(), one)


def test_profiles_table_is_read_profile_by_profile(psd_files, tmp_path):
    """write_profiles puts PROFILES_PER_ROW_GROUP whole profiles in each row group (their id
    range in the group's statistics), and a study sample's read_profile gets its profile bit
    for bit as the table in memory has it; an unsorted table is refused."""
    import pyarrow.parquet as pq

    from ttbpipe.study.samples import PROFILE_CHANNELS, read_profile
    from ttbpipe.tipm.profiles import PROFILES_PER_ROW_GROUP, write_profiles

    selection, weights, _ = select_stage(psd_files[:2], TIPM_CFG, PSD_CFG)
    profiles = profiles_stage(selection, weights, DATES[1], TIPM_CFG, PSD_CFG, study_seed=7)
    ids = np.unique(profiles["sample_index"])
    assert ids.size > PROFILES_PER_ROW_GROUP   # more than one row group
    path = write_profiles(profiles, tmp_path / "profiles.parquet", id_column="sample_index",
                          kind="tipm_profiles")
    meta = pq.ParquetFile(path).metadata
    assert meta.num_row_groups == -(-ids.size // PROFILES_PER_ROW_GROUP)
    column = meta.schema.to_arrow_schema().get_field_index("sample_index")
    for g in range(meta.num_row_groups):
        stats = meta.row_group(g).column(column).statistics
        in_group = ids[g * PROFILES_PER_ROW_GROUP:(g + 1) * PROFILES_PER_ROW_GROUP]
        assert (stats.min, stats.max) == (in_group[0], in_group[-1])
    for sample in ids[::-1]:
        expected = profiles[profiles["sample_index"] == sample][["chainage_m", *PROFILE_CHANNELS]]
        pd.testing.assert_frame_equal(read_profile(str(path), "sample_index", int(sample)),
                                      expected.reset_index(drop=True), check_exact=True)
    with pytest.raises(ValueError, match="not sorted by sample_index"):
        write_profiles(profiles.iloc[::-1], tmp_path / "unsorted.parquet",
                       id_column="sample_index", kind="tipm_profiles")


def test_evolution_forecast_and_validation_run_end_to_end(psd_files):
    table, meta = evolution_stage(psd_files, TIPM_CFG, PSD_CFG)
    model = SpectralEvolution.from_table(table, meta)
    assert meta["interval_months"] == pytest.approx(1.0)
    selection, weights, _ = select_stage(psd_files, TIPM_CFG, PSD_CFG)
    base = forecast_base(TIPM_CFG, PSD_CFG, psd_files[-1], selection, weights)
    assert base.n_samples == 6 and np.allclose(base.weights, 1 / 6)      # latest campaign's sections
    sets = forecast_base({**TIPM_CFG, "forecast": {**TIPM_CFG["forecast"], "base": "selection"}},
                         PSD_CFG, psd_files[-1], selection, weights)
    assert sets.n_samples == len(weights)
    forecast, states, profiles = forecast_stage(model, base, DATES[-1], TIPM_CFG, PSD_CFG, study_seed=7)
    assert set(forecast["envelope"]) == {"fixed_p", "monte_carlo"}
    assert set(forecast["target_date"]) == {"2024-10-15", "2024-11-15"}
    assert len(states) == 2 * 3 * 6
    assert set(profiles["profile_index"]) == set(states["profile_index"])
    assert (forecast["psd_mm2_m"] > 0).all()
    # the upper envelope lies above the lower one at every ordinate (p is monotone)
    fx = forecast[forecast["envelope"] == "fixed_p"]
    lo = fx[fx["level"] == 0.05]["psd_mm2_m"].to_numpy()
    hi = fx[fx["level"] == 0.95]["psd_mm2_m"].to_numpy()
    assert np.all(hi >= lo)
    coverage, tqi, summary = validation_stage(psd_files, TIPM_CFG, PSD_CFG, study_seed=7)
    assert summary["held_out_campaigns"] == DATES[-3:]
    assert coverage["coverage_mc"].between(0, 1).all() and len(coverage) == 3 * 4
    assert {"observed", "forecast_mc", "forecast_fixed_p"} == set(tqi["kind"])
