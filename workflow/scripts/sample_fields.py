"""Snakemake script of rule sample_fields: thin wrapper around ttbpipe.fields.sample_study."""

from ttbpipe.fields import sample_study
from ttbpipe.logs import setup_logging

setup_logging(snakemake.log[0])  # noqa: F821 (injected by Snakemake)
config = dict(snakemake.config)  # noqa: F821
config["fields"] = snakemake.params.fields  # noqa: F821
config["study"] = dict(config["study"], seed=snakemake.params.seed)  # noqa: F821
sample_study(config, snakemake.output[0])  # noqa: F821
