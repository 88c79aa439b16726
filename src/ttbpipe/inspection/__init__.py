"""Inspection-car data: campaign file format, validation and cleaning, synthetic campaigns.

Public API::

    read_campaign(path, columns=..., units=...) -> DataFrame           # format.py
    clean_campaign(df, source, **options) -> (clean, CleaningReport)   # validate.py
        (its steps: checks.py, grid.py, repairs.py; the report: cleaning_report.py)
    check_campaign(path, columns=..., units=..., **options) -> (clean, CleaningReport)
    options_from_config(config["inspections"]) -> check_campaign keyword arguments
    discover_campaigns(folder, exclude=...) -> {date: path}            # discover.py
    write_synthetic_campaigns(out_dir, dates=..., ...) -> list[Path]   # synthetic.py

Errors are :class:`InspectionError` (a ``ValueError``) naming the file, row and column.
The synthetic module is imported lazily, since it depends on the irregularity stage.
"""

from ..dates import DATE_PATTERN
from .discover import CampaignFolderError, discover_campaigns
from .format import (CHAINAGE_COLUMN, REQUIRED_COLUMNS, InspectionError, apply_mapping,
                     campaign_date, read_campaign)
from .cleaning_report import REPAIR_KINDS, CleaningReport
from .validate import CLEANING_DEFAULTS, check_campaign, clean_campaign, options_from_config

__all__ = ["CHAINAGE_COLUMN", "DATE_PATTERN", "REQUIRED_COLUMNS", "REPAIR_KINDS",
           "CLEANING_DEFAULTS", "InspectionError", "CampaignFolderError", "CleaningReport",
           "campaign_date", "read_campaign", "apply_mapping", "clean_campaign", "check_campaign",
           "options_from_config", "discover_campaigns", "write_synthetic_campaigns",
           "campaign_dates"]


def __getattr__(name: str):
    if name in ("write_synthetic_campaigns", "campaign_dates", "synthetic_campaign_series"):
        from . import synthetic
        return getattr(synthetic, name)
    raise AttributeError(name)
