"""Workflow stages of the TIPM: what each Snakemake script of workflow/rules/tipm.smk calls.

Every function takes file paths and the ``tipm:`` / ``psd:`` configuration and returns tables;
the scripts only read inputs and write outputs. Defaults: :data:`DEFAULTS`, the study schema's
``tipm:`` defaults.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from .. import streams
from ..dates import add_months, months_between
from .distribution import (FIT_COLUMNS, MIN_SECTIONS_FOR_FIT, SUMMARY_COLUMNS,
                           fit_ordinate_distributions, summarize_fits)
from .evolution import SpectralEvolution, forecast_coverage
from .population import PSDPopulation, load_population, pooled_population, population_dates
from .profiles import (STREAM_FORECAST, STREAM_MONTE_CARLO, STREAM_REPRESENTATIVE, date_key,
                       profiles_from_psd_sets)
from .selection import TIPMSelection, TIPMSelector, selection_metrics
from .settings import DEFAULTS, resolve_config

__all__ = ["DEFAULTS", "resolve_config", "load_population", "population_dates",
           "select_stage", "profiles_stage", "distribution_stage", "evolution_stage",
           "forecast_base", "sections_as_selection", "forecast_stage", "validation_stage"]

log = logging.getLogger(__name__)

def selector_from_config(cfg: Mapping[str, Any]) -> TIPMSelector:
    """The TIPM selector of a resolved ``tipm:`` section."""
    s = cfg["selection"]
    return TIPMSelector(fraction=s["fraction"], min_samples=s["min_samples"],
                        max_samples=s.get("max_samples"), method=s["method"],
                        match_variance=s["match_variance"])


def select_stage(psd_paths: Sequence[str | Path], tipm: Mapping[str, Any], psd: Mapping[str, Any]
                 ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(representative PSD long table with weights, weights table, fidelity metrics)."""
    cfg = resolve_config(tipm)
    population = pooled_population(psd_paths, psd.get("wavelength_band_m"))
    selection = selector_from_config(cfg).select(population)
    metrics = selection_metrics(population, selection)
    for row in metrics.itertuples():
        log.info("%s: %d of %d sections; max rel. error mean %.2e, std %.2e; RMS KS p = %.3f",
                 row.channel, row.n_samples, row.n_population, row.max_rel_error_mean,
                 row.max_rel_error_std, row.rms_ks_pvalue)
    return selection.to_long_table(), selection.samples, metrics


def profiles_stage(selection_table: pd.DataFrame, weights: pd.DataFrame, date: str,
                   tipm: Mapping[str, Any], psd: Mapping[str, Any], study_seed: int) -> pd.DataFrame:
    """Space-domain profiles of one campaign's representative sets (stream 0; synthesis
    ``tipm.profiles.amplitudes``)."""
    cfg = resolve_config(tipm)
    selection = TIPMSelection.from_long_table(selection_table, weights)
    return profiles_from_psd_sets(
        selection.psd_mm2_m, selection.frequency_per_m, selection.channels,
        selection.samples["sample_index"].to_list(), length_m=cfg["profiles"]["length_m"],
        dx_m=cfg["profiles"]["dx_m"], study_seed=study_seed, date=date,
        stream=STREAM_REPRESENTATIVE, wavelength_band_m=tuple(psd["wavelength_band_m"]),
        amplitudes=cfg["profiles"]["amplitudes"])


def distribution_stage(psd_paths: Sequence[str | Path], psd: Mapping[str, Any]
                       ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per-frequency fits, per-channel-and-band summary) of a campaign's population."""
    population = pooled_population(psd_paths, psd.get("wavelength_band_m"))
    if population.n_sections < MIN_SECTIONS_FOR_FIT:
        log.warning("population of %d sections: fewer than %d, no distribution fit (empty tables); "
                    "later campaigns enlarge the population", population.n_sections,
                    MIN_SECTIONS_FOR_FIT)
        return pd.DataFrame(columns=FIT_COLUMNS), pd.DataFrame(columns=SUMMARY_COLUMNS)
    fits = fit_ordinate_distributions(population)
    return fits, summarize_fits(fits)


def _fit_evolution(pops: Sequence[PSDPopulation], cfg: Mapping[str, Any]) -> SpectralEvolution:
    e = cfg["evolution"]
    dates = [str(p.sections["campaign_date"].iloc[0]) for p in pops]
    months = [months_between(dates[0], d) for d in dates]
    return SpectralEvolution(e["n_partitions"], e["partition_scale"], e["min_partition_count"]
                             ).fit(pops, months)


