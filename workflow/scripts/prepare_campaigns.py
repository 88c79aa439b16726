"""Snakemake script of rules prepare_campaigns_<year>: each campaign file of one calendar year
validated and cleaned, then its Welch PSD per section and channel (one interpreter start per year).

Run alone: ``python workflow/scripts/prepare_campaigns.py`` (the default study's first year)."""

import json
import logging

from ttbpipe.inspection import InspectionError, check_campaign
from ttbpipe.io import write_table, write_text
from ttbpipe.irregularity.psd import estimate_campaign_psd
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "prepare_campaigns_2023")
setup_logging(snakemake.log[0])
log = logging.getLogger("prepare_campaigns")
params, output = snakemake.params, snakemake.output
for k, date in enumerate(params.dates):
    source, clean_path = str(snakemake.input[k]), output.clean[k]
    log.info("campaign %s (%d of %d): %s", date, k + 1, len(params.dates), source)
    try:
        # mapping: inspections.columns / inspections.units for the user's files ({} when synthetic)
        clean, report = check_campaign(source, **params.mapping[date], **params.cleaning)
    except InspectionError as exc:
        log.error("%s", exc)
        raise
    log.info("summary:\n%s", report.summary())
    write_table(clean, clean_path, config=snakemake.config, kind="inspection_clean", source=source,
                cleaning=report.to_dict())
    write_text(json.dumps(report.to_dict(), indent=2) + "\n", output.repairs[k])
    psd = estimate_campaign_psd(clean, params.psd, source=clean_path)
    write_table(psd, output.psd[k], config=snakemake.config, kind="psd", source=clean_path,
                psd=dict(params.psd))
