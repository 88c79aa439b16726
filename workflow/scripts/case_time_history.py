"""Snakemake script of rule case_time_history: case 1's Figs. 6-7 run (ttbpipe.study.cases)."""

from ttbpipe.io import write_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.cases import time_history_run
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "case_time_history")
setup_logging(snakemake.log[0])
speed = float(snakemake.params.sweep.get("history_speed_kmh", 300.0))
table, layout = time_history_run(snakemake.config, speed,
                                 car=int(snakemake.params.sweep.get("history_car", 2)))
write_table(table, snakemake.output.table, config=snakemake.config, kind="case_time_history",
            layout=layout)
