"""Snakemake script of rule en1991_report: the EN 1991-2 study's tables, page and figures."""

from ttbpipe.en1991.study import summarise, write_figures
from ttbpipe.io import read_table, write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "en1991_report")
setup_logging(snakemake.log[0])
tables = [read_table(p) for p in snakemake.input.trains]
summary = summarise(tables, snakemake.config)
for name in ("envelope", "resonance", "checks"):
    write_table(summary[name], snakemake.output[name], config=snakemake.config,
                kind=f"en1991_{name}")
write_figures(tables, summary, snakemake.output.figures)
write_text(summary["summary"], snakemake.output.summary)
