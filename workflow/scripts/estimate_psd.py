"""Snakemake script of rule estimate_psd: Welch PSD per section and channel of one campaign."""

from ttbpipe.io import read_table, write_table
from ttbpipe.irregularity.psd import estimate_campaign_psd
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "estimate_psd", date="2023-01-15")
setup_logging(snakemake.log[0])
source = str(snakemake.input[0])
table = estimate_campaign_psd(read_table(source), snakemake.params.psd, source=source)
write_table(table, snakemake.output[0], config=snakemake.config, kind="psd", source=source,
            psd=dict(snakemake.params.psd))
