"""Snakemake script of rule aggregate_study: tables, figures and report pages of the study."""

import matplotlib

matplotlib.use("Agg")

import pandas as pd  # noqa: E402

from ttbpipe.io import read_table, write_table  # noqa: E402
from ttbpipe.logs import setup_logging  # noqa: E402
from ttbpipe.study.aggregate import aggregate_study  # noqa: E402
from ttbpipe.study.batch import verify_batches  # noqa: E402
from ttbpipe.workflow import snakemake_context  # noqa: E402

snakemake = snakemake_context(globals(), "aggregate_study")
setup_logging(snakemake.log[0])
out = snakemake.output
design = pd.concat([read_table(p) for p in snakemake.input.designs], ignore_index=True)
# provenance first: stale (other settings or code) or unreadable batches stop here, named
verify_batches([*snakemake.input.extremes, *snakemake.input.histories], design,
               snakemake.params.settings)
write_table(design, out.design, config=snakemake.config, kind="study_design")
aggregate_study(list(snakemake.input.extremes), list(snakemake.input.histories), design,
                snakemake.config, out=out.extremes.rsplit("/", 1)[0])
