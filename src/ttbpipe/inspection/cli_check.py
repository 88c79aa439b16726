"""``ttbpipe check-inspection FILE``: validate and clean one campaign file on its own.

Prints a one-screen summary of the checks and repairs; exits 0 on success and 1 with the error
message (naming file, row and column) when the file cannot be used. Optionally writes the cleaned
table (Parquet, with provenance) and the repairs report (JSON).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys

from ..io import write_table, write_text
from .format import InspectionError
from .validate import DETREND_KINDS, check_campaign

logger = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="campaign file YYYY-MM-DD.csv or YYYY-MM-DD.parquet")
    parser.add_argument("--out", default=None, metavar="CLEAN.parquet",
                        help="write the cleaned table here (Parquet with provenance)")
    parser.add_argument("--report", default=None, metavar="REPAIRS.json",
                        help="write the repairs report here (JSON)")
    group = parser.add_argument_group("cleaning options (defaults as in config/config.yaml)")
    group.add_argument("--max-gap-m", type=float, default=2.0,
                       help="longest run of missing values/rows interpolated (m) [%(default)s]")
    group.add_argument("--spike-threshold-mm", type=float, default=15.0,
                       help="deviation from the local median that makes a spike [%(default)s]")
    group.add_argument("--max-spike-run", type=int, default=2,
                       help="most consecutive samples forming one spike [%(default)s]")
    group.add_argument("--plausible-limit-mm", type=float, default=60.0,
                       help="largest plausible |value| after repair [%(default)s]")
    group.add_argument("--detrend", choices=DETREND_KINDS, default="linear",
                       help="per-channel detrending [%(default)s]")


def run(args: argparse.Namespace) -> int:
    options = dict(max_gap_m=args.max_gap_m, spike_threshold_mm=args.spike_threshold_mm,
                   max_spike_run=args.max_spike_run, plausible_limit_mm=args.plausible_limit_mm,
                   detrend=args.detrend)
    try:
        clean, report = check_campaign(args.file, **options)
    except InspectionError as exc:
        print(f"ttbpipe check-inspection: FAILED: {exc}", file=sys.stderr)
        return 1
    print(report.summary())
    if args.out:
        write_table(clean, args.out, config={"inspections": {"cleaning": options}},
                    kind="inspection_clean", source=str(args.file), cleaning=report.to_dict())
        print(f"cleaned table: {args.out}")
    if args.report:
        write_text(json.dumps(report.to_dict(), indent=2) + "\n", args.report)
        print(f"repairs report: {args.report}")
    print("OK")
    return 0
