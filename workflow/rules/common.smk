# Configuration validation, campaign discovery and input functions shared by all stages.

import os
import re
from pathlib import Path

import sys

try:
    import ttbpipe
except ModuleNotFoundError as _exc:
    if _exc.name != "ttbpipe":
        raise
    # this Snakemake runs in a Python where the package is not installed (e.g. a snakemake on
    # PATH outside the project's environment): use this checkout's src/, and say so
    _SRC = Path(workflow.basedir) / "src"   # basedir: the folder of the main Snakefile
    sys.path.insert(0, str(_SRC))
    # the rules' scripts run in child processes of this Python: they need the same path
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(_SRC), os.environ.get("PYTHONPATH", "")) if p)
    try:
        import ttbpipe
    except ModuleNotFoundError as _inner:
        raise WorkflowError(
            f"ttbpipe cannot be imported by this Snakemake's Python ({sys.executable}): "
            f"{_inner}. Install the project in the environment that runs Snakemake "
            "(pip install -c requirements.lock.txt -e \".[test]\", the README's first "
            "command) or run `python -m snakemake` with that environment's python") from None
    from snakemake.logging import logger as _logger

    _logger.warning(
        f"ttbpipe is not installed in this Snakemake's Python ({sys.executable}); using "
        f"{_SRC} with that Python's packages, which may not be the locked versions "
        "(requirements.lock.txt): install with the README's first command for a reproducible run")
from ttbpipe.configuration import ConfigurationError as _ConfigurationError
from ttbpipe.configuration import validate_scale_overlays as _validate_scale_overlays
from ttbpipe.configuration import validate_study_config as _validate_study_config

# Paper case studies (config/case*.yaml): `--config scale=small` merges the case file's small:
# overlay before validation (ttbpipe.study.cases.apply_scale).
from ttbpipe.study.cases import apply_scale as _apply_case_scale

# One schema for every section (src/ttbpipe/schemas/study.schema.yaml, with the case schema's
# structure and train): unknown keys anywhere are errors naming the key and the closest valid
# one; the schema's defaults are filled in, so every table's provenance records what ran.
_CONFIG_SOURCE = ", ".join(map(str, workflow.configfiles)) or "config"
try:
    _validate_scale_overlays(config, source=_CONFIG_SOURCE)
    _apply_case_scale(config)
    _validate_study_config(config, source=_CONFIG_SOURCE)
except (_ConfigurationError, ValueError) as _exc:
    raise WorkflowError(str(_exc)) from None

# Package code under src/ is not tracked by Snakemake for reruns: every rule passes this through
# `params:` (the release plus a digest of the package's code) so that changed code reruns what it
# made.
MODEL_VERSION = ttbpipe.code_version()

# Where a study writes (config `results_dir`, `logs_dir`): each paper case has its own
# (config/case<N>.yaml: results/case<N>, logs/case<N>) so that cases and the default study can
# share one checkout without overwriting each other's outputs.
RESULTS = config["results_dir"].rstrip("/")
LOGS = config["logs_dir"].rstrip("/")


def results_path(relative: str) -> str:
    """`relative` under the study's results directory (wildcards pass through unchanged)."""
    return f"{RESULTS}/{relative}"


def log_path(relative: str) -> str:
    """`relative` under the study's log directory."""
    return f"{LOGS}/{relative}"


def report_caption_path(path: str) -> str:
    """A generated file as a report() caption: captions resolve against workflow/rules/."""
    return path if os.path.isabs(path) else os.path.join("..", "..", path)


# The campaign date and its month arithmetic (ttbpipe.dates) and the folder scan
# (ttbpipe.inspection) live in the package.
from ttbpipe.dates import DATE_PATTERN, add_months
from ttbpipe.inspection.discover import discover_campaigns as _discover_campaign_files

wildcard_constraints:
    date=DATE_PATTERN,

# Cheap rules (seconds) run on the submitting node under a cluster executor instead of waiting in
# the queue (profiles/slurm, docs/cluster.md). Only rules that exist are listed.
localrules:
    all,
    study_design,
    sample_fields,
    plot_psd_vs_standard,
    tipm_figures,
    study_span_frequencies,


def synthetic_dates() -> list[str]:
    """Dates of the synthetic default campaigns, when the configuration asks for them: the
    start date and every `interval_months` calendar months after it (day clamped to the month)."""
    syn = config["inspections"].get("synthetic", {})
    if not syn.get("enabled", False):
        return []
    return [add_months(syn["start_date"], k * syn["interval_months"])
            for k in range(syn["campaigns"])]


def discover_campaigns() -> dict[str, str]:
    """Map campaign date -> file, from the user folder and the synthetic series."""
    folder = Path(config["inspections"]["directory"])
    syn = config["inspections"].get("synthetic", {})
    exclude = [syn["directory"]] if "directory" in syn else []
    try:  # every unusable file (bad name, subfolder, two files for one date) in one error
        found = _discover_campaign_files(folder, exclude=exclude)
    except ValueError as exc:
        raise WorkflowError(str(exc)) from None
    campaigns = {date.isoformat(): str(path) for date, path in found.items()}
    for date in synthetic_dates():
        path = str(Path(syn["directory"]) / f"{date}.parquet")
        if date in campaigns:
            raise WorkflowError(
                f"campaign {date} is both a file of yours ({campaigns[date]}) and a synthetic "
                "campaign; disable inspections.synthetic or rename your file"
            )
        campaigns[date] = path
    if not campaigns:
        raise WorkflowError(
            f"no inspection campaigns: put YYYY-MM-DD.csv or .parquet files in {folder} "
            "or set inspections.synthetic.enabled: true"
        )
    return dict(sorted(campaigns.items()))


CAMPAIGNS = discover_campaigns()


def campaigns_by_year() -> dict[str, list[str]]:
    """Campaign dates per calendar year: one preparation job each (rules
    prepare_campaigns_<year>), so that a job's start-up is paid once per year and a new or changed
    campaign reruns only its own year (docs/performance.md)."""
    years: dict[str, list[str]] = {}
    for date in CAMPAIGNS:   # sorted by date
        years.setdefault(date[:4], []).append(date)
    return years


CAMPAIGN_YEARS = campaigns_by_year()


def campaign_file(wildcards) -> str:
    return CAMPAIGNS[wildcards.date]


def all_targets() -> list[str]:
    """Every final output of the stages that exist (a paper case: only the case's outputs)."""
    if config.get("case"):
        return case_targets()  # workflow/rules/cases.smk
    if config.get("en1991"):
        return en1991_targets()  # workflow/rules/en1991.smk
    targets = [results_path("figures/psd_vs_standard.png")]
    targets += expand(results_path("psd/{date}.parquet"), date=CAMPAIGNS)
    targets.append(results_path("fields/samples.parquet"))
    targets += tipm_targets()  # workflow/rules/tipm.smk
    targets += study_targets()  # workflow/rules/report.smk
    targets += subset_targets()  # workflow/rules/reliability.smk
    return targets
