"""Snakemake script of checkpoint study_design: every sample of the study (docs/studies.md)."""

from ttbpipe.io import read_table, write_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.design import build_design
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "study_design")
setup_logging(snakemake.log[0])
inputs = snakemake.input
design = build_design(
    snakemake.params.study, latest_campaign=snakemake.params.latest_campaign,
    tipm_weights=read_table(inputs.weights) if "weights" in inputs.keys() else None,
    forecast_states=read_table(inputs.states) if "states" in inputs.keys() else None,
    horizons_months=snakemake.params.horizons_months,
    n_population_sections=(sum(int(read_table(p)["section"].nunique()) for p in inputs.population)
                           if "population" in inputs.keys() else None))
write_table(design, snakemake.output[0], config=snakemake.config, kind="study_design")
