# Stage: study simulation (docs/studies.md). Samples of the TIPM irregularity sets, their forecast
# states and the random parameter fields, simulated in batches by the coupled model.
#
# Every batch is known when the workflow starts (ttbpipe.study.plan): the number of samples of
# each scenario follows from the configuration and, for the TIPM scenarios, from the campaigns'
# chainage, so there is no checkpoint and `snakemake -n` lists exactly the jobs a run will run.
# Each scenario has its own design file, with only its own inputs and parameters, so a new
# inspection campaign leaves the fields and single-excitation designs and batches alone.
# Batch files sit under a digest of the settings their results depend on
# (batches/<digest>/<scenario>/...): changing a setting reruns every affected batch, even after a
# killed run whose batch jobs finished untracked. A batch file's content depends only on its
# samples, never on the batch size or core count.

from snakemake.logging import logger as _smk_logger

from ttbpipe.assessment.study import needs_span_frequencies as _study_needs_span_frequencies
from ttbpipe.assessment.study import resolve_assessment as _study_resolve_assessment
from ttbpipe.inspection.format import InspectionError as _InspectionError
from ttbpipe.study.batch import batch_paths as _study_batch_paths
from ttbpipe.study.design import resolve_scenarios as _study_resolve_scenarios
from ttbpipe.study.design import scenario_labels as _study_scenario_labels
from ttbpipe.study import plan as _study_plan
from ttbpipe.study.samples import resolve_simulation as _study_resolve_simulation
from ttbpipe.tipm.population import population_dates as _tipm_population_dates_of

STUDY_SIMULATION = _study_resolve_simulation(config["simulation"])
STUDY_SCENARIOS = _study_resolve_scenarios(config["study"])
STUDY_BATCH_ROOT = results_path("study/batches")
_STUDY_HORIZONS = [float(h) for h in TIPM["forecast"]["horizons_months"]]
STUDY = config["study"]
if STUDY_SCENARIOS["forecast"]["enabled"] and len(CAMPAIGNS) < 2:
    # the spectral evolution needs two campaigns (tipm.smk makes no forecast then)
    _smk_logger.warning("study.scenarios.forecast: only one inspection campaign, no forecast to simulate")
    STUDY = {**STUDY, "scenarios": {**STUDY.get("scenarios", {}),
                                    "forecast": {**STUDY_SCENARIOS["forecast"], "enabled": False}}}
STUDY_LABELS = _study_scenario_labels(STUDY, TIPM_LAST, _STUDY_HORIZONS)
STUDY_KIND = {label: kind for kind, labels in STUDY_LABELS.items() for label in labels}


def _campaign_sections(date: str) -> int:
    synthetic = config["inspections"].get("synthetic", {}) if date in synthetic_dates() else None
    return _study_plan.campaign_sections(CAMPAIGNS[date], config["psd"]["section_length_m"],
                                         synthetic, inspection_mapping(date))


try:
    if STUDY_LABELS["irregularity"] or STUDY_LABELS["forecast"]:
        _latest_sections = _campaign_sections(TIPM_LAST)
        _population_sections = sum(_campaign_sections(d) for d in _tipm_population_dates_of(
            list(CAMPAIGNS), TIPM_LAST, TIPM["population_campaigns"]))
    else:
        _latest_sections = _population_sections = None
    STUDY_COUNTS = _study_plan.sample_counts({**config, "study": STUDY}, STUDY_LABELS,
                                             latest_sections=_latest_sections,
                                             population_sections=_population_sections)
except (_InspectionError, ValueError, OSError) as _exc:
    raise WorkflowError(f"planning the study's batches: {_exc}") from None
STUDY_SETTINGS = {label: _study_plan.batch_settings(config, kind, MODEL_VERSION)
                  for label, kind in STUDY_KIND.items()}
