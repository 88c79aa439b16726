"""The campaign folder scan: every file the workflow cannot use is reported, none skipped.

The workflow reads campaign files named ``YYYY-MM-DD.csv|parquet`` directly in
``inspections.directory`` (docs/inspection_format.md). A file meant as a campaign but named or
placed otherwise must be reported with its cause and the name it should have, all in one error;
files that are clearly not data are ignored (and logged).
"""

from __future__ import annotations

import datetime as dt
import logging

import pytest

from ttbpipe.inspection import InspectionError, campaign_date
from ttbpipe.inspection.discover import CampaignFolderError, UnusableFile, discover_campaigns
from ttbpipe.inspection.synthetic import write_synthetic_campaigns


def touch(folder, *names):
    for name in names:
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("chainage_m\n0\n")


def test_good_folder(tmp_path, caplog):
    touch(tmp_path, "2026-03-14.csv", "2026-04-14.parquet", "README.md", ".gitkeep", "notes.txt")
    with caplog.at_level(logging.DEBUG, logger="ttbpipe.inspection.discover"):
        found = discover_campaigns(tmp_path)
    assert found == {dt.date(2026, 3, 14): tmp_path / "2026-03-14.csv",
                     dt.date(2026, 4, 14): tmp_path / "2026-04-14.parquet"}
    assert list(found) == sorted(found)
    for name in ("README.md", ".gitkeep", "notes.txt"):  # ignored, but said so
        assert f"{tmp_path / name}: not a campaign file" in caplog.text
    assert discover_campaigns(tmp_path / "missing") == {}


# file -> (words of its cause, what to do)
UNUSABLE = {
    "2026-03-14.CSV": ("upper-case suffix '.CSV'", "rename it to 2026-03-14.csv"),
    "campaign_2026-03-15.csv": ("text around the date ('campaign_' before it)",
                                "rename it to 2026-03-15.csv"),
    "20260316.csv": ("compact date (YYYYMMDD)", "rename it to 2026-03-16.csv"),
    "2026_03_17.parquet": ("date written with '_' instead of '-'",
                           "rename it to 2026-03-17.parquet"),
    "2026-02-30.csv": ("2026-02-30 is not a valid date (day is out of range for month)",
                       "rename it to YYYY-MM-DD.csv (or .parquet) with the campaign date"),
    "2026-03-18 (1).csv": ("text around the date (' (1)' after it)",
                           "rename it to 2026-03-18.csv"),
    "2026-03-19.xlsx": ("unsupported file type '.xlsx'", "rename it to 2026-03-19.csv"),
    "campaign.parquet": ("no date in the name",
                         "rename it to YYYY-MM-DD.csv (or .parquet) with the campaign date"),
}


def test_every_unusable_file_is_reported_with_cause_and_name(tmp_path):
    touch(tmp_path, "2026-01-10.csv", "README.md", *UNUSABLE,
          "2026/2026-03-20.csv", "old/20260321.CSV")
    with pytest.raises(CampaignFolderError) as info:
        discover_campaigns(tmp_path)
    err = info.value
    assert isinstance(err, ValueError)
    message = str(err)
    assert message.startswith(f"{tmp_path}: {len(UNUSABLE) + 2} inspection file(s) the "
                              "workflow cannot use")
    lines = {line.split(": ", 1)[0].removeprefix("  - "): line for line in message.splitlines()[1:]}
    for name, (cause, action) in UNUSABLE.items():
        line = lines[str(tmp_path / name)]
        assert cause in line and line.endswith(action), line
    sub = lines[str(tmp_path / "2026" / "2026-03-20.csv")]
    assert "in a subfolder (2026/)" in sub
    assert sub.endswith(f"move it to {tmp_path / '2026-03-20.csv'}")
    sub = lines[str(tmp_path / "old" / "20260321.CSV")]
    assert "in a subfolder (old/)" in sub and "compact date" in sub and "upper-case" in sub
    assert sub.endswith(f"move it to {tmp_path / '2026-03-21.csv'}")
    assert str(tmp_path / "2026-01-10.csv") not in lines and "README.md" not in message
    assert {p.path.name for p in err.problems} == {*UNUSABLE, "2026-03-20.csv", "20260321.CSV"}
    assert all(isinstance(p, UnusableFile) for p in err.problems)


def test_two_files_for_one_date(tmp_path):
    touch(tmp_path, "2026-03-14.csv", "2026-03-14.parquet")
    with pytest.raises(CampaignFolderError, match=r"two inspection files for campaign 2026-03-14"
                                                  r".*keep one of them"):
        discover_campaigns(tmp_path)


def test_synthetic_directories_are_excluded(tmp_path):
    """The configured synthetic directory (a subfolder by default) and, elsewhere, synthetic
    campaigns written by ttbpipe for another configuration are not the user's files."""
    write_synthetic_campaigns(tmp_path / "synthetic", dates=["2026-01-15"], length_km=0.2)
    write_synthetic_campaigns(tmp_path / "synthetic_case3", dates=["2026-02-15"], length_km=0.2)
    touch(tmp_path, "2026-03-14.csv", "synthetic/notes.csv")
    found = discover_campaigns(tmp_path, exclude=[tmp_path / "synthetic"])
    assert found == {dt.date(2026, 3, 14): tmp_path / "2026-03-14.csv"}
    # a Parquet file of the user in a subfolder is still reported
    touch(tmp_path, "synthetic_case3/2026-04-15.parquet")
    with pytest.raises(CampaignFolderError, match=r"2026-04-15.parquet: in a subfolder"):
        discover_campaigns(tmp_path, exclude=[tmp_path / "synthetic"])


def test_campaign_date_says_the_same(tmp_path):
    with pytest.raises(InspectionError, match=r"compact date \(YYYYMMDD\).*rename it to "
                                              r"2026-03-14.csv"):
        campaign_date(tmp_path / "20260314.csv")
    with pytest.raises(InspectionError, match=r"upper-case suffix '.CSV'.*rename it to "
                                              r"2026-03-14.csv"):
        campaign_date(tmp_path / "2026-03-14.CSV")
    assert campaign_date(tmp_path / "2026-03-14.csv") == dt.date(2026, 3, 14)
