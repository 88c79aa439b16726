"""Snakemake script of rule case_compare: cases 2-4 over the study outputs (docs/validation.md)."""

from ttbpipe.io import read_table, write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.study.case_report import compare_report
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "case_compare")
setup_logging(snakemake.log[0])
inp = snakemake.input
comparison, summary = compare_report(
    extremes=read_table(inp.extremes), history=read_table(inp.history),
    table1=read_table(inp.table1), table1_history=read_table(inp.table1_history),
    design=read_table(inp.design), case=snakemake.params.case,
    latest_campaign=snakemake.params.latest_campaign, figures=snakemake.output.figures)
write_table(comparison, snakemake.output.comparison, config=snakemake.config, kind="case_comparison")
write_text(summary, snakemake.output.summary)
