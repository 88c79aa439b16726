"""``ttbpipe psd``: per-section, per-channel Welch PSDs of one inspection campaign.

    ttbpipe psd FILE --section-length-m 1000 [--segment-length-m 1000] [--overlap 0.5]
                [--window hann] [--detrend linear] [--band-m 2 200] [--config config.yaml]
                [--input-kind auto|clean|raw] --out PSD.parquet

FILE is a cleaned campaign Parquet (written by ``check-inspection`` / the
``prepare_campaigns_<year>`` rules) or a raw campaign CSV/Parquet, which is read and cleaned first
with :func:`ttbpipe.inspection.check_campaign` (cleaning options and the column/unit mapping from
the ``inspections`` section of ``--config``, else the package defaults).
``--input-kind auto`` treats CSV files as raw and Parquet files as cleaned when their ttbpipe
provenance ``kind`` contains "clean", raw otherwise.

Estimator options: command line > ``psd:`` section of ``--config`` > :data:`psd.DEFAULTS`;
without ``--segment-length-m`` the segment equals the section (docs/irregularity.md).
The result is written atomically with provenance (``kind="psd"``).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from ..io import read_provenance, read_table, write_table
from .psd import DEFAULTS, estimate_campaign_psd

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", type=Path, help="campaign file: cleaned Parquet, or raw CSV/Parquet")
    parser.add_argument("--out", type=Path, required=True, help="output PSD Parquet")
    parser.add_argument("--section-length-m", type=float, default=None,
                        help=f"section length in m (default {DEFAULTS['section_length_m']:g})")
    parser.add_argument("--segment-length-m", type=float, default=None,
                        help="Welch segment length in m, <= section (default: the section length)")
    parser.add_argument("--overlap", type=float, default=None,
                        help=f"Welch overlap fraction (default {DEFAULTS['overlap']})")
    parser.add_argument("--window", default=None, help="Welch window (default hann)")
    parser.add_argument("--detrend", choices=("constant", "linear"), default=None,
                        help="per-segment detrend (default linear)")
    parser.add_argument("--band-m", type=float, nargs=2, metavar=("MIN", "MAX"), default=None,
                        help="keep wavelengths MIN..MAX m (default 2 200)")
    parser.add_argument("--config", type=Path, default=None,
                        help="study config YAML: psd and inspections (cleaning, columns, units) sections")
    parser.add_argument("--input-kind", choices=("auto", "clean", "raw"), default="auto",
                        help="whether FILE is already cleaned (default: auto-detect)")


def _is_clean(path: Path, input_kind: str) -> bool:
    if input_kind != "auto":
        return input_kind == "clean"
    if path.suffix.lower() != ".parquet":
        return False
    try:
        kind = str(read_provenance(path).get("kind") or "")
    except KeyError:
        return False
    return "clean" in kind


def _load_config(path: Path | None) -> dict[str, Any]:
    if path is None:
        return {}
    import yaml

    with open(path) as handle:
        return yaml.safe_load(handle) or {}


def run(args: argparse.Namespace) -> int:
    path: Path = args.file
    if not path.is_file():
        log.error("%s: no such file", path)
        return 2
    config = _load_config(args.config)
    psd_options: dict[str, Any] = {k: v for k, v in dict(config.get("psd") or {}).items()
                                   if k in DEFAULTS}
    for key, value in (("section_length_m", args.section_length_m),
                       ("segment_length_m", args.segment_length_m), ("overlap", args.overlap),
                       ("window", args.window), ("detrend", args.detrend),
                       ("wavelength_band_m", args.band_m)):
        if value is not None:
            psd_options[key] = value
    psd_options.setdefault("section_length_m", DEFAULTS["section_length_m"])
    if args.segment_length_m is None and "segment_length_m" not in dict(config.get("psd") or {}):
        psd_options["segment_length_m"] = psd_options["section_length_m"]

    try:
        if _is_clean(path, args.input_kind):
            clean = read_table(path)
            log.info("%s: cleaned campaign, %d rows", path, len(clean))
        else:
            from ..inspection import check_campaign, options_from_config

            # cleaning options and the column/unit mapping of the inspections section
            clean, report = check_campaign(path, **options_from_config(config.get("inspections")))
            log.info("%s: raw campaign cleaned first: %s", path, report.summary())
        table = estimate_campaign_psd(clean, psd_options, source=str(path))
    except ValueError as exc:  # includes InspectionError; name the file if the message does not
        message = str(exc)
        log.error("%s", message if str(path) in message else f"{path}: {message}")
        return 1
    resolved = {**DEFAULTS, **psd_options}
    write_table(table, args.out, config={"psd": resolved}, kind="psd", source=str(path))
    log.info("wrote %s (%d rows, %d sections)", args.out, len(table), table["section"].nunique())
    return 0
