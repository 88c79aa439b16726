# Stage: rare-event reliability (docs/reliability.md §10). With study.scenarios.subset enabled,
# one job per configured limit runs subset simulation of the coupled model in standard-normal
# space (ttbpipe.reliability.study). The job evaluates each chain step's points in `threads`
# worker processes and saves the estimator's state after every step
# (results/study/subset/state/<limit>.<digest>.state.npz, not a Snakemake output, so a killed
# job keeps it): rerunning the job resumes where it stopped, with the same result.

from ttbpipe.study.design import resolve_subset as _subset_resolve

SUBSET = _subset_resolve(config)


def subset_targets() -> list[str]:
    """The rare-event table and page of the configured limits (none when disabled)."""
    if not SUBSET["enabled"]:
        return []
    return [results_path("study/rare_events.parquet")]


def subset_inputs(wildcards) -> list[str]:
    """PSD tables of the latest campaign's population (spectrum: population), else none."""
    if SUBSET["spectrum"] != "population":
        return []
    return tipm_population_psds(type("W", (), {"date": TIPM_LAST}))


rule subset_simulation:
    """Subset simulation of one limit of the coupled model (rare exceedance probability)."""
    input:
        population=subset_inputs,
        kernels=ancient(results_path("study/kernels.json")),   # compiled once (study.smk)
    output:
        results_path("study/subset/{limit}.parquet"),
        results_path("study/subset/{limit}.levels.csv"),
    params:
        subset=SUBSET,
        version=MODEL_VERSION,
        state_dir=results_path("study/subset/state"),
    wildcard_constraints:
        limit=r"[a-z_]+",
    threads: workflow.cores
    log:
        log_path("study/subset/{limit}.log"),
    script:
        "../scripts/subset_simulation.py"


rule rare_events:
    """The subset-simulation estimates with their target verdicts, beside the ordinary
    scenarios' estimates of the same limits (report page)."""
    input:
        subset=expand(results_path("study/subset/{limit}.parquet"), limit=SUBSET["limits"]),
        reliability=results_path("study/reliability.parquet"),
    output:
        table=results_path("study/rare_events.parquet"),
        page=report(
            results_path("study/report/rare_events.html"),
            caption="../report/rare_events.rst",
            category="4. Reliability",
        ),
    params:
        limits=config.get("limits"),
    log:
        log_path("study/rare_events.log"),
    script:
        "../scripts/rare_events.py"
