"""Snakemake script of rule check_inspection: validate and clean one campaign file."""

import json
import logging

from ttbpipe.inspection import InspectionError, check_campaign
from ttbpipe.io import write_table, write_text
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "check_inspection", date="2023-01-15")
setup_logging(snakemake.log[0])
log = logging.getLogger("check_inspection")
source = snakemake.input[0]
try:
    # mapping: inspections.columns / inspections.units for the user's files ({} when synthetic)
    clean, report = check_campaign(source, **snakemake.params.mapping,
                                   **snakemake.params.cleaning)
except InspectionError as exc:
    log.error("%s", exc)
    raise
log.info("summary:\n%s", report.summary())
write_table(clean, snakemake.output.clean, config=snakemake.config,
            kind="inspection_clean", source=str(source), cleaning=report.to_dict())
write_text(json.dumps(report.to_dict(), indent=2) + "\n", snakemake.output.repairs)
