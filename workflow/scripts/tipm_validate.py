"""Snakemake script of rule tipm_validate: hold-out coverage of the spectral evolution forecast."""

import json

from ttbpipe.io import save_figure, write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.plots import plot_forecast
from ttbpipe.tipm.stages import validation_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_validate")
setup_logging(snakemake.log[0])
sources = [str(p) for p in snakemake.input]
coverage, tqi, summary = validation_stage(sources, snakemake.params.tipm, snakemake.params.psd,
                                          snakemake.params.seed)
write_table(coverage, snakemake.output.coverage, config=snakemake.config,
            kind="tipm_validation_coverage", summary=summary)
write_table(tqi, snakemake.output.tqi, config=snakemake.config, kind="tipm_validation_tqi")
write_text(json.dumps(summary, indent=2) + "\n", snakemake.output.summary)
save_figure(plot_forecast(tqi, coverage), snakemake.output.figure)
