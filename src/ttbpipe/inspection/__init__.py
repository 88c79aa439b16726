"""Inspection-car data: campaign file format, validation and cleaning, synthetic campaigns.

Public API::

    read_campaign(path) -> DataFrame                       # format.py
    clean_campaign(df, source, **options) -> (clean, CleaningReport)   # validate.py
    check_campaign(path, **options) -> (clean, CleaningReport)
    write_synthetic_campaigns(out_dir, dates=..., ...) -> list[Path]   # synthetic.py

Errors are :class:`InspectionError` (a ``ValueError``) naming the file, row and column.
The synthetic module is imported lazily, since it depends on the irregularity stage.
"""

from .format import (CHAINAGE_COLUMN, REQUIRED_COLUMNS, InspectionError, campaign_date,
                     read_campaign)
from .validate import REPAIR_KINDS, CleaningReport, check_campaign, clean_campaign

__all__ = ["CHAINAGE_COLUMN", "REQUIRED_COLUMNS", "REPAIR_KINDS", "InspectionError",
           "CleaningReport", "campaign_date", "read_campaign", "clean_campaign", "check_campaign",
           "write_synthetic_campaigns", "campaign_dates"]


def __getattr__(name: str):
    if name in ("write_synthetic_campaigns", "campaign_dates", "synthetic_campaign_series"):
        from . import synthetic
        return getattr(synthetic, name)
    raise AttributeError(name)
