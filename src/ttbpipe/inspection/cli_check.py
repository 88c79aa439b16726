"""``ttbpipe check-inspection FILE``: validate and clean one campaign file on its own.

Prints a one-screen summary of the checks and repairs; exits 0 on success and 1 with the error
message (naming file, row and column) when the file cannot be used. Optionally writes the cleaned
table (Parquet, with provenance) and the repairs report (JSON).

Options: command line > the ``inspections`` section of ``--config`` (``cleaning``, ``columns``,
``units``) > :data:`ttbpipe.inspection.validate.CLEANING_DEFAULTS`. ``--columns`` and ``--units``
entries are added to (and override) the mapping of ``--config``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path
from typing import Any

from ..io import write_table, write_text
from .format import InspectionError, check_mapping
from .repairs import DETREND_KINDS
from .validate import CLEANING_DEFAULTS, check_campaign, options_from_config

logger = logging.getLogger(__name__)

# command-line option -> cleaning option (config inspections.cleaning), with its help text
_CLEANING_OPTIONS: dict[str, tuple[type, str]] = {
    "max_gap_m": (float, "longest run of missing values/rows interpolated (m)"),
    "spike_threshold_mm": (float, "deviation from the local median that makes a spike"),
    "max_spike_run": (int, "most consecutive samples forming one spike"),
    "plausible_limit_mm": (float, "largest plausible |value| after repair"),
    "band_rms_margin": (float, "factor on the band RMS beyond the standard spectra's range"),
    "max_constant_run_m": (float, "longest run of exactly equal samples (m)"),
}


def _pairs(text: str, what: str) -> dict[str, str]:
    """``A=B,C=D`` -> {A: B, C: D}."""
    pairs: dict[str, str] = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise argparse.ArgumentTypeError(f"{what}: expected NAME=VALUE, got {item!r}")
        pairs[key.strip()] = value.strip()
    return pairs


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="campaign file YYYY-MM-DD.csv or YYYY-MM-DD.parquet")
    parser.add_argument("--out", default=None, metavar="CLEAN.parquet",
                        help="write the cleaned table here (Parquet with provenance)")
    parser.add_argument("--report", default=None, metavar="REPAIRS.json",
                        help="write the repairs report here (JSON)")
    parser.add_argument("--config", type=Path, default=None, metavar="CONFIG.yaml",
                        help="study configuration: its inspections section (cleaning, columns, "
                             "units) sets the defaults")
    mapping = parser.add_argument_group("column and unit mapping (config inspections.columns "
                                        "and inspections.units)")
    mapping.add_argument("--columns", action="append", default=[], metavar="SRC=DST[,...]",
                         help="read column SRC of the file as ttbpipe column DST, e.g. "
                              "KM=chainage_m,GAUGE=gauge_mm")
    mapping.add_argument("--units", action="append", default=[], metavar="KEY=UNIT[,...]",
                         help="units of the file: chainage=m|km|ft, channels=mm|cm|m|in|um, or a "
                              "column, e.g. chainage=km,channels=cm")
    group = parser.add_argument_group("cleaning options (defaults: --config, else "
                                      "ttbpipe.inspection.validate.CLEANING_DEFAULTS)")
    for name, (kind, help_text) in _CLEANING_OPTIONS.items():
        group.add_argument(f"--{name.replace('_', '-')}", dest=name, type=kind, default=None,
                           help=f"{help_text} [{CLEANING_DEFAULTS[name]}]")
    group.add_argument("--detrend", choices=DETREND_KINDS, default=None,
                       help=f"per-channel detrending [{CLEANING_DEFAULTS['detrend']}]")


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """check_campaign keyword arguments: command line > --config > package defaults."""
    config: dict[str, Any] = {}
    if args.config is not None:
        import yaml

        with open(args.config) as handle:
            config = yaml.safe_load(handle) or {}
    options = options_from_config(config.get("inspections"))
    for name in (*_CLEANING_OPTIONS, "detrend"):
        value = getattr(args, name)
        if value is not None:
            options[name] = value
        options.setdefault(name, CLEANING_DEFAULTS[name])
    for key, entries in (("columns", args.columns), ("units", args.units)):
        merged = dict(options.get(key) or {})
        for entry in entries:
            merged.update(_pairs(entry, f"--{key}"))
        if merged:
            options[key] = merged
    check_mapping(options.get("columns"), options.get("units"))  # a clear error before reading
    return options


def run(args: argparse.Namespace) -> int:
    try:
        options = _options(args)
    except (OSError, ValueError, argparse.ArgumentTypeError) as exc:
        print(f"ttbpipe check-inspection: bad options: {exc}", file=sys.stderr)
        return 2
    try:
        clean, report = check_campaign(args.file, **options)
    except InspectionError as exc:
        print(f"ttbpipe check-inspection: FAILED: {exc}", file=sys.stderr)
        return 1
    print(report.summary())
    if args.out:
        cleaning = {k: v for k, v in options.items() if k not in ("columns", "units")}
        mapping = {k: options[k] for k in ("columns", "units") if k in options}
        write_table(clean, args.out, config={"inspections": {"cleaning": cleaning, **mapping}},
                    kind="inspection_clean", source=str(args.file), cleaning=report.to_dict())
        print(f"cleaned table: {args.out}")
    if args.report:
        write_text(json.dumps(report.to_dict(), indent=2) + "\n", args.report)
        print(f"repairs report: {args.report}")
    print("OK")
    return 0
