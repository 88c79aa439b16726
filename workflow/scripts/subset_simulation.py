"""Snakemake script of rule subset_simulation: thin wrapper around
ttbpipe.reliability.study.run_subset_limit (runs outside Snakemake as
``python -m ttbpipe.reliability.study``)."""

from ttbpipe.logs import setup_logging
from ttbpipe.reliability.study import run_subset_limit

setup_logging(snakemake.log[0])  # noqa: F821 (injected by Snakemake)
run_subset_limit(dict(snakemake.config), snakemake.wildcards.limit,  # noqa: F821
                 snakemake.output[0], state_dir=snakemake.params.state_dir,  # noqa: F821
                 population_paths=[str(p) for p in snakemake.input.population],  # noqa: F821
                 workers=snakemake.threads, model_version=snakemake.params.version)  # noqa: F821
