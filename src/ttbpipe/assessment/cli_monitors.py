"""``ttbpipe assess-monitors CASE.yaml --out CASE_DECK.yaml``: the case with the monitors the
EN 1990 A2 deck checks need.

Writes a copy of the case whose ``monitors:`` are its own (or the structure's default ones)
followed by :func:`ttbpipe.assessment.monitors.deck_check_monitors` of its structure (both rails'
vertical displacement at the twist sections), so that ``ttbpipe simulate CASE_DECK.yaml`` records
what ``ttbpipe assess --standard en1990`` reads. Exit status 1 on an invalid case.
"""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("config", help="case YAML (schema: src/ttbpipe/schemas/simulation.schema.json)")
    parser.add_argument("--out", required=True, help="case YAML with the deck-check monitors")


def run(args: argparse.Namespace) -> int:
    import yaml

    from ..io import jsonable, write_text
    from ..simulation.config import load_case
    from .monitors import case_with_deck_monitors

    try:
        case = case_with_deck_monitors(load_case(args.config))
    except ValueError as exc:
        print(f"ttbpipe assess-monitors: {exc}", file=sys.stderr)
        return 1
    header = (f"# {args.config} with the monitors of the EN 1990 A2 deck checks "
              "(ttbpipe assess-monitors)\n")
    write_text(header + yaml.safe_dump(jsonable(case), sort_keys=False), args.out)
    log.info("wrote %s (%d monitors)", args.out, len(case["monitors"]))
    return 0
