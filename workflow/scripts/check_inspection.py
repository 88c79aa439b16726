"""Snakemake script of rule check_inspection: validate and clean one campaign file."""

import json
import logging

from ttbpipe.inspection import InspectionError, check_campaign
from ttbpipe.io import write_table, write_text
from ttbpipe.logs import setup_logging

setup_logging(snakemake.log[0])  # noqa: F821 (snakemake object injected by Snakemake)
source = snakemake.input[0]  # noqa: F821
try:
    clean, report = check_campaign(source, **snakemake.params.cleaning)  # noqa: F821
except InspectionError as exc:
    logging.getLogger("check_inspection").error("%s", exc)
    raise
logging.getLogger("check_inspection").info("summary:\n%s", report.summary())
write_table(clean, snakemake.output.clean, config=snakemake.config,  # noqa: F821
            kind="inspection_clean", source=str(source), cleaning=report.to_dict())
write_text(json.dumps(report.to_dict(), indent=2) + "\n", snakemake.output.repairs)  # noqa: F821
