"""``ttbpipe assess RESULT.parquet --standard NAME --out ASSESSMENT.parquet [--option KEY=VALUE]``.

Evaluates a ``ttbpipe simulate`` result against a standard's profile (:mod:`ttbpipe.assessment`)
and writes one row per index (:data:`ttbpipe.assessment.COLUMNS`) with ``ttbpipe.io.write_table``
(provenance kind "assessment": the standard, the options, the result file and its case). Prints
the rows (index, location, processed and raw values, limit, utilisation). ``--option`` sets a
profile option (value read as YAML: numbers, true/false, null, lists); repeat it for several.
Exit status 1 with the message on stderr when the result cannot be assessed (not a simulate
result, missing monitors, unknown standard or option).
"""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from .registry import profiles

    names = sorted(profiles())
    parser.add_argument("result", help="Parquet result of ttbpipe simulate")
    parser.add_argument("--standard", required=True, choices=names,
                        help="assessment profile: " + ", ".join(
                            f"{n} ({p.standard})" for n, p in sorted(profiles().items())))
    parser.add_argument("--out", required=True, help="output Parquet table of the assessment")
    parser.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                        help="profile option (see docs/assessment.md), value as YAML")


def parse_options(items: list[str]) -> dict:
    import yaml

    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--option {item!r}: expected KEY=VALUE")
        out[key.strip()] = yaml.safe_load(value)
    return out


def format_rows(df) -> str:
    lines = [f"{'index':32s} {'location':22s} {'processed':>11s} {'raw':>11s} {'limit':>11s} "
             f"{'util.':>7s} unit"]
    for r in df.itertuples():
        lines.append(f"{r.index:32s} {r.location:22s} {r.processed_value:11.4g} {r.raw_value:11.4g} "
                     f"{r.limit:11.4g} {r.utilisation:7.3f} {r.unit}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ..io import read_provenance, write_table
    from .api import assess_result
    from .registry import get_profile

    try:
        options = parse_options(args.option)
        profile = get_profile(args.standard)
        df = assess_result(args.result, args.standard, options=options)
        prov = read_provenance(args.result)
    except (ValueError, KeyError, OSError) as exc:
        print(f"ttbpipe assess: {exc}", file=sys.stderr)
        return 1
    write_table(df, args.out, config=prov.get("config"), kind="assessment",
                standard=profile.standard, profile=profile.name,
                options=profile.resolve_options(options), result=str(args.result))
    print(f"{profile.standard} ({profile.name}): {args.result}")
    print(format_rows(df))
    log.info("wrote %s (%d rows)", args.out, len(df))
    return 0
