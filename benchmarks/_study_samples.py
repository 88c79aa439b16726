"""Shared set-up of the benchmarks that run a study's Monte Carlo samples outside Snakemake
(imported as a sibling module: benchmarks/study_sample_stages.py, benchmarks/track_window_study.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from snakemake.utils import update_config


def mc_sample_inputs(root: Path, configfile: str = "config/case3.yaml"
                     ) -> tuple[dict[str, Any], list[dict[str, Any]], dict[str, Any]]:
    """(configuration, Monte Carlo design rows by sample index, `run_sample` keyword arguments)
    of the study `snakemake --configfile <configfile>` wrote in the clone ``root``: the
    configuration merged as Snakemake merges it, the pooled population where the workflow wrote
    it (else the campaigns' PSD tables), and the span frequencies, as a batch reads them."""
    from ttbpipe.io import read_table
    from ttbpipe.study.batch import _sample_kwargs
    from ttbpipe.study.plan import mc_profile_settings

    config = yaml.safe_load((root / "config/config.yaml").read_text())
    update_config(config, yaml.safe_load((root / configfile).read_text()))
    results = root / config["results_dir"]
    design = read_table(results / "study/design/mc.parquet")
    paths = sorted(str(p) for p in (results / "psd").glob("*.parquet"))
    population = {**mc_profile_settings(config), "date": max(Path(p).stem for p in paths)}
    pooled = results / "study/mc_population.parquet"
    population.update({"pooled_path": str(pooled)} if pooled.is_file() else {"psd_paths": paths})
    kwargs = _sample_kwargs(config, {"irregularity_mc": population},
                            results / "study/span_frequencies.json")
    return config, design.sort_values("sample_index").to_dict("records"), kwargs