def evolution_stage(psd_paths: Sequence[str | Path], tipm: Mapping[str, Any],
                    psd: Mapping[str, Any]) -> tuple[pd.DataFrame, dict]:
    """(fitted model table, model metadata) from every campaign."""
    cfg = resolve_config(tipm)
    model = _fit_evolution(load_population(psd_paths, psd.get("wavelength_band_m")), cfg)
    return model.to_table(), model.metadata()


def sections_as_selection(population: PSDPopulation) -> TIPMSelection:
    """A campaign's own sections as equally weighted PSD sets (the forecast base ``sections``)."""
    n = population.n_sections
    samples = pd.DataFrame({
        "sample_index": np.arange(n), "weight": np.full(n, 1.0 / n), "stratum": np.arange(n),
        "stratum_size": 1, "source_campaign_date": population.sections["campaign_date"].astype(str),
        "source_section": population.sections["section"].to_numpy(),
        "source_section_start_m": population.sections["section_start_m"].to_numpy(float),
        "source_section_end_m": population.sections["section_end_m"].to_numpy(float)})
    selection = TIPMSelection(population.psd_mm2_m, samples["weight"].to_numpy(),
                              population.frequency_per_m, population.channels, samples, "sections")
    for c, channel in enumerate(population.channels):
        samples[f"tqi_{channel}_mm"] = selection.tqi_mm()[:, c]
    return selection


def forecast_base(tipm: Mapping[str, Any], psd: Mapping[str, Any], latest_psd: str | Path,
                  selection_table: pd.DataFrame, weights: pd.DataFrame) -> TIPMSelection:
    """The PSD sets the forecast starts from (``tipm.forecast.base``):

    * ``sections`` (default): the latest campaign's own sections, equal weights — the current
      state of the line, as in the paper's eq. 56 (P(ω; t_i) is the spectrum at t_i) and as in
      the hold-out validation;
    * ``selection``: the latest campaign's TIPM sets, which describe its whole population
      (with ``population_campaigns: all`` the pooled history, not only the current state).
    """
    cfg = resolve_config(tipm)
    if cfg["forecast"]["base"] == "selection":
        return TIPMSelection.from_long_table(selection_table, weights)
    return sections_as_selection(load_population([latest_psd], psd.get("wavelength_band_m"))[0])


