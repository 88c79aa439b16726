# Stage: study simulation (issue 7; docs/studies.md). Samples of the TIPM irregularity sets, their
# forecast states and the random parameter fields, simulated in batches by the coupled model.
#
# The number of TIPM representative sets depends on the data (the campaigns' sections), so the
# design is a checkpoint: `study_design` lists every sample (scenario, sample_index, weight, seed)
# and the batch jobs appear once it exists. Scenario labels are known from the configuration.
# A batch file's content depends only on its samples, never on the batch size or core count.

import pandas as _pd
from snakemake.logging import logger as _smk_logger

from ttbpipe.study.batch import batch_paths as _study_batch_paths
from ttbpipe.study.design import batches as _study_batches
from ttbpipe.study.design import resolve_scenarios as _study_resolve_scenarios
from ttbpipe.study.design import scenario_labels as _study_scenario_labels
from ttbpipe.study.samples import resolve_simulation as _study_resolve_simulation

STUDY_SIMULATION = _study_resolve_simulation(config.get("simulation"))
STUDY_SCENARIOS = _study_resolve_scenarios(config["study"])
STUDY_BATCH_ROOT = results_path("study/batches")
_STUDY_HORIZONS = [float(h) for h in TIPM.get("forecast", {}).get("horizons_months", [6, 12])]
STUDY = config["study"]
if STUDY_SCENARIOS["forecast"]["enabled"] and len(CAMPAIGNS) < 2:
    # the spectral evolution needs two campaigns (tipm.smk makes no forecast then)
    _smk_logger.warning("study.scenarios.forecast: only one inspection campaign, no forecast to simulate")
    STUDY = {**STUDY, "scenarios": {**STUDY.get("scenarios", {}),
                                    "forecast": {**STUDY_SCENARIOS["forecast"], "enabled": False}}}
STUDY_LABELS = _study_scenario_labels(STUDY, TIPM_LAST, _STUDY_HORIZONS)
STUDY_KIND = {label: kind for kind, labels in STUDY_LABELS.items() for label in labels}
# Snakemake threads of a batch job: a LocalCluster batch occupies its workers' cores.
_STUDY_THREADS = (int(STUDY_SIMULATION["dask"]["local_workers"])
                  if STUDY_SIMULATION["executor"] == "dask"
                  and not (os.environ.get("TTBPIPE_DASK_SCHEDULER")
                           or STUDY_SIMULATION["dask"]["scheduler"]) else 1)

wildcard_constraints:
    first=r"\d{5}",
    last=r"\d{5}",


def study_design_inputs(wildcards) -> dict[str, str]:
    """TIPM tables the design needs: the latest campaign's weights, the forecast states."""
    inputs = {}
    if STUDY_LABELS["irregularity"]:
        inputs["weights"] = f"{RESULTS}/tipm/selection/{TIPM_LAST}.weights.parquet"
    if STUDY_LABELS["forecast"]:
        inputs["states"] = results_path("tipm/forecast_states.parquet")
    if STUDY_LABELS["irregularity_mc"]:   # case 3: the pooled PSD population of the latest campaign
        inputs["population"] = tipm_population_psds(type("W", (), {"date": TIPM_LAST}))
    return inputs


checkpoint study_design:
    """Every sample of the study: scenario, index, probability weight, profile, seed entropy."""
    input:
        unpack(study_design_inputs),
    output:
        results_path("study/design.parquet"),
    params:
        study=STUDY,
        latest_campaign=TIPM_LAST,
        horizons_months=_STUDY_HORIZONS,
        version=MODEL_VERSION,
    log:
        log_path("study/design.log"),
    script:
        "../scripts/study_design.py"


def study_batch_inputs(wildcards) -> dict[str, str]:
    """The design and the irregularity profiles the batch's scenario reads."""
    kind = STUDY_KIND.get(wildcards.scenario)
    if kind is None:
        raise WorkflowError(f"unknown study scenario {wildcards.scenario!r}; the configured ones "
                            f"are {sorted(STUDY_KIND)}")
    inputs = {"design": results_path("study/design.parquet")}
    if kind == "irregularity":
        inputs["profiles"] = f"{RESULTS}/tipm/profiles/{TIPM_LAST}.parquet"
    elif kind == "forecast":
        inputs["profiles"] = results_path("tipm/forecast_profiles.parquet")
    elif kind == "irregularity_mc":
        inputs["population"] = tipm_population_psds(type("W", (), {"date": TIPM_LAST}))
    return inputs


rule simulate_batch:
    """Coupled runs of samples first..last of one scenario: extremes and time histories."""
    input:
        unpack(study_batch_inputs),
    output:
        extremes=f"{STUDY_BATCH_ROOT}/{{scenario}}/extremes_{{first}}-{{last}}.parquet",
        histories=f"{STUDY_BATCH_ROOT}/{{scenario}}/histories_{{first}}-{{last}}.parquet",
    params:
        # what a sample's result depends on (not batch_size / executor: results are identical)
        simulation={k: v for k, v in STUDY_SIMULATION.items()
                    if k not in ("batch_size", "executor", "dask")},
        structure=config.get("structure", {}),
        fields=config.get("fields"),
        seed=config["study"]["seed"],
        mc_profiles={"wavelength_band_m": config["psd"].get("wavelength_band_m"),
                     **TIPM.get("profiles", {})},
        version=MODEL_VERSION,
    threads: _STUDY_THREADS
    log:
        log_path("study/batches/{scenario}/{first}-{last}.log"),
    script:
        "../scripts/simulate_batch.py"


def study_batch_files(wildcards=None) -> dict[str, list[str]]:
    """Every batch file of the design (evaluated after the study_design checkpoint)."""
    design = _pd.read_parquet(checkpoints.study_design.get().output[0])
    pairs = [_study_batch_paths(STUDY_BATCH_ROOT, *b)
             for b in _study_batches(design, STUDY_SIMULATION["batch_size"])]
    return {"extremes": [p[0] for p in pairs], "histories": [p[1] for p in pairs]}
