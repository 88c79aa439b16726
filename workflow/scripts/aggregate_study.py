"""Snakemake script of rule aggregate_study: tables, figures and report pages of the study."""

import matplotlib

matplotlib.use("Agg")

from ttbpipe.logs import setup_logging  # noqa: E402
from ttbpipe.study.outputs import aggregate_study, output_folder, read_design  # noqa: E402
from ttbpipe.workflow import snakemake_context  # noqa: E402

snakemake = snakemake_context(globals(), "aggregate_study")
setup_logging(snakemake.log[0])
# provenance first (settings=): stale (other settings or code) or unreadable batches stop there
aggregate_study(list(snakemake.input.extremes), list(snakemake.input.histories),
                read_design(snakemake.input.designs), snakemake.config,
                out=output_folder(dict(snakemake.output.items())),
                settings=snakemake.params.settings, workers=snakemake.threads)
