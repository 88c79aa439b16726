# Stage 1: inspection campaigns -> validated, cleaned tables -> per-section PSDs (one job per
# calendar year of campaigns: rules prepare_campaigns_<year>).


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


def inspection_mapping(date: str) -> dict:
    """inspections.columns / inspections.units for a file of yours; none for a synthetic campaign
    (written in ttbpipe's own names and units). A params entry, so a changed mapping reruns."""
    if date in synthetic_dates():
        return {}
    section = config["inspections"]
    return {key: dict(section[key]) for key in ("columns", "units") if section.get(key)}


# One job per calendar year of campaigns (rule prepare_campaigns_<year>): each campaign file
# validated, cleaned (the documented repairs), and its Welch PSD per track section and channel.
# A job's interpreter and imports (~2.5 s) cost ten times a campaign's work (~0.25 s), so the
# campaigns of a year share them; a new or changed campaign reruns its own year only
# (docs/performance.md, "The workflow around the runs").
for _year, _dates in CAMPAIGN_YEARS.items():

    rule:
        name:
            f"prepare_campaigns_{_year}"
        input:
            [CAMPAIGNS[d] for d in _dates],
        output:
            clean=[results_path(f"inspections/clean/{d}.parquet") for d in _dates],
            repairs=[results_path(f"inspections/clean/{d}.repairs.json") for d in _dates],
            psd=[results_path(f"psd/{d}.parquet") for d in _dates],
        params:
            dates=list(_dates),
            cleaning=config["inspections"].get("cleaning", {}),
            mapping={d: inspection_mapping(d) for d in _dates},
            psd=config["psd"],
            version=MODEL_VERSION,
        resources:
            runtime=20,
            mem_mb=4000,
        log:
            log_path(f"inspections/prepare/{_year}.log"),
        script:
            "../scripts/prepare_campaigns.py"


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