def forecast_stage(model: SpectralEvolution, selection: TIPMSelection, base_date: str,
                   tipm: Mapping[str, Any], psd: Mapping[str, Any], study_seed: int
                   ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Forecasts of the PSD sets ``selection`` (see :func:`forecast_base`) at the configured
    horizons.

    Returns (forecast PSD table, forecast states table (one row per profile), profiles
    (synthesis ``tipm.profiles.amplitudes``)).
    ``envelope = "fixed_p"``: eq. 56 iterated with the constant index p = level (the states that
    get profiles); ``envelope = "monte_carlo"``: percentiles of simulated paths (p ~ U(0,1) per
    step), the calibrated predictive band of docs/tipm.md. p = 0.5 is the median path, not the
    mean: increments are right-skewed, so it may fall slightly below the starting spectrum at
    short wavelengths.
    """
    cfg = resolve_config(tipm)
    f = cfg["forecast"]
    if selection.channels != model.channels or selection.frequency_per_m.shape != model.frequency_per_m.shape:
        raise ValueError("the selection and the evolution model have different channels or "
                         "frequency grids; rerun both with one psd configuration")
    horizons = [float(h) for h in f["horizons_months"]]
    levels = [float(p) for p in f["levels"]]
    steps = [model.steps_for(h) for h in horizons]
    rng = np.random.default_rng(np.random.SeedSequence([int(study_seed), date_key(base_date),
                                                        STREAM_MONTE_CARLO]))
    unique_steps = sorted(set(steps))
    mc_band, _ = model.envelope(selection.psd_mm2_m, max(steps), levels, int(f["monte_carlo_paths"]),
                                rng, at_steps=unique_steps)
    rows, states, psd_sets = [], [], []
    for h, n_steps in zip(horizons, steps):
        target = add_months(base_date, h)
        for li, p in enumerate(levels):
            fixed = model.forecast_fixed(selection.psd_mm2_m, n_steps, p)
            mc = mc_band[unique_steps.index(n_steps), li]
            for envelope, values in (("fixed_p", fixed), ("monte_carlo", mc)):
                t = TIPMSelection(values, selection.weights, selection.frequency_per_m,
                                  selection.channels, selection.samples).to_long_table()
                t.insert(0, "level", p)
                t.insert(0, "envelope", envelope)
                t.insert(0, "target_date", target)
                t.insert(0, "horizon_months", h)
                rows.append(t)
            for j, w in zip(selection.samples["sample_index"], selection.weights):
                states.append({"profile_index": len(states), "horizon_months": h, "target_date": target,
                               "steps": n_steps, "level": p, "sample_index": int(j), "weight": float(w)})
            psd_sets.append(fixed)
    states_df = pd.DataFrame(states)
    profiles = profiles_from_psd_sets(
        np.concatenate(psd_sets), selection.frequency_per_m, selection.channels,
        states_df["profile_index"].to_list(), length_m=cfg["profiles"]["length_m"],
        dx_m=cfg["profiles"]["dx_m"], study_seed=study_seed, date=base_date,
        stream=STREAM_FORECAST, wavelength_band_m=tuple(psd["wavelength_band_m"]),
        amplitudes=cfg["profiles"]["amplitudes"])
    profiles = profiles.rename(columns={"sample_index": "profile_index"})
    return pd.concat(rows, ignore_index=True), states_df, profiles


def validation_stage(psd_paths: Sequence[str | Path], tipm: Mapping[str, Any],
                     psd: Mapping[str, Any], study_seed: int
                     ) -> tuple[pd.DataFrame, pd.DataFrame, dict[str, Any]]:
    """Hold-out validation of the evolution model, and TQI bands for the figure.

    Fits on all campaigns but the last ``holdout_campaigns``, forecasts from the last fitted
    campaign to each held-out one and scores the coverage (:func:`forecast_coverage`).
    Returns (coverage table, TQI table for the figure, summary dict).
    """
    cfg = resolve_config(tipm)
    v = cfg["validation"]
    pops = load_population(psd_paths, psd.get("wavelength_band_m"))
    holdout = int(v["holdout_campaigns"])
    if not 0 < holdout <= len(pops) - 3:
        raise ValueError(f"validation needs >= 3 fitted campaigns plus {holdout} held out; there are "
                         f"{len(pops)} campaigns: lower tipm.validation.holdout_campaigns")
    fitted, held = pops[:-holdout], pops[-holdout:]
    model = _fit_evolution(fitted, cfg)
    base = fitted[-1]
    base_date = str(base.sections["campaign_date"].iloc[0])
    observed = [(months_between(base_date, str(p.sections["campaign_date"].iloc[0])), p) for p in held]
    levels = tuple(float(x) for x in v["band"])
    rng = np.random.default_rng(np.random.SeedSequence([int(study_seed), date_key(base_date),
                                                        STREAM_MONTE_CARLO,
                                                        streams.TIPM_VALIDATION_SUBSTREAM]))
    coverage, _, tqi_band = forecast_coverage(model, base, observed, levels,
                                              int(v["monte_carlo_paths"]), rng)
    n_steps = tqi_band.shape[0]
    # TQI (band RMS) for the figure: observed per section, forecast band per section
    rows = []
    for p in pops:
        d = str(p.sections["campaign_date"].iloc[0])
        tqi = p.tqi_mm()
        for i, sec in enumerate(p.sections["section_start_m"]):
            for c, ch in enumerate(p.channels):
                rows.append({"kind": "observed", "campaign_date": d, "months": months_between(base_date, d),
                             "section_start_m": float(sec), "channel": ch, "level": np.nan,
                             "tqi_mm": float(tqi[i, c])})
    for s in range(n_steps):
        months = (s + 1) * model.interval_months
        for li, level in enumerate((levels[0], 0.5, levels[1])):
            for i, sec in enumerate(base.sections["section_start_m"]):
                for c, ch in enumerate(base.channels):
                    rows.append({"kind": "forecast_mc", "campaign_date": "", "months": months,
                                 "section_start_m": float(sec), "channel": ch, "level": level,
                                 "tqi_mm": float(tqi_band[s, li, i, c])})
    for level in (levels[0], 0.5, levels[1]):
        state = base.psd_mm2_m
        for s in range(n_steps):
            state = model.forecast_fixed(state, 1, level)
            tqi = np.sqrt(state.sum(axis=1) * base.delta_n_per_m)
            for i, sec in enumerate(base.sections["section_start_m"]):
                for c, ch in enumerate(base.channels):
                    rows.append({"kind": "forecast_fixed_p", "campaign_date": "",
                                 "months": (s + 1) * model.interval_months,
                                 "section_start_m": float(sec), "channel": ch, "level": level,
                                 "tqi_mm": float(tqi[i, c])})
    per_channel = coverage.groupby("channel", sort=False)[["coverage_mc", "coverage_fixed_p"]].mean()
    summary = {"fitted_campaigns": [str(p.sections["campaign_date"].iloc[0]) for p in fitted],
               "held_out_campaigns": [str(p.sections["campaign_date"].iloc[0]) for p in held],
               "nominal_coverage": levels[1] - levels[0],
               "coverage_mc": per_channel["coverage_mc"].to_dict(),
               "coverage_fixed_p": per_channel["coverage_fixed_p"].to_dict(),
               "model": model.metadata()}
    return coverage, pd.DataFrame(rows), summary
