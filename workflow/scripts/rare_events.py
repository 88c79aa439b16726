"""Snakemake script of rule rare_events: ttbpipe.reliability.study.rare_event_table and its page."""

import pandas as pd

from ttbpipe.io import write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.reliability.study import rare_event_table, rare_events_html

setup_logging(snakemake.log[0])  # noqa: F821 (injected by Snakemake)
table = rare_event_table(list(snakemake.input.subset),  # noqa: F821
                         pd.read_parquet(snakemake.input.reliability),  # noqa: F821
                         snakemake.params.limits)  # noqa: F821
write_table(table, snakemake.output.table, config=snakemake.config, kind="rare_events")  # noqa: F821
write_text(rare_events_html(table), snakemake.output.page)  # noqa: F821
