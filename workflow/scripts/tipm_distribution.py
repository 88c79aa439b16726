"""Snakemake script of rule tipm_distribution: per-frequency fits of one campaign's population."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.stages import distribution_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_distribution", date="2025-12-15")
setup_logging(snakemake.log[0])
sources = [str(p) for p in snakemake.input]
fits, summary = distribution_stage(sources, snakemake.params.psd)
extra = dict(config=snakemake.config, campaign_date=snakemake.wildcards.date, sources=sources)
write_table(fits, snakemake.output.fits, kind="tipm_distribution", **extra)
write_table(summary, snakemake.output.summary, kind="tipm_distribution_summary", **extra)
