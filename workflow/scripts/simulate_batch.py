"""Snakemake script of rule simulate_batch: one batch of samples (ttbpipe.study.batch)."""

from ttbpipe.io import read_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.batch import simulate_batch
from ttbpipe.study.design import batch_rows
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "simulate_batch", scenario="C1", first="00000",
                              last="00003")
setup_logging(snakemake.log[0])
w = snakemake.wildcards
rows = batch_rows(read_table(snakemake.input.design), w.scenario, int(w.first), int(w.last))
profiles = {}
if "profiles" in snakemake.input.keys():
    profiles = {str(rows["kind"].iloc[0]): snakemake.input.profiles}
simulate_batch(rows, snakemake.config, profiles, snakemake.output.extremes,
               snakemake.output.histories, scenario=w.scenario, first=int(w.first),
               last=int(w.last))
