"""Snakemake script of rule prepare_campaign: validate and clean one campaign file, then its
Welch PSD per section and channel (one interpreter start per campaign)."""

import json
import logging

from ttbpipe.inspection import InspectionError, check_campaign
from ttbpipe.io import write_table, write_text
from ttbpipe.irregularity.psd import estimate_campaign_psd
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "prepare_campaign", date="2023-01-15")
setup_logging(snakemake.log[0])
log = logging.getLogger("prepare_campaign")
source = str(snakemake.input[0])
try:
    # mapping: inspections.columns / inspections.units for the user's files ({} when synthetic)
    clean, report = check_campaign(source, **snakemake.params.mapping,
                                   **snakemake.params.cleaning)
except InspectionError as exc:
    log.error("%s", exc)
    raise
log.info("summary:\n%s", report.summary())
clean_path = snakemake.output.clean
write_table(clean, clean_path, config=snakemake.config, kind="inspection_clean", source=source,
            cleaning=report.to_dict())
write_text(json.dumps(report.to_dict(), indent=2) + "\n", snakemake.output.repairs)
psd = estimate_campaign_psd(clean, snakemake.params.psd, source=clean_path)
write_table(psd, snakemake.output.psd, config=snakemake.config, kind="psd", source=clean_path,
            psd=dict(snakemake.params.psd))
