"""Shared set-up of the benchmarks that run a study's samples outside Snakemake
(imported as a sibling module: benchmarks/study_sample_stages.py, benchmarks/study_variants.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from snakemake.utils import update_config


def study_sample_inputs(root: Path, configfile: str = "config/case3.yaml", scenario: str = "mc"
                     ) -> tuple[dict[str, Any], list[dict[str, Any]], dict[str, Any]]:
    """(configuration, design rows of ``scenario`` by sample index, `run_sample` keyword
    arguments) of the study `snakemake --configfile <configfile>` wrote in the clone ``root``:
    the configuration merged as Snakemake merges it, the span frequencies and the profiles the
    scenario's kind reads, as workflow/scripts/simulate_batch.py gives them to a batch: the
    Monte Carlo irregularity scenario (``mc``, paper case 3) the pooled population where the
    workflow wrote it (else the campaigns' PSD tables), a forecast scenario (paper case 4) the
    forecast profiles, a TIPM scenario the latest campaign's representative profiles; the
    fields scenarios (``C1`` .. ``C4``, ``C4_mc``, paper case 2) run on the study's single
    mean-spectrum irregularity and read none."""
    from ttbpipe.io import read_table
    from ttbpipe.study.batch import _sample_kwargs
    from ttbpipe.study.plan import mc_profile_settings

    config = yaml.safe_load((root / "config/config.yaml").read_text())
    update_config(config, yaml.safe_load((root / configfile).read_text()))
    results = root / config["results_dir"]
    design = read_table(results / f"study/design/{scenario}.parquet")
    kind = str(design["kind"].iloc[0])
    profiles: dict[str, Any] = {}
    if kind == "forecast":
        profiles = {kind: str(results / "tipm/forecast_profiles.parquet")}
    elif kind == "irregularity":   # the latest campaign's representative profiles
        profiles = {kind: str(max((results / "tipm/profiles").glob("*.parquet")))}
    elif kind == "irregularity_mc":
        paths = sorted(str(p) for p in (results / "psd").glob("*.parquet"))
        population = {**mc_profile_settings(config), "date": max(Path(p).stem for p in paths)}
        pooled = results / "study/mc_population.parquet"
        population.update({"pooled_path": str(pooled)} if pooled.is_file() else {"psd_paths": paths})
        profiles = {"irregularity_mc": population}
    kwargs = _sample_kwargs(config, profiles, results / "study/span_frequencies.json")
    return config, design.sort_values("sample_index").to_dict("records"), kwargs