STUDY_DIGEST = {label: _study_plan.settings_digest(s) for label, s in STUDY_SETTINGS.items()}
STUDY_BATCHES = _study_plan.batch_ranges(STUDY_COUNTS, STUDY_SIMULATION["batch_size"])
# Snakemake threads of a batch job: a LocalCluster batch occupies its workers' cores.
_STUDY_THREADS = (int(STUDY_SIMULATION["dask"]["local_workers"])
                  if STUDY_SIMULATION["executor"] == "dask"
                  and not (os.environ.get("TTBPIPE_DASK_SCHEDULER")
                           or STUDY_SIMULATION["dask"]["scheduler"]) else 1)

wildcard_constraints:
    first=r"\d{5}",
    last=r"\d{5}",
    digest=r"[0-9a-f]{12}",


def _study_kind(scenario: str) -> str:
    if scenario not in STUDY_KIND:
        raise WorkflowError(f"unknown study scenario {scenario!r}; the configured ones are "
                            f"{sorted(STUDY_KIND)}")
    return STUDY_KIND[scenario]


# The Monte Carlo irregularity scenario's population (case 3: 36 campaigns' PSD tables), pooled
# once per study: every batch reads one file instead of pivoting each campaign's long table again
# (about 2 s per batch), and each batch job has 4 inputs for Snakemake to check, not 39.
STUDY_MC_POPULATION = results_path("study/mc_population.parquet")


rule study_mc_population:
    """The PSD tables of the latest campaign's population pooled into one table, over the
    study's wavelength band (ttbpipe.tipm.population.write_pooled_population)."""
    input:
        psds=lambda wildcards: tipm_population_psds(type("W", (), {"date": TIPM_LAST})),
    output:
        STUDY_MC_POPULATION,
    params:
        wavelength_band_m=config["psd"].get("wavelength_band_m"),
        version=MODEL_VERSION,
    log:
        log_path("study/mc_population.log"),
    script:
        "../scripts/study_mc_population.py"


def study_design_inputs(wildcards) -> dict[str, str]:
    """TIPM tables one scenario's design needs (none for the fields and single scenarios)."""
    kind = _study_kind(wildcards.scenario)
    if kind == "irregularity":
        return {"weights": f"{RESULTS}/tipm/selection/{TIPM_LAST}.weights.parquet"}
    if kind == "forecast":
        return {"states": results_path("tipm/forecast_states.parquet")}
    if kind == "irregularity_mc":   # case 3: the pooled PSD population of the latest campaign
        return {"population": STUDY_MC_POPULATION}
    return {}


def study_design_params(wildcards) -> dict:
    """What one scenario's design depends on, and nothing else (so that a new campaign does not
    rewrite the designs of the scenarios that do not read inspection data)."""
    kind = _study_kind(wildcards.scenario)
    out = {"kind": kind, "seed": STUDY["seed"], "expected_samples": STUDY_COUNTS[wildcards.scenario],
           "scenario": {kind: STUDY_SCENARIOS[kind]} if kind in STUDY_SCENARIOS else {}}
    if kind in ("irregularity", "forecast", "irregularity_mc"):
        out["latest_campaign"] = TIPM_LAST
    if kind == "forecast":
        out["horizons_months"] = _STUDY_HORIZONS
    if kind == "irregularity_mc":   # the band the pooled population was pooled over
        out["wavelength_band_m"] = config["psd"].get("wavelength_band_m")
    return out


rule study_design:
    """The samples of one scenario: index, probability weight, profile, seed entropy."""
    input:
        unpack(study_design_inputs),
    output:
        results_path("study/design/{scenario}.parquet"),
    params:
        design=study_design_params,
        version=MODEL_VERSION,
    log:
        log_path("study/design/{scenario}.log"),
    script:
        "../scripts/study_design.py"


# EN 1990 A2's span frequencies of the study's nominal structure, analysed once per study when a
# batch would need them (the profile selected without f0/f3/span lengths as options).
STUDY_NEEDS_SPANS = bool(STUDY_BATCHES) and _study_needs_span_frequencies(
    _study_resolve_assessment(config.get("assessment")))


