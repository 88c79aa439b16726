"""Snakemake script of rule case_sweep_batch: case 1 runs at a few speeds (ttbpipe.study.cases)."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.cases import run_sweep
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "case_sweep_batch", sfirst="000", slast="003")
setup_logging(snakemake.log[0])
table = run_sweep(snakemake.config, list(snakemake.params.speeds))
write_table(table, snakemake.output[0], config=snakemake.config, kind="case_sweep_batch",
            speeds_kmh=list(snakemake.params.speeds))
