"""Snakemake script of rule tipm_select: representative PSD sets of one campaign's population
and their profiles."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.profiles import PROFILE_ID_COLUMN, write_profiles
from ttbpipe.tipm.stages import profiles_stage, select_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_select", date="2025-12-15")
setup_logging(snakemake.log[0])
sources = [str(p) for p in snakemake.input]
date = snakemake.wildcards.date
selection, weights, metrics = select_stage(sources, snakemake.params.tipm, snakemake.params.psd)
profiles = profiles_stage(selection, weights, date, snakemake.params.tipm, snakemake.params.psd,
                          snakemake.params.seed)
extra = dict(config=snakemake.config, campaign_date=date, sources=sources)
write_table(selection, snakemake.output.selection, kind="tipm_selection", **extra)
write_table(weights, snakemake.output.weights, kind="tipm_weights", **extra)
write_table(metrics, snakemake.output.metrics, kind="tipm_selection_metrics", **extra)
write_profiles(profiles, snakemake.output.profiles, id_column=PROFILE_ID_COLUMN["irregularity"],
               kind="tipm_profiles", weights_table=str(snakemake.output.weights), **extra)
