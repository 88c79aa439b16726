"""Snakemake script of rule tipm_select: representative PSD sets of one campaign's population."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.stages import select_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_select", date="2025-12-15")
setup_logging(snakemake.log[0])
sources = [str(p) for p in snakemake.input]
selection, weights, metrics = select_stage(sources, snakemake.params.tipm, snakemake.params.psd)
extra = dict(config=snakemake.config, campaign_date=snakemake.wildcards.date, sources=sources)
write_table(selection, snakemake.output.selection, kind="tipm_selection", **extra)
write_table(weights, snakemake.output.weights, kind="tipm_weights", **extra)
write_table(metrics, snakemake.output.metrics, kind="tipm_selection_metrics", **extra)
