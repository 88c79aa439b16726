# Stage: track irregularity probabilistic model (TIPM) and spectral evolution
# (seed paper sec. 3.2-3.3 and 5.3-5.4; docs/tipm.md).
#
# Incremental by construction: campaign t's selection, profiles and distribution fit read only
# the PSDs of campaigns up to t (tipm.population_campaigns), so adding a later campaign reruns
# nothing of earlier campaigns; the evolution model, the forecast and the hold-out validation
# genuinely depend on every campaign and are refitted.

from ttbpipe.tipm.population import population_dates as _tipm_population_dates

TIPM = config.get("tipm", {})
TIPM_LAST = list(CAMPAIGNS)[-1]
# What the TIPM jobs compute from (params): not which campaigns are targets, so that asking for
# every campaign's selection does not rerun the latest one's.
TIPM_MODEL = {key: value for key, value in TIPM.items() if key != "campaign_selections"}


def tipm_population_psds(wildcards) -> list[str]:
    """PSD tables of the campaigns forming campaign {date}'s population (never a later one)."""
    dates = _tipm_population_dates(list(CAMPAIGNS), wildcards.date,
                                   TIPM.get("population_campaigns", "all"))
    return [f"{RESULTS}/psd/{d}.parquet" for d in dates]


rule tipm_select:
    """Representative PSD sets with probability weights for one campaign's population, and
    their space-domain profiles (one job per campaign: selection and profiles are cheap)."""
    input:
        tipm_population_psds,
    output:
        selection=results_path("tipm/selection/{date}.parquet"),
        weights=results_path("tipm/selection/{date}.weights.parquet"),
        metrics=results_path("tipm/selection/{date}.metrics.parquet"),
        profiles=results_path("tipm/profiles/{date}.parquet"),
    params:
        tipm=TIPM_MODEL,
        psd=config["psd"],
        seed=config["study"]["seed"],
        version=MODEL_VERSION,
    log:
        log_path("tipm/select/{date}.log"),
    script:
        "../scripts/tipm_select.py"


rule tipm_distribution:
    """Per-frequency lognormal and gamma fits of the PSD ordinates of one campaign's population."""
    input:
        tipm_population_psds,
    output:
        fits=results_path("tipm/distribution/{date}.parquet"),
        summary=results_path("tipm/distribution/{date}.summary.parquet"),
    params:
        psd=config["psd"],
        version=MODEL_VERSION,
    log:
        log_path("tipm/distribution/{date}.log"),
    script:
        "../scripts/tipm_distribution.py"


rule tipm_evolution:
    """Spectral evolution model (eqs. 50-53) fitted on every campaign."""
    input:
        expand(results_path("psd/{date}.parquet"), date=CAMPAIGNS),
    output:
        results_path("tipm/evolution.parquet"),
    params:
        tipm=TIPM_MODEL,
        psd=config["psd"],
        version=MODEL_VERSION,
    log:
        log_path("tipm/evolution.log"),
    script:
        "../scripts/tipm_evolution.py"


rule tipm_forecast:
    """Forecast (eqs. 54, 56) of the latest campaign's sections (or TIPM sets) and profiles."""
    input:
        model=results_path("tipm/evolution.parquet"),
        selection=f"{RESULTS}/tipm/selection/{TIPM_LAST}.parquet",
        weights=f"{RESULTS}/tipm/selection/{TIPM_LAST}.weights.parquet",
        latest_psd=f"{RESULTS}/psd/{TIPM_LAST}.parquet",
    output:
        forecast=results_path("tipm/forecast.parquet"),
        states=results_path("tipm/forecast_states.parquet"),
        profiles=results_path("tipm/forecast_profiles.parquet"),
        figure=report(
            results_path("figures/tipm_forecast_spectra.png"),
            caption="../report/tipm_forecast_spectra.rst",
            category="3. TIPM and spectral evolution",
        ),
    params:
        tipm=TIPM_MODEL,
        psd=config["psd"],
        seed=config["study"]["seed"],
        base_date=TIPM_LAST,
        version=MODEL_VERSION,
    log:
        log_path("tipm/forecast.log"),
    script:
        "../scripts/tipm_forecast.py"


rule tipm_validate:
    """Hold-out validation: fit on all but the last campaigns, forecast them, score coverage."""
    input:
        expand(results_path("psd/{date}.parquet"), date=CAMPAIGNS),
    output:
        coverage=results_path("tipm/validation/coverage.parquet"),
        tqi=results_path("tipm/validation/tqi.parquet"),
        summary=results_path("tipm/validation/summary.json"),
        figure=report(
            results_path("figures/tipm_forecast.png"),
            caption="../report/tipm_forecast.rst",
            category="3. TIPM and spectral evolution",
        ),
    params:
        tipm=TIPM_MODEL,
        psd=config["psd"],
        seed=config["study"]["seed"],
        version=MODEL_VERSION,
    log:
        log_path("tipm/validate.log"),
    script:
        "../scripts/tipm_validate.py"


rule tipm_figures:
    """PSD percentile bands and the selected sets against the population (latest campaign)."""
    input:
        psd=lambda wildcards: tipm_population_psds(wildcards),
        selection=results_path("tipm/selection/{date}.parquet"),
        weights=results_path("tipm/selection/{date}.weights.parquet"),
        metrics=results_path("tipm/selection/{date}.metrics.parquet"),
    output:
        bands=report(
            results_path("figures/tipm_psd_bands_{date}.png"),
            caption="../report/tipm_psd_bands.rst",
            category="3. TIPM and spectral evolution",
        ),
        fidelity=report(
            results_path("figures/tipm_selection_{date}.png"),
            caption="../report/tipm_selection.rst",
            category="3. TIPM and spectral evolution",
        ),
    params:
        psd=config["psd"],
        version=MODEL_VERSION,
    log:
        log_path("tipm/figures/{date}.log"),
    script:
        "../scripts/tipm_figures.py"


def tipm_targets() -> list[str]:
    """Final TIPM outputs: the latest campaign's selection, profiles, distribution fit and
    figures (every campaign's selection and profiles with tipm.campaign_selections: all), the
    forecast and the hold-out validation."""
    selected = CAMPAIGNS if TIPM["campaign_selections"] == "all" else [TIPM_LAST]
    targets = expand(results_path("tipm/profiles/{date}.parquet"), date=selected)
    targets += [
        f"{RESULTS}/tipm/distribution/{TIPM_LAST}.parquet",
        f"{RESULTS}/figures/tipm_psd_bands_{TIPM_LAST}.png",
        f"{RESULTS}/figures/tipm_selection_{TIPM_LAST}.png",
    ]
    if len(CAMPAIGNS) >= 2:
        targets.append(results_path("tipm/forecast.parquet"))
    holdout = int(TIPM.get("validation", {}).get("holdout_campaigns", 12))
    if len(CAMPAIGNS) >= holdout + 3:
        targets.append(results_path("tipm/validation/summary.json"))
    return targets
