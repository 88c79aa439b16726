"""Snakemake script of rule tipm_profiles: profiles of one campaign's representative sets."""

from ttbpipe.io import read_table, write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.stages import profiles_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_profiles", date="2025-12-15")
setup_logging(snakemake.log[0])
profiles = profiles_stage(read_table(snakemake.input.selection), read_table(snakemake.input.weights),
                          snakemake.wildcards.date, snakemake.params.tipm, snakemake.params.psd,
                          snakemake.params.seed)
write_table(profiles, snakemake.output[0], config=snakemake.config, kind="tipm_profiles",
            campaign_date=snakemake.wildcards.date, weights_table=str(snakemake.input.weights))
