"""Finding the campaign files of a folder, and reporting every file the workflow cannot use.

The workflow builds its jobs from the campaign files directly in ``inspections.directory``,
named ``YYYY-MM-DD.csv`` or ``YYYY-MM-DD.parquet``. A file that was meant as a campaign but is
named otherwise (``2026-03-14.CSV``, ``campaign_2026-03-14.csv``, ``20260314.csv``,
``2026-02-30.csv``) or put in a subfolder would be skipped without a word, and the study would
silently run on fewer campaigns. :func:`discover_campaigns` therefore reports all such files in
one error, each with its probable cause and the name it should have, when the workflow is
parsed (``workflow/rules/common.smk``), before any job runs.

What is a candidate: a file whose suffix is ``.csv`` or ``.parquet`` in any letter case (also as
an inner suffix, ``2026-03-14.csv.gz``), or a file with a date in its name and the suffix of a
table format (:data:`TABLE_SUFFIXES`, e.g. ``2026-03-14.xlsx``). Everything else (``README.md``,
``notes.txt``, hidden files such as ``.gitkeep``) is clearly not data: ignored and logged.
Excluded: the folders in ``exclude`` (the synthetic campaigns' directory) and, in subfolders,
Parquet files whose provenance says they are synthetic campaigns written by ttbpipe (the
directories of other configurations, e.g. a paper case's ``synthetic_case3``).
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import logging
import os
import re
from pathlib import Path
from typing import Iterable

from ..io import read_provenance
from .format import CAMPAIGN_NAME, SUFFIXES, diagnose_campaign_name

logger = logging.getLogger(__name__)

#: Suffixes of table formats that a campaign may have been saved in by mistake; a file with one of
#: them and a date in its name is reported (export it as CSV), not ignored.
TABLE_SUFFIXES: tuple[str, ...] = (".xlsx", ".xls", ".ods", ".tsv", ".txt", ".dat", ".gz",
                                   ".zip", ".bz2", ".xz", ".feather", ".h5", ".hdf5", ".mat")

#: Provenance ``kind`` of the campaigns written by :mod:`ttbpipe.inspection.synthetic`.
SYNTHETIC_KIND = "inspection_synthetic"

_ANY_DATE = re.compile(r"(?<!\d)\d{4}[-_.]?\d{2}[-_.]?\d{2}(?!\d)")


@dataclasses.dataclass(frozen=True)
class UnusableFile:
    """A file of the campaign folder the workflow cannot use, why, and what to do."""

    path: Path
    cause: str
    action: str

    def __str__(self) -> str:
        return f"{self.path}: {self.cause}; {self.action}"


class CampaignFolderError(ValueError):
    """Files of a campaign folder that the workflow cannot use, all of them in one message."""

    def __init__(self, folder: str | Path, problems: list[UnusableFile]) -> None:
        self.folder = str(folder)
        self.problems = list(problems)
        lines = [f"{self.folder}: {len(self.problems)} inspection file(s) the workflow cannot "
                 "use (campaign files are named by their date, YYYY-MM-DD.csv or "
                 "YYYY-MM-DD.parquet, directly in this folder; docs/inspection_format.md):"]
        lines += [f"  - {problem}" for problem in self.problems]
        super().__init__("\n".join(lines))

    def __reduce__(self):
        return (type(self), (self.folder, self.problems))


def _is_synthetic(path: Path) -> bool:
    """Whether ``path`` is a Parquet campaign written by ttbpipe's synthetic generator."""
    if path.suffix != ".parquet":
        return False
    try:
        return read_provenance(path).get("kind") == SYNTHETIC_KIND
    except Exception:  # no provenance, not Parquet, unreadable: not ours
        return False


def _is_candidate(path: Path) -> bool:
    suffixes = [s.lower() for s in path.suffixes]
    if any(s in SUFFIXES for s in suffixes):
        return True
    return bool(suffixes) and suffixes[-1] in TABLE_SUFFIXES and bool(_ANY_DATE.search(path.name))


def _inside(path: Path, folders: list[Path]) -> bool:
    return any(path == folder or folder in path.parents for folder in folders)


def discover_campaigns(folder: str | Path, *, exclude: Iterable[str | Path] = ()
                       ) -> dict[_dt.date, Path]:
    """Map campaign date -> file for the campaign files directly in ``folder``.

    ``exclude``: folders not scanned (the synthetic campaigns' directory, which may lie inside
    ``folder``). A missing ``folder`` has no campaigns (``{}``). Raises
    :class:`CampaignFolderError` (a ``ValueError``) listing every file that was meant as a
    campaign but cannot be used, with its cause and the name or place it should have, and every
    date given by two files. Files that are clearly not data are ignored and logged.
    """
    folder = Path(folder)
    if not folder.is_dir():
        logger.info("%s: no such folder, no campaign files", folder)
        return {}
    root = folder.resolve()
    excluded = [Path(e).resolve() for e in exclude]
    problems: list[UnusableFile] = []
    by_date: dict[_dt.date, list[Path]] = {}
    for current, dirs, files in os.walk(folder):
        current_path = Path(current)
        kept = []
        for name in sorted(dirs):
            sub = current_path / name
            if name.startswith("."):
                logger.debug("%s: hidden folder, not scanned", sub)
            elif _inside(sub.resolve(), excluded):
                logger.debug("%s: excluded (synthetic campaigns), not scanned", sub)
            else:
                kept.append(name)
        dirs[:] = kept
        in_subfolder = current_path.resolve() != root
        for name in sorted(files):
            path = current_path / name
            if name.startswith(".") or not _is_candidate(path):
                logger.info("%s: not a campaign file (not CSV or Parquet), ignored", path)
                continue
            problem = diagnose_campaign_name(name)
            if in_subfolder:
                if problem is None and _is_synthetic(path):
                    logger.info("%s: synthetic campaign written by ttbpipe (another "
                                "configuration's), ignored", path)
                    continue
                relative = path.parent.relative_to(folder)
                target = name if problem is None else (problem[1] or "YYYY-MM-DD.csv")
                cause = f"in a subfolder ({relative}/), which the workflow does not read"
                if problem is not None:
                    cause += f"; {problem[0]}"
                problems.append(UnusableFile(path, cause, f"move it to {folder / target}"))
                continue
            if problem is not None:
                cause, suggestion = problem
                action = (f"rename it to {suggestion}" if suggestion else
                          "rename it to YYYY-MM-DD.csv (or .parquet) with the campaign date")
                problems.append(UnusableFile(path, cause, action))
                continue
            date = _dt.date.fromisoformat(CAMPAIGN_NAME.match(name).group(1))
            by_date.setdefault(date, []).append(path)
    for date, paths in sorted(by_date.items()):
        for extra in paths[1:]:
            problems.append(UnusableFile(
                extra, f"two inspection files for campaign {date.isoformat()}: {paths[0]} and "
                f"{extra}", "keep one of them"))
    if problems:
        raise CampaignFolderError(folder, problems)
    campaigns = {date: paths[0] for date, paths in sorted(by_date.items())}
    logger.info("%s: %d campaign file(s)", folder, len(campaigns))
    return campaigns
