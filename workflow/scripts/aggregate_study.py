"""Snakemake script of rule aggregate_study: tables, figures and report pages of the study."""

import matplotlib

matplotlib.use("Agg")

from ttbpipe.io import read_table  # noqa: E402
from ttbpipe.logs import setup_logging  # noqa: E402
from ttbpipe.study.aggregate import aggregate_study  # noqa: E402
from ttbpipe.workflow import snakemake_context  # noqa: E402

snakemake = snakemake_context(globals(), "aggregate_study")
setup_logging(snakemake.log[0])
out = snakemake.output
aggregate_study(list(snakemake.input.extremes), list(snakemake.input.histories),
                read_table(snakemake.input.design), snakemake.config,
                out=out.extremes.rsplit("/", 1)[0])
