# Stage 1: inspection campaigns -> validated, cleaned tables -> per-section PSDs (one job per
# campaign: rule prepare_campaign).


rule synth_inspections:
    """Write the synthetic default campaign series (the embedded default data)."""
    output:
        expand(
            "{directory}/{date}.parquet",
            directory=config["inspections"].get("synthetic", {}).get("directory", "resources/inspections/synthetic"),
            date=synthetic_dates(),
        ),
    params:
        synthetic=config["inspections"].get("synthetic", {}),
        dates=synthetic_dates(),
        version=MODEL_VERSION,
    log:
        log_path("inspections/synth_inspections.log"),
    script:
        "../scripts/synth_inspections.py"


def inspection_mapping(wildcards) -> dict:
    """inspections.columns / inspections.units for a file of yours; none for a synthetic campaign
    (written in ttbpipe's own names and units). A params entry, so a changed mapping reruns."""
    if wildcards.date in synthetic_dates():
        return {}
    section = config["inspections"]
    return {key: dict(section[key]) for key in ("columns", "units") if section.get(key)}


rule prepare_campaign:
    """One campaign file: validated, cleaned (the documented repairs), and its Welch PSD per
    track section and channel. One job per campaign: a job's interpreter and imports cost more
    than the work (docs/performance.md), and a new campaign still runs only its own job."""
    input:
        campaign_file,
    output:
        clean=results_path("inspections/clean/{date}.parquet"),
        repairs=results_path("inspections/clean/{date}.repairs.json"),
        psd=results_path("psd/{date}.parquet"),
    params:
        cleaning=config["inspections"].get("cleaning", {}),
        mapping=inspection_mapping,
        psd=config["psd"],
        version=MODEL_VERSION,
    log:
        log_path("inspections/prepare/{date}.log"),
    script:
        "../scripts/prepare_campaign.py"


rule plot_psd_vs_standard:
    """Estimated PSDs of all campaigns against the standard spectrum, per channel."""
    input:
        expand(results_path("psd/{date}.parquet"), date=CAMPAIGNS),
    output:
        report(
            results_path("figures/psd_vs_standard.png"),
            caption="../report/psd_vs_standard.rst",
            category="2. Track irregularity",
        ),
    params:
        psd=config["psd"],
        version=MODEL_VERSION,
    log:
        log_path("psd/plot_psd_vs_standard.log"),
    script:
        "../scripts/plot_psd_vs_standard.py"
