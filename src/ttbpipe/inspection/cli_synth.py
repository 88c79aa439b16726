"""``ttbpipe synth-inspections``: write a synthetic series of inspection campaigns.

The model (base line from a standard spectrum, section-wise degradation, local defects,
condition-based maintenance, measurement noise, dropouts and spikes) is described in
:mod:`ttbpipe.inspection.synthetic` and docs/inspection_format.md.
"""

from __future__ import annotations

import argparse
import logging

from .synthetic import campaign_dates, write_synthetic_campaigns

logger = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--spectrum", default="tbt3352",
                        help="base-line spectrum: tbt3352 | german_low | german_high | "
                             "fra_class1..6 [%(default)s]")
    parser.add_argument("--length-km", type=float, default=5.0, help="line length [%(default)s]")
    parser.add_argument("--campaigns", type=int, default=36,
                        help="number of campaigns [%(default)s]")
    parser.add_argument("--seed", type=int, default=1, help="random seed [%(default)s]")
    parser.add_argument("--start-date", default="2023-01-15",
                        help="date of the first campaign, YYYY-MM-DD [%(default)s]")
    parser.add_argument("--interval-months", type=int, default=1,
                        help="months between campaigns [%(default)s]")
    parser.add_argument("--dx-m", type=float, default=0.25,
                        help="sampling interval (m) [%(default)s]")
    parser.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                        help="file format [%(default)s]")
    parser.add_argument("--out", required=True, help="output folder")


def run(args: argparse.Namespace) -> int:
    if args.campaigns < 1 or args.interval_months < 1 or args.length_km <= 0:
        print("ttbpipe synth-inspections: need --campaigns >= 1, --interval-months >= 1 and "
              "--length-km > 0")
        return 2
    dates = campaign_dates(args.start_date, args.campaigns, args.interval_months)
    settings = {"spectrum": args.spectrum, "length_km": args.length_km, "seed": args.seed,
                "campaigns": args.campaigns, "start_date": args.start_date,
                "interval_months": args.interval_months, "dx_m": args.dx_m}
    paths = write_synthetic_campaigns(args.out, dates=dates, spectrum=args.spectrum,
                                      length_km=args.length_km, seed=args.seed, dx_m=args.dx_m,
                                      fmt=args.format,
                                      config={"inspections": {"synthetic": settings}})
    print(f"wrote {len(paths)} campaigns to {args.out}: {paths[0].name} .. {paths[-1].name}")
    return 0
