"""Snakemake script of rule case_sweep_report: case 1's tables and figures (docs/validation.md)."""

import pandas as pd

from ttbpipe.io import read_provenance, read_table, write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.study.case_report import sweep_report
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "case_sweep_report")
setup_logging(snakemake.log[0])
sweep = pd.concat([read_table(p) for p in snakemake.input.batches], ignore_index=True)
sweep = sweep.sort_values("speed_kmh").reset_index(drop=True)
history = read_table(snakemake.input.history)
layout = read_provenance(snakemake.input.history).get("layout", {})
resonance, summary = sweep_report(sweep, history, layout, snakemake.config, snakemake.output.figures)
write_table(sweep, snakemake.output.sweep, config=snakemake.config, kind="case_sweep")
write_table(resonance, snakemake.output.resonance, config=snakemake.config, kind="case_resonance")
write_text(summary, snakemake.output.summary)
