"""``ttbpipe sample-fields CONFIG --out SAMPLES.parquet [--samples N] [--method mc|kle]``."""

from __future__ import annotations

import argparse
import logging

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("config", help="study configuration (YAML) with study.seed and fields:")
    parser.add_argument("--out", required=True, help="output Parquet table of field samples")
    parser.add_argument("--samples", type=int, default=None,
                        help="number of samples (default: fields.samples)")
    parser.add_argument("--first-sample", type=int, default=0,
                        help="index of the first sample (samples are independent of the batch)")
    parser.add_argument("--method", choices=["kle", "mc"], default=None,
                        help="kle: truncated Karhunen-Loeve; mc: full-rank Monte Carlo "
                             "(default: fields.method)")


def run(args: argparse.Namespace) -> int:
    import yaml

    from .sampling import sample_study

    with open(args.config) as handle:
        config = yaml.safe_load(handle)
    if not isinstance(config, dict) or "study" not in config or "seed" not in config["study"]:
        log.error("%s: needs study.seed and a fields: section", args.config)
        return 2
    try:
        sample_study(config, args.out, n_samples=args.samples, method=args.method,
                     first_sample=args.first_sample)
    except (ValueError, KeyError) as exc:
        log.error("%s: %s", args.config, exc)
        return 1
    return 0
