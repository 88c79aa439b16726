"""Snakemake script of rule en1991_train: one train's EN 1991-2 speed sweep (ttbpipe.en1991)."""

from ttbpipe.en1991.study import run_train
from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "en1991_train", train="HSLM-A1")
setup_logging(snakemake.log[0])
table = run_train(snakemake.config, snakemake.wildcards.train)
write_table(table, snakemake.output[0], config=snakemake.config, kind="en1991_train",
            train=snakemake.wildcards.train)
