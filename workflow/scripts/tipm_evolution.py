"""Snakemake script of rule tipm_evolution: spectral evolution model fitted on every campaign."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.stages import evolution_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_evolution")
setup_logging(snakemake.log[0])
sources = [str(p) for p in snakemake.input]
table, metadata = evolution_stage(sources, snakemake.params.tipm, snakemake.params.psd)
write_table(table, snakemake.output[0], config=snakemake.config, kind="tipm_evolution",
            model=metadata, sources=sources)
