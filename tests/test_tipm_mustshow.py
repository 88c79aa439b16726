"""TIPM acceptance criteria on the synthetic default series (tbt3352, 5 km, 36 monthly
campaigns, seed 1: the data of the default study), through the real cleaning and PSD APIs."""

import numpy as np
import pytest

from ttbpipe.tipm import PSDPopulation, SpectralEvolution, TIPMSelector, forecast_coverage, selection_metrics

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def campaigns():
    from ttbpipe.inspection import clean_campaign
    from ttbpipe.inspection.synthetic import campaign_dates, synthetic_campaign_series
    from ttbpipe.irregularity.psd import estimate_campaign_psd

    dates = campaign_dates("2023-01-15", 36, 1)
    pops = []
    for campaign in synthetic_campaign_series(dates, spectrum="tbt3352", length_km=5.0, seed=1):
        clean, _ = clean_campaign(campaign.table, campaign.date)
        table = estimate_campaign_psd(clean, {"section_length_m": 1000.0, "segment_length_m": 1000.0,
                                              "wavelength_band_m": (2.0, 200.0)}, source=campaign.date)
        pops.append(PSDPopulation.from_long_table(table, campaign.date, (2.0, 200.0)))
    return pops


def test_selection_reproduces_population_statistics(campaigns):
    """At most a tenth of the sections; per-frequency mean and std within 5 % and the section
    RMS distribution not rejected by a two-sample KS test at 5 %, for every channel, for the
    population of every campaign with >= 50 sections (campaigns 10-36)."""
    for t in range(9, 36):
        population = PSDPopulation.concat(campaigns[:t + 1])
        selection = TIPMSelector(fraction=0.1).select(population)
        assert selection.n_samples <= population.n_sections / 10
        metrics = selection_metrics(population, selection)
        assert (metrics["max_rel_error_mean"] < 0.05).all(), (t, metrics)
        assert (metrics["max_rel_error_std"] < 0.05).all(), (t, metrics)
        assert not metrics["rms_ks_rejected"].any(), (t, metrics)


def test_forecast_band_covers_held_out_campaigns(campaigns):
    """Fit on campaigns 1-24, forecast 25-36 from 24: the Monte Carlo 5-95 % band (nominal
    90 %) contains 85-95 % of the observed section ordinates per channel (measured 0.89-0.91,
    docs/tipm.md; the tolerance allows for the 500-path Monte Carlo and the dependence of the
    5 x 496 x 12 ordinates)."""
    model = SpectralEvolution(n_partitions=5, partition_scale="log").fit(campaigns[:24], np.arange(24.0))
    observed = [(float(h), campaigns[23 + h]) for h in range(1, 13)]
    coverage, _, _ = forecast_coverage(model, campaigns[23], observed, (0.05, 0.95), 500,
                                       np.random.default_rng(1))
    per_channel = coverage.groupby("channel")["coverage_mc"].mean()
    assert per_channel.between(0.85, 0.95).all(), per_channel


def test_selection_of_a_campaign_ignores_later_campaigns(campaigns):
    """The population of campaign 24 is campaigns 1-24 whatever follows, and the selection is
    deterministic, so adding campaigns 25-36 leaves it bit-identical."""
    from ttbpipe.tipm.stages import population_dates
    dates = [str(p.sections["campaign_date"].iloc[0]) for p in campaigns]
    by_date = dict(zip(dates, campaigns))
    early = TIPMSelector().select(PSDPopulation.concat(
        by_date[d] for d in population_dates(dates[:24], dates[23], "all")))
    late = TIPMSelector().select(PSDPopulation.concat(
        by_date[d] for d in population_dates(dates, dates[23], "all")))
    assert np.array_equal(early.psd_mm2_m, late.psd_mm2_m)
    assert early.samples.equals(late.samples)