rule study_span_frequencies:
    """f0 and f3 of every span of the study's structure (EN 1990 A2 band rule), once per study:
    each batch job would otherwise repeat the modal analysis (about 1.1 s)."""
    output:
        results_path("study/span_frequencies.json"),
    params:
        structure=config.get("structure") or {},
        version=MODEL_VERSION,
    log:
        log_path("study/span_frequencies.log"),
    script:
        "../scripts/span_frequencies.py"


rule study_kernels:
    """Compiles the coupled model's numba kernels into numba's cache once, by a short run of the
    study's nominal case, before any batch starts (ttbpipe.study.kernels): on a fresh checkout
    every batch job would otherwise compile them itself, about 40 s each, the first ones at the
    same time. Its record is an ``ancient`` input of the batches: rerunning it reruns none."""
    output:
        results_path("study/kernels.json"),
    params:
        version=MODEL_VERSION,
    log:
        log_path("study/kernels.log"),
    script:
        "../scripts/study_kernels.py"


def study_batch_inputs(wildcards) -> dict[str, str]:
    """The scenario's design, the irregularity profiles the batch reads, the span frequencies
    and the compiled kernels' record (``ancient``: its time stamp reruns nothing)."""
    kind = _study_kind(wildcards.scenario)
    if wildcards.digest != STUDY_DIGEST[wildcards.scenario]:
        raise WorkflowError(
            f"batch {wildcards.scenario} {wildcards.first}-{wildcards.last}: settings digest "
            f"{wildcards.digest} is not the current one ({STUDY_DIGEST[wildcards.scenario]}): "
            "that folder holds results of other settings or code; ask for the current targets "
            "(snakemake --cores N) instead of an old batch file")
    inputs = {"design": results_path(f"study/design/{wildcards.scenario}.parquet"),
              "kernels": ancient(results_path("study/kernels.json"))}
    if STUDY_NEEDS_SPANS:
        inputs["span_frequencies"] = results_path("study/span_frequencies.json")
    if kind == "irregularity":
        inputs["profiles"] = f"{RESULTS}/tipm/profiles/{TIPM_LAST}.parquet"
    elif kind == "forecast":
        inputs["profiles"] = results_path("tipm/forecast_profiles.parquet")
    elif kind == "irregularity_mc":
        inputs["population"] = STUDY_MC_POPULATION
    return inputs


rule simulate_batch:
    """Coupled runs of samples first..last of one scenario: extremes and time histories."""
    input:
        unpack(study_batch_inputs),
    output:
        extremes=f"{STUDY_BATCH_ROOT}/{{digest}}/{{scenario}}/extremes_{{first}}-{{last}}.parquet",
        histories=f"{STUDY_BATCH_ROOT}/{{digest}}/{{scenario}}/histories_{{first}}-{{last}}.parquet",
    params:
        # what a sample's result depends on (its digest is in the path; not batch_size or the
        # executor: results are identical)
        settings=lambda wildcards: STUDY_SETTINGS[wildcards.scenario],
        version=MODEL_VERSION,
    threads: _STUDY_THREADS
    log:
        log_path("study/batches/{digest}/{scenario}/{first}-{last}.log"),
    script:
        "../scripts/simulate_batch.py"


def study_batch_files(wildcards=None) -> dict[str, list[str]]:
    """Every batch file of the study (known from the plan: no checkpoint)."""
    pairs = [_study_batch_paths(f"{STUDY_BATCH_ROOT}/{STUDY_DIGEST[s]}", s, first, last)
             for s, first, last in STUDY_BATCHES]
    return {"extremes": [p[0] for p in pairs], "histories": [p[1] for p in pairs]}


def study_design_files(wildcards=None) -> list[str]:
    return [results_path(f"study/design/{label}.parquet") for label in STUDY_COUNTS]
